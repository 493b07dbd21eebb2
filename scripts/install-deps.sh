#!/usr/bin/env bash
# Installs every Debian 12 package comorph needs to build, test and run.
# Run as root or through sudo. Safe to run again: apt-get skips what is there.
set -euo pipefail

packages=(
  build-essential cmake ccache pkg-config
  libmujoco-dev libmujoco-samples libqhull-dev      # physics (+ viewer, testxml)
  libtorch-dev libopenblas0-pthread                 # neural networks on OpenBLAS
  libblas-dev                                       # cblas.h: the TD3 update's own matrix products (rl/mlp_pass)
  libyaml-cpp-dev libcli11-dev libspdlog-dev libfmt-dev
  nlohmann-json3-dev                                # JSON of evaluation summaries (report)
  zlib1g-dev                                        # gzip of an exported run's episodes.csv.gz (common/gzip)
  libgtest-dev libgmock-dev libbenchmark-dev
  libegl-dev libegl-mesa0 libgl1-mesa-dri libgl-dev # headless rendering
  libopengl-dev                                     # libOpenGL.so: GL without GLX, for EGL (report)
  ffmpeg gnuplot-nox                                # video, plots
  pybind11-dev python3-dev python3-numpy python3-pytest  # the Python module and its tests (docs/python.md)
  python3-torch                                     # examples/train_reinforce.py (its test skips without it)
  mpi-default-dev openmpi-bin                       # OpenMPI: the trainer's actors on MPI ranks (mpirun)
  parallel slurm-wlm munge                          # engines of `comorph experiment --jobs/--slurm` (tests: scripts/slurm-local.sh)
)

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: run as root or install sudo" >&2; exit 1; }
  sudo_cmd=(sudo)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
