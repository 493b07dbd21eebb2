#!/usr/bin/env bash
# The main job of `make run`. Until the learning side lands this is the
# scripted demo of the simulated robot; later it trains the quick preset.
set -euo pipefail
build_dir=${1:-build}
exec "$build_dir/apps/comorph" demo --modules 4 --seed 1
