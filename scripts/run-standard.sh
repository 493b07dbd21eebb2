#!/usr/bin/env bash
# The standard preset end to end (docs/results.md): train the scene classifier
# (runs/classifier, ~2 minutes), train configs/standard.yaml with the
# classifier driving the switches (300 + 4000 episodes, about 1.5 to 2 hours on
# 2 cores), then evaluate it greedily on 300 episodes (100 per stair height).
# Usage: scripts/run-standard.sh [build_dir] [run_dir] [extra --set ...]
# Interrupted? Run it again: it resumes the run from its last checkpoint.
set -euo pipefail
build_dir=${1:-build}
run=${2:-runs/standard}
shift $(( $# < 2 ? $# : 2 ))
cd "$(dirname "$0")/.."
comorph="$build_dir/apps/comorph"
classifier=runs/classifier

if [ ! -f "$classifier/classifier.pt" ]; then
  "$comorph" classifier prepare --out "$classifier"
fi
if [ -f "$run/checkpoint/trainer.yaml" ] || [ -f "$run/checkpoint.old/trainer.yaml" ]; then
  "$comorph" train --resume "$run"
else
  sets=(--set trainer.scene_source=classifier --set trainer.classifier_dir="$classifier")
  for s in "$@"; do sets+=(--set "$s"); done
  "$comorph" train --config configs/standard.yaml --out "$run" "${sets[@]}"
fi
"$comorph" eval --run "$run" --scenario default --episodes 300
