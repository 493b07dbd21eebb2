#!/usr/bin/env bash
# The main job of `make run`: train the quick preset (configs/quick.yaml, about
# 20 minutes of training on 2 cores) into runs/quick, evaluate it greedily on
# the paper's protocol (stair heights 0.04/0.06/0.08 m), print where the results are.
# Interrupted (Ctrl-C)? Run it again: it resumes runs/quick from its checkpoint.
set -euo pipefail
build_dir=${1:-build}
cd "$(dirname "$0")/.."
comorph="$build_dir/apps/comorph"
run=runs/quick

if [ -f "$run/checkpoint/trainer.yaml" ] || [ -f "$run/checkpoint.old/trainer.yaml" ]; then
  "$comorph" train --resume "$run"
else
  if [ -e "$run" ]; then
    echo "$run exists without a checkpoint; move it away first" >&2
    exit 1
  fi
  "$comorph" train --config configs/quick.yaml --out "$run"
fi
"$comorph" eval --run "$run" --scenario default

echo
echo "Results in $run/:"
echo "  episodes.csv        one row per training episode (the learning curve)"
echo "  evaluations.csv     periodic greedy evaluations during training"
echo "  eval-default.json   success per stair height, time, energy, F, configurations"
echo "  checkpoint/         both learners, replay buffers and trainer state (resume/eval)"
echo "A report with plots: $comorph report $run --out $run/report"
