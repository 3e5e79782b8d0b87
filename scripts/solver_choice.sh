#!/usr/bin/env bash
# The default linear solver (auto) against each explicit one on recordings:
# the bundled Plaza 1 and MRCLAM robot 1 and the simulated 10 Hz laser run
# (12k poses), both priors, default flags otherwise. Prints a Markdown table
# of wall times (one thread, every rff_slam under a timeout) and the ratio
# auto / best explicit; the ratio compares runs of the same invocation.
#   scripts/solver_choice.sh BUILD_DIR [TIMEOUT_SECONDS]
set -euo pipefail

fail() { echo "solver_choice: error: $*" >&2; exit 1; }
[ $# -ge 1 ] && [ $# -le 2 ] ||
  fail "usage: scripts/solver_choice.sh BUILD_DIR [TIMEOUT_SECONDS]"
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$1"
limit="${2:-120}"
[[ "$limit" =~ ^[1-9][0-9]*$ ]] ||
  fail "TIMEOUT_SECONDS must be a positive integer, got '$limit'"
[ -x "$build/rff_slam" ] && [ -x "$build/rff_simulate" ] ||
  fail "$build/rff_slam or rff_simulate not found: build first"
for file in "$root/data/plaza1.rffd" "$root/data/mrclam6_robot1.rffd"; do
  [ -f "$file" ] || fail "$file not found"
done
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
"$build/rff_simulate" --preset=laser_10hz --seed=1 \
    --output="$work/laser_10hz_s1.rffd" > /dev/null 2> "$work/simulate.err" ||
  fail "rff_simulate failed: $(cat "$work/simulate.err")"

solvers=(auto BANDED_CHOLESKY SPARSE_NORMAL_CHOLESKY SPARSE_SCHUR ITERATIVE_SCHUR
  DENSE_SCHUR)
header="| recording | prior |" rule="| --- | --- |"
for solver in "${solvers[@]}"; do
  header="$header $solver |" rule="$rule --- |"
done
echo "$header auto / best explicit |"
echo "$rule --- |"
for dataset in "$root/data/plaza1.rffd" "$root/data/mrclam6_robot1.rffd" \
    "$work/laser_10hz_s1.rffd"; do
  for prior in rff wnoa; do
    row="| $(basename "$dataset" .rffd) | $prior |"
    auto="" best=""
    for solver in "${solvers[@]}"; do
      start=$(date +%s.%N)
      status=0
      timeout "$limit" "$build/rff_slam" --dataset="$dataset" \
          --prior="$prior" --linear_solver="$solver" \
          > "$work/out" 2> "$work/err" || status=$?
      seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN {print b - a}')
      if [ $status = 0 ]; then
        cell=$(printf '%.2f s' "$seconds")
        if [ "$solver" = auto ]; then
          auto=$seconds
        elif [ -z "$best" ] ||
            awk -v s="$seconds" -v b="$best" 'BEGIN {exit !(s < b)}'; then
          best=$seconds
        fi
      elif [ $status = 124 ]; then
        cell="> $limit s"
      elif grep -q "needs about" "$work/err"; then
        cell="refused"
      else
        cell="exit $status"
      fi
      row="$row $cell |"
    done
    ratio=""
    if [ -n "$auto" ] && [ -n "$best" ]; then
      ratio=$(awk -v a="$auto" -v b="$best" 'BEGIN {printf "%.2f", a / b}')
    fi
    echo "$row $ratio |"
  done
done
