#!/usr/bin/env bash
# Actors as threads and as MPI ranks (docs/coopt.md, "Actors on more cores"):
# control steps/s of a short quick-preset training with 1 and 2 actors, each
# as threads (trainer.simulation_threads) and as ranks (mpirun -np 2 and 3),
# in alternating rounds so that a drift of the machine's speed hits all
# alike; then the learner's ingest ceiling: transitions/s it stores and
# trains on at the preset's update ratio (bench_trainer's "learner alone").
# Ratios measured in one run; the median of the rounds. EPISODES (4) sets the
# trainings' length after their warm-up episode: longer runs weigh each
# process's start-up (the ranks pay it once per rank) less.
# usage: bench_actors [ROUNDS] [EPISODES]   (installed as build/bench/coopt/bench_actors)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "$here/../.." && pwd)
exe=$build/apps/comorph
rounds=${1:-2}
episodes=${2:-4}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # as root
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# 1 + EPISODES episodes of at most 1000 steps, learning from step 500, no evaluation.
sets=(--set trainer.warmup_episodes=1 --set trainer.episodes="$episodes" --set trainer.config_refit_episodes=0
      --set trainer.eval_interval=0 --set env.task.max_steps=1000 --set td3.learning_starts=500)
config=@PROJECT_SOURCE_DIR@/configs/quick.yaml  # configure_file fills in the sources

# The steps/s of `comorph train`'s closing line ("... N control steps, W s wall, R steps/s").
rate() { sed -n 's/.* \([0-9.]*\) steps\/s$/\1/p' "$1" | tail -1; }
run() {  # name, then the command's prefix and extra arguments
  local name=$1
  shift
  rm -rf "$work/$name"
  "$@" --config "$config" "${sets[@]}" --out "$work/$name" > "$work/$name.log" 2>&1 || {
    tail -5 "$work/$name.log" >&2
    exit 1
  }
  rate "$work/$name.log"
}
declare -A rates
variants=("threads 1" "ranks 1" "threads 2" "ranks 2")
echo "load average at the start: $(cut -d' ' -f1-3 /proc/loadavg); 1 + $episodes episodes a training"
for r in $(seq "$rounds"); do
  rates["threads 1"]+=" $(run t1 "$exe" train)"
  rates["ranks 1"]+=" $(run r1 mpirun --oversubscribe -np 2 "$exe" train)"
  rates["threads 2"]+=" $(run t2 "$exe" train --set trainer.simulation_threads=2)"
  rates["ranks 2"]+=" $(run r2 mpirun --oversubscribe -np 3 "$exe" train)"
done
median() { tr ' ' '\n' | grep . | sort -g | awk '{v[NR]=$1} END {print (NR % 2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }
printf "%-10s %8s   %s\n" "actors" "steps/s" "(rounds)"
for v in "${variants[@]}"; do
  printf "%-10s %8.0f   (%s)\n" "$v" "$(echo "${rates[$v]}" | median)" "${rates[$v]# }"
done
t2=$(echo "${rates["threads 2"]}" | median)
r2=$(echo "${rates["ranks 2"]}" | median)
echo "2 actors, ranks / threads: $(awk -v a="$r2" -v b="$t2" 'BEGIN {printf "%.2f", a / b}')"
# The learner alone on the acting side's transitions: its ingest ceiling.
"$build/bench/coopt/bench_trainer" --config "$config" "${sets[@]}" --steps 4000 --no-checkpoint-cost --json \
  > "$work/sides.json" 2> "$work/sides.log"
python3 -c "
import json, sys
j = json.load(open(sys.argv[1]))
print('one actor alone (acting side): %.0f steps/s' % j['env_only_steps_per_s'])
print('learner ingest ceiling: %.0f transitions/s (store + updates at the preset ratio)' % j['learner_only_steps_per_s'])
" "$work/sides.json"
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg)"
