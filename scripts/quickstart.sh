#!/usr/bin/env bash
# Installs the dependencies, builds rff-slam (Release) and solves the bundled
# CMU Plaza 1 dataset with configs/plaza.flags, printing the summary and the
# errors against ground truth. The first Quick start command of README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install_deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
mkdir -p out
build/rff_slam --flagfile=configs/plaza.flags --dataset=data/plaza1.rffd \
  --output_trajectory=out/plaza1.tum --output_landmarks=out/plaza1.landmarks \
  --summary_json=out/plaza1.json
