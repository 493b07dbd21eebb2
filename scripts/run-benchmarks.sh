#!/usr/bin/env bash
# Runs every benchmark program the build made (bench/<area>/bench_*); each one
# prints its own ratios measured in one run.
set -euo pipefail
build_dir=${1:-build}
found=0
while IFS= read -r program; do
  found=1
  echo "== ${program#"$build_dir"/}"
  "$program"
done < <(find "$build_dir/bench" -type f -name 'bench_*' -perm -u+x | sort)
[ "$found" -eq 1 ] || { echo "run-benchmarks: no bench_* programs under $build_dir/bench" >&2; exit 1; }
