#!/usr/bin/env bash
# Runs the full experiment grid (Table I, Figure 1, Table II, Figure 2 and the
# solver comparison; see rff_ceres/experiment/experiment.h) into
# docs/experiments/, with the per-run progress in docs/experiments/progress.log:
#   scripts/experiments.sh [BUILD_DIR] [extra rff_experiment flags]
# e.g. scripts/experiments.sh build --methods=rff,wnoa --num_threads=2
# Methods whose configs are missing give failed rows, and the script then
# exits 1 after writing every table (rff_experiment's exit status).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build=${1:-$root/build}
shift || true
out="$root/docs/experiments"
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release > /dev/null
make -C "$build" -j2 rff_experiment
mkdir -p "$out"
"$build/rff_experiment" --out_dir="$out" --configs_dir="$root/configs" \
    --data_dir="$root/data" "$@" 2> >(tee "$out/progress.log" >&2)
