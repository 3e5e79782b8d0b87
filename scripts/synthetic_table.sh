#!/usr/bin/env bash
# Median APE-trans of rff_slam over the simulated benchmark sets (paper
# protocol; seeds 1-5 x {10, 50} landmarks per cell), as a Markdown table:
#   scripts/synthetic_table.sh BUILD_DIR SYNTHETIC_DIR [extra rff_slam flags]
# Uses configs/synthetic_{range_bearing,range,bearing}${SUFFIX}.flags, so
# SUFFIX=_wnoa gives the LTV-SDE baseline's table.
set -euo pipefail
build=$1 dir=$2
shift 2
root="$(cd "$(dirname "$0")/.." && pwd)"
echo "| kind | odometry | median APE-trans [m] | worst [m] | mean time [s] | failures |"
echo "| --- | --- | --- | --- | --- | --- |"
for kind in rb range bearing; do
  case $kind in
    rb) config=synthetic_range_bearing ;;
    range) config=synthetic_range ;;
    bearing) config=synthetic_bearing ;;
  esac
  for odometry in 1 0; do
    results=""
    failures=0
    for seed in 1 2 3 4 5; do
      for landmarks in 10 50; do
        file="$dir/s${seed}_${kind}_L${landmarks}_o${odometry}.rffd"
        if out=$("$build/rff_slam" \
                 --flagfile="$root/configs/$config${SUFFIX:-}.flags" \
                 --dataset="$file" "$@" 2>/dev/null); then
          results+=$(echo "$out" | awk '/^APE translation/ {a = $4}
                                        / s total$/ {t = $(NF - 2)}
                                        END {print a, t}')$'\n'
        else
          failures=$((failures + 1))
        fi
      done
    done
    echo -n "$results" | sort -g | awk -v kind=$kind -v odo=$odometry \
        -v failures=$failures '
      {ape[NR] = $1; time += $2}
      END {
        if (NR == 0) {printf "| %s | %s | - | - | - | %d |\n", kind, odo ? "yes" : "no", failures; exit}
        median = (NR % 2) ? ape[(NR + 1) / 2] : (ape[NR / 2] + ape[NR / 2 + 1]) / 2
        printf "| %s | %s | %.2f | %.2f | %.2f | %d |\n", kind,
               odo ? "yes" : "no", median, ape[NR], time / NR, failures
      }'
  done
done
