#!/usr/bin/env bash
# Prints a Markdown table comparing the Ceres linear solvers on one dataset:
#   scripts/solver_table.sh BUILD_DIR DATASET FLAGFILE [extra rff_slam flags]
# Each row: wall time of the whole solve (best of 3), Ceres iterations, final
# cost and APE-trans.
set -euo pipefail
build=$1 dataset=$2 flagfile=$3
shift 3
echo "| linear solver | time [s] | iterations | final cost | APE-trans [m] |"
echo "| --- | --- | --- | --- | --- |"
for solver in DENSE_SCHUR SPARSE_SCHUR ITERATIVE_SCHUR DENSE_QR \
              DENSE_NORMAL_CHOLESKY SPARSE_NORMAL_CHOLESKY CGNR; do
  best=""
  for _ in 1 2 3; do
    out=$("$build/rff_slam" --flagfile="$flagfile" --dataset="$dataset" \
          --linear_solver="$solver" "$@" 2>/dev/null) || { best=fail; break; }
    line=$(echo "$out" | awk '
      /iterations,/ {it = $3}
      /^  cost/ {cost = $4}
      /s total/ {t = $6}
      /^APE translation/ {ape = $4}
      END {printf "%.3f %s %.6g %.3f", t, it, cost, ape}')
    if [ -z "$best" ] || awk -v a="$line" -v b="$best" \
        'BEGIN {split(a, x, " "); split(b, y, " "); exit !(x[1] < y[1])}'; then
      best=$line
    fi
  done
  if [ "$best" = fail ]; then
    echo "| $solver | failed | | | |"
  else
    read -r t it cost ape <<< "$best"
    echo "| $solver | $t | $it | $cost | $ape |"
  fi
done
