#!/usr/bin/env bash
# Runs the solver benchmarks (bench/solver_benchmark.cc) and prints Markdown
# tables for the README:
#   scripts/bench_table.sh [BUILD_DIR] [--large] [--solver_choice]
#                          [extra rff_bench flags]
# BUILD_DIR defaults to ./build; it is configured (Release) if it has no
# CMakeCache.txt, and rff_bench is (re)built. The default run takes a few
# minutes on 2 cores; --large adds the N = 1e6 BM_Iteration rows
# (SPARSE_SCHUR, ITERATIVE_SCHUR, BANDED_CHOLESKY) and whole solves with the
# default linear solver at 125000 and 1e6 observations, each in a process of
# its own so that its peak RSS is its own (a few minutes each).
# --solver_choice adds the BM_DefaultSolver rows (default flags against each
# explicit linear solver, 2k-1e5 poses), each in a process of its own under
# a 240 s timeout (30 rows: 30-40 minutes on 2 cores, at most 2 hours).
# Extra flags go to rff_bench, e.g. --threads=2 or
# --benchmark_repetitions=3 (the tables then use the medians).
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
build=$repo/build
large=0
solver_choice=0
timeout_seconds=240
extra=()
for arg in "$@"; do
  case $arg in
    --large) large=1 ;;
    --solver_choice) solver_choice=1 ;;
    --*) extra+=("$arg") ;;
    *) build=$arg ;;
  esac
done

if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release >&2
fi
make -C "$build" -j2 rff_bench >&2
bench=$build/bench/rff_bench

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# Console progress goes to stderr; the tables are made from the JSON.
"$bench" --benchmark_out="$out/quick.json" --benchmark_out_format=json \
  ${extra[@]+"${extra[@]}"} >&2
if [ "$large" = 1 ]; then
  # A row that fails (out of memory, say) is reported; the others stay.
  large_row() {
    local filter=$1 json=$2 status=0
    "$bench" --large --benchmark_filter="$filter" --benchmark_out="$json" \
      --benchmark_out_format=json ${extra[@]+"${extra[@]}"} >&2 || status=$?
    if [ $status != 0 ]; then
      printf '{"benchmarks": [{"name": "%s", "run_name": "%s", "error_occurred": true, "error_message": "exit %s"}]}\n' \
        "$filter" "$filter" "$status" > "$json"
    fi
  }
  for solver in 1 2 3; do
    large_row "BM_Iteration/N:1000000/.*/solver:$solver/" \
      "$out/large$solver.json"
  done
  for n in 125000 1000000; do
    large_row "BM_FullSolve/N:$n/" "$out/full$n.json"
  done
fi

if [ "$solver_choice" = 1 ]; then
  for poses in 2000 20000 100000; do
    for prior in 0 1; do
      for solver in 0 1 2 3 4; do
        row="BM_DefaultSolver/prior:$prior/poses:$poses/solver:$solver"
        json="$out/choice_${prior}_${poses}_$solver.json"
        status=0
        timeout "$timeout_seconds" "$bench" --solver_choice \
            ${extra[@]+"${extra[@]}"} --benchmark_filter="$row/" \
            --benchmark_out="$json" --benchmark_out_format=json >&2 ||
          status=$?
        if [ $status != 0 ]; then
          # Killed by the timeout (124) or failed: a row that says which.
          message="exit $status"
          [ $status = 124 ] && message="timeout $timeout_seconds s"
          printf '{"benchmarks": [{"name": "%s", "run_name": "%s", "error_occurred": true, "error_message": "%s"}]}\n' \
            "$row" "$row" "$message" > "$json"
        fi
      done
    done
  done
fi

