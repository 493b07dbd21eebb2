# Shared steps of scripts/run-main.sh and scripts/run-standard.sh (sourced).

# prepare_classifier COMORPH DIR: trains the scene classifier into DIR unless it is there.
prepare_classifier() {
  if [ ! -f "$2/classifier.pt" ]; then
    "$1" classifier prepare --out "$2"
  fi
}

# train_or_resume COMORPH RUN CONFIG CLASSIFIER [--set k=v ...]: resumes RUN
# from its checkpoint, or trains CONFIG into it with CLASSIFIER driving the
# scene switches.
train_or_resume() {
  local comorph=$1 run=$2 config=$3 classifier=$4
  shift 4
  if [ -f "$run/checkpoint/trainer.yaml" ] || [ -f "$run/checkpoint.old/trainer.yaml" ]; then
    "$comorph" train --resume "$run"
  else
    if [ -e "$run" ]; then
      echo "$run exists without a checkpoint; move it away first" >&2
      exit 1
    fi
    "$comorph" train --config "$config" --out "$run" \
      --set trainer.scene_source=classifier --set trainer.classifier_dir="$classifier" "$@"
  fi
}
