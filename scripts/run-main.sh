#!/usr/bin/env bash
# The main job of `make run`: train the scene classifier (ResNet-18 on labelled
# simulator depth images, ~2 minutes) into runs/classifier, train the quick
# preset (configs/quick.yaml, about 16 minutes on 2 cores) into runs/quick with
# that classifier driving the scene-switch detector, evaluate it greedily on the
# paper's protocol (stair heights 0.04/0.06/0.08 m), render one evaluation
# episode per stair height to video, write the report (tables beside the
# paper's, training curves, keyframes) and print where the results are.
# Interrupted (Ctrl-C)? Run it again: it resumes runs/quick from its checkpoint.
set -euo pipefail
build_dir=${1:-build}
cd "$(dirname "$0")/.."
comorph="$build_dir/apps/comorph"
run=runs/quick
classifier=runs/classifier

source scripts/run-lib.sh
prepare_classifier "$comorph" "$classifier"
train_or_resume "$comorph" "$run" configs/quick.yaml "$classifier"
"$comorph" eval --run "$run" --scenario default
# Evaluation episodes 0, 1, 2 = stair heights 0.04, 0.06, 0.08 m (~20 s each).
for seed in 700000 700001 700002; do
  "$comorph" render --run "$run" --seed $seed --width 480 --height 360 --frame-step 2 --out "$run/episode-$seed.mp4"
done
"$comorph" report "$run" --out "$run/report"

echo
echo "Results in $run/:"
echo "  report/report.html  the paper's Table I beside ours, training curves, configurations, keyframes"
echo "  episode-*.mp4       evaluation episodes 0..2 (stairs 0.04, 0.06, 0.08 m), camera on the robot"
echo "  episodes.csv        one row per training episode (the learning curve)"
echo "  evaluations.csv     periodic greedy evaluations during training"
echo "  eval-default.json   success per stair height, time, energy, F, configurations"
echo "  checkpoint/         both learners, replay buffers and trainer state (resume/eval)"
echo "The scene classifier in $classifier/ (classifier-eval.txt: held-out accuracy, confusion matrix, switch delays)"
echo "The paper's whole tables: $comorph experiment --table 1 --config configs/quick.yaml --out runs/tables"