python3 - "$out"/*.json <<'EOF'
import json
import sys

rows = []
for path in sys.argv[1:]:
    with open(path) as f:
        report = json.load(f)
    runs = report["benchmarks"]
    # With --benchmark_repetitions the medians stand for each row.
    has_aggregates = any(r.get("run_type") == "aggregate" for r in runs)
    for r in runs:
        if has_aggregates and r.get("aggregate_name") != "median":
            continue
        if r.get("error_occurred"):
            print(f"<!-- {r['name']}: {r.get('error_message')} -->")
            if not r["name"].startswith("BM_DefaultSolver"):
                continue
        args = {}
        parts = r["run_name"].split("/")
        for part in parts[1:]:
            if ":" in part:
                key, value = part.split(":", 1)
                args[key] = value
        r["bench"] = parts[0]
        r["args"] = args
        rows.append(r)

def ms(r):  # The row's own time (every benchmark reports milliseconds).
    return float(r["real_time"])

def fmt(x, digits=3):
    if x is None:
        return ""
    if abs(x) >= 100:
        return f"{x:.0f}"
    return f"{x:.{digits}g}"

solvers = ["DENSE_SCHUR", "SPARSE_SCHUR", "ITERATIVE_SCHUR", "BANDED_CHOLESKY"]

print("### One Levenberg-Marquardt iteration (BM_Iteration)\n")
print("| N | D | landmarks | windows | solver | ms/iteration | jacobian ms "
      "| linear solve ms | first linear solve ms | BLAS-3 bound ms "
      "| ratio to BLAS-3 | ratio (CPU time) | peak RSS MiB |")
print("| " + " | ".join(["---"] * 13) + " |")
for r in rows:
    if r["bench"] != "BM_Iteration":
        continue
    a = r["args"]
    seg = int(a["seg"])
    windows = (f"{int(r['segments'])} x {seg} s" if seg > 0 else "global")
    print(f"| {a['N']} | {a['D']} | {a['L']} | {windows} "
          f"| {solvers[int(a['solver'])]} | {fmt(r['iteration_ms'])} "
          f"| {fmt(r.get('jacobian_ms'))} | {fmt(r['linear_ms'])} "
          f"| {fmt(r['first_linear_ms'])} | {fmt(r['blas3_ms'])} "
          f"| {fmt(r['ratio_to_blas3'])} | {fmt(r['ratio_to_blas3_cpu'])} "
          f"| {fmt(r['peak_rss_MiB'])} |")

full = {(r["args"]["solver"], int(r["args"]["N"])): r
        for r in rows if r["bench"] == "BM_FullSolve"}
if full:
    print("\n### Full RunSlam, 10 LM steps (BM_FullSolve)\n")
    print("| N | landmarks | linear solver | total ms | mean ms | Ceres ms "
          "| outside Ceres and mean ms | ms/iteration | time(N)/time(N/8) "
          "| Ceres(N)/Ceres(N/8) | CPU(N)/CPU(N/8) | peak RSS MiB |")
    print("| " + " | ".join(["---"] * 12) + " |")
    for (solver, n) in sorted(full):
        r = full[(solver, n)]
        base = full.get((solver, n // 8))
        scale = fmt(ms(r) / ms(base)) if base else ""
        ceres = fmt(r["ceres_ms"] / base["ceres_ms"]) if base else ""
        cpu = fmt(r["cpu_time"] / base["cpu_time"]) if base else ""
        name = ["SPARSE_SCHUR", "auto"][int(solver)]
        print(f"| {n} | {int(r['landmarks'])} | {name} | {fmt(ms(r))} "
              f"| {fmt(r['mean_ms'])} | {fmt(r['ceres_ms'])} "
              f"| {fmt(r['outside_ceres_ms'])} "
              f"| {fmt(r['ms_per_iteration'])} | {scale} | {ceres} | {cpu} "
              f"| {fmt(r['peak_rss_MiB'])} |")

# Default (auto) against every explicit linear solver, whole RunSlam.
default_solvers = ["auto", "SPARSE_NORMAL_CHOLESKY", "SPARSE_SCHUR",
                   "ITERATIVE_SCHUR", "DENSE_SCHUR"]
choice = {}
for r in rows:
    if r["bench"] == "BM_DefaultSolver":
        a = r["args"]
        choice.setdefault((a["prior"], int(a["poses"])), {})[
            default_solvers[int(a["solver"])]] = r
if choice:
    print("\n### Default flags against each explicit linear solver "
          "(BM_DefaultSolver)\n")
    print("| prior | poses | " + " | ".join(default_solvers) +
          " | auto / best explicit | APE m (auto) |")
    print("| " + " | ".join(["---"] * (len(default_solvers) + 4)) + " |")
    for (prior, poses), by_solver in sorted(choice.items()):
        cells, explicit = [], []
        for name in default_solvers:
            r = by_solver.get(name)
            if r is None:
                cells.append("not run")
            elif r.get("error_message", "").startswith("timeout"):
                cells.append("> " + r["error_message"][8:])
            elif "needs about" in r.get("error_message", ""):
                cells.append("refused")
            elif r.get("error_occurred"):
                cells.append("failed: " + r.get("error_message", ""))
            else:
                cells.append(f"{ms(r) / 1e3:.1f} s")
                if name != "auto":
                    explicit.append(ms(r))
        auto = by_solver.get("auto")
        ratio = (fmt(ms(auto) / min(explicit))
                 if auto and not auto.get("error_occurred") and explicit
                 else "")
        ape = fmt(auto["ape_m"]) if auto and "ape_m" in auto else ""
        name = ["rff", "wnoa"][int(prior)]
        print(f"| {name} | {poses} | " + " | ".join(cells) +
              f" | {ratio} | {ape} |")

cache = {}
for r in rows:
    if r["bench"] == "BM_FeatureCache":
        a = r["args"]
        cache.setdefault((int(a["N"]), int(a["D"])), {})[a["cached"]] = r
if cache:
    print("\n### Pose maps of all observations, feature cache on/off "
          "(BM_FeatureCache)\n")
    print("| N | D | cached ms | uncached ms | speed-up | feature MiB cached "
          "| feature MiB uncached |")
    print("| " + " | ".join(["---"] * 7) + " |")
    for (n, d), pair in sorted(cache.items()):
        on, off = pair.get("1"), pair.get("0")
        if not on or not off:
            continue
        print(f"| {n} | {d} | {fmt(ms(on))} | {fmt(ms(off))} "
              f"| {fmt(ms(off) / ms(on))} | {fmt(on['feature_MiB'])} "
              f"| {fmt(off['feature_MiB'])} |")

gram = [r for r in rows if r["bench"] == "BM_GramLowerBound"]
if gram:
    print("\n### Dense Gram J^T J, Eigen SYRK, one thread "
          "(BM_GramLowerBound)\n")
    print("| rows | cols (3D) | ms | GFLOP/s |")
    print("| --- | --- | --- | --- |")
    for r in gram:
        a = r["args"]
        print(f"| {a['rows']} | {3 * int(a['D'])} | {fmt(ms(r))} "
              f"| {fmt(r['GFLOPs'])} |")
EOF
