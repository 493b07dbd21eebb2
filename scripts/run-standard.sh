#!/usr/bin/env bash
# The standard preset end to end (docs/results.md): train the scene classifier
# (runs/classifier, ~2 minutes), train configs/standard.yaml with the
# classifier driving the switches (300 + 4000 episodes + 1000 of DQN refit;
# about 2 hours for seed 1 on 2 cores, docs/results.md), then evaluate it greedily on
# 300 episodes (100 per stair height) of the config's eval seeds.
# Usage: [PRESET=configs/rl-only.yaml] scripts/run-standard.sh [build_dir] [run_dir] [extra --set ...]
# PRESET: another preset of the standard budget (default configs/standard.yaml).
# Interrupted? Run it again: it resumes the run from its last checkpoint.
set -euo pipefail
build_dir=${1:-build}
run=${2:-runs/standard}
shift $(( $# < 2 ? $# : 2 ))
cd "$(dirname "$0")/.."
comorph="$build_dir/apps/comorph"
classifier=runs/classifier

source scripts/run-lib.sh
prepare_classifier "$comorph" "$classifier"
sets=()
for s in "$@"; do sets+=(--set "$s"); done
train_or_resume "$comorph" "$run" "${PRESET:-configs/standard.yaml}" "$classifier" "${sets[@]}"
"$comorph" eval --run "$run" --scenario default --episodes 300
