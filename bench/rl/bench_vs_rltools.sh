#!/usr/bin/env bash
# comorph's TD3 beside RLtools' TD3 Pendulum example, 20 000 steps each, in
# alternating pairs on this machine (docs/rl.md, "Beside RLtools"). RLtools
# is not a Debian package and is never part of this repository: build its
# example yourself, outside the tree, and pass the binary, e.g.
#   g++ -I rl-tools/include rl-tools/src/rl/environments/pendulum/td3/cpu/standalone.cpp \
#       /usr/lib/x86_64-linux-gnu/libopenblas.so.0 -DRL_TOOLS_BACKEND_ENABLE_OPENBLAS \
#       -std=c++17 -Ofast -o pendulum_td3_openblas
# Prints, per pair, the training time each reports (RLtools' "Time:", comorph's
# wall_s) and each process's wall time, then the medians of the ratios
# comorph / RLtools: at RLtools' sizes (pendulum_td3_rltools_sizes.yaml) and
# with comorph's own preset (configs/rl/pendulum_td3.yaml: batch 128, 1000
# random steps first). Both single-threaded (OPENBLAS_NUM_THREADS=1).
# usage: bench_vs_rltools RLTOOLS_BINARY [PAIRS]   (installed as build/bench/rl/bench_vs_rltools)
set -euo pipefail
rltools=${1:?usage: bench_vs_rltools RLTOOLS_BINARY [PAIRS]}
pairs=${2:-5}
[ -x "$rltools" ] || { echo "bench_vs_rltools: $rltools is not an executable" >&2; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
exe=$(cd "$here/../.." && pwd)/apps/comorph
sizes=@CMAKE_CURRENT_SOURCE_DIR@/pendulum_td3_rltools_sizes.yaml  # configure_file fills in the sources
preset=@PROJECT_SOURCE_DIR@/configs/rl/pendulum_td3.yaml
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# "<training s> <process wall s> <return>" of one run
comorph_run() {
  /usr/bin/time -f "%e" -o "$work/time" "$exe" classic --env pendulum --algo td3 --steps 20000 --seed "$2" \
    --config "$1" --json > "$work/out"
  python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['wall_s'], open(sys.argv[2]).read().strip(), j['mean_return'])" \
    "$work/out" "$work/time"
}
rltools_run() {
  /usr/bin/time -f "%e" -o "$work/time" "$rltools" "$1" > "$work/out" 2>&1
  echo "$(sed -n 's/^Time: \([0-9.]*\)s$/\1/p' "$work/out") $(cat "$work/time") \
$(grep 'Mean return' "$work/out" | tail -1 | sed 's/.*Mean return: \([-0-9.]*\).*/\1/')"
}
median() { sort -g | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }

echo "load average at the start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf "%-6s %-22s %-22s %-22s %s\n" pair "RLtools train/wall s" "comorph sizes train/wall" "comorph preset train/wall" "returns (RLtools, sizes, preset)"
: > "$work/ratios"
for p in $(seq "$pairs"); do
  read -r rt rw rr < <(rltools_run "$p")
  read -r st sw sr < <(comorph_run "$sizes" "$p")
  read -r pt pw pr < <(comorph_run "$preset" "$p")
  printf "%-6s %-22s %-22s %-22s %s\n" "$p" "$rt / $rw" "$st / $sw" "$pt / $pw" "$rr, $sr, $pr"
  awk -v rt="$rt" -v rw="$rw" -v st="$st" -v sw="$sw" -v pt="$pt" -v pw="$pw" \
    'BEGIN {print st / rt, sw / rw, pt / rt, pw / rw}' >> "$work/ratios"
done
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
col() { awk -v c="$1" '{print $c}' "$work/ratios" | median; }
printf "comorph / RLtools, median of %s pairs:\n" "$pairs"
printf "  RLtools' sizes:  training %.2fx, process wall %.2fx\n" "$(col 1)" "$(col 2)"
printf "  comorph preset:  training %.2fx, process wall %.2fx\n" "$(col 3)" "$(col 4)"
