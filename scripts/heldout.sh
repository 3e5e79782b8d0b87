#!/usr/bin/env bash
# The held-out evaluation protocol (docs/heldout.md): generates the tune and
# score datasets, solves each with rff_slam's DEFAULT flags under both
# priors, scores them, and prints one Markdown row per dataset and a summary
# per split.
#   scripts/heldout.sh BUILD_DIR OUT_DIR [--quick] [--consistency]
# Builds the tools in BUILD_DIR first (Release). Needs ../shared/data
# beside the repository. Writes OUT_DIR/data (inputs),
# OUT_DIR/runs (every output and log), OUT_DIR/heldout.csv and
# OUT_DIR/heldout.md. --quick: one dataset of each kind, a smoke test.
# --consistency: every solve also writes its pose covariances, and the
# table gains the mean position NEES and the 95%-ellipse coverage (the
# times then include the covariance).
set -euo pipefail

fail() { echo "heldout: error: $*" >&2; exit 1; }

usage="usage: scripts/heldout.sh BUILD_DIR OUT_DIR [--quick] [--consistency]"
[ $# -ge 2 ] && [ $# -le 4 ] || fail "$usage"
quick=0 consistency=0
for option in "${@:3}"; do
  case "$option" in
    --quick) quick=1 ;;
    --consistency) consistency=1 ;;
    *) fail "unknown option '$option' (expected --quick or --consistency)" ;;
  esac
done
root="$(cd "$(dirname "$0")/.." && pwd)"
shared="$root/../shared/data"
[ -d "$shared" ] || fail "$shared not found: the protocol needs ../shared/data (the raw datasets) beside the repository"
mkdir -p "$1" "$2"
build="$(cd "$1" && pwd)"
out="$(cd "$2" && pwd)"
data="$out/data" runs="$out/runs"
rm -rf "$data" "$runs"
mkdir -p "$data" "$runs"
start_seconds=$SECONDS

# The tools as the working tree has them now, so that the table is the
# solver's of this moment.
echo "heldout: building the tools in $build" >&2
{ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release &&
    cmake --build "$build" -j2 --target rff_slam rff_evaluate \
        rff_dead_reckoning rff_convert rff_simulate rff_perturb \
        exact_gp_reference; } > "$out/build.log" 2>&1 ||
  fail "the build failed (see $out/build.log)"
manifest="$out/datasets.tsv"
: > "$manifest"

# ---------------------------------------------------------------------------
# (a) Data. Every dataset is OUT_DIR/data/NAME.rffd, listed in the manifest
# with its split and kind. Tool output goes to runs/generate.log.
log="$runs/generate.log"
add() {
  if awk -F'\t' -v name="$1" '$1 == name {found = 1} END {exit !found}' \
      "$manifest"; then
    fail "two datasets named $1"
  fi
  printf '%s\t%s\t%s\n' "$1" "$2" "$3" >> "$manifest"
}
quietly() { "$@" >> "$log" 2>&1 || fail "$* failed (see $log)"; }

# MRCLAM robot N with its map priors 1 m off (seed 100 + N).
mrclam() {
  local robot=$1 split=$2
  quietly "$build/rff_convert" --format=mrclam --input="$shared/mrclam6" \
      --mrclam_robot="$robot" --mrclam_odometry_interval=1 \
      --output="$data/mrclam6_robot$robot.rffd"
  quietly "$build/rff_perturb" --input="$data/mrclam6_robot$robot.rffd" \
      --output="$data/mrclam6_robot${robot}_map_1m_off.rffd" \
      --landmark_prior_offset=1 --seed=$((100 + robot))
  add "mrclam6_robot${robot}_map_1m_off" "$split" mrclam
}

# The same robot stated as the ../shared heldout/ file is (loose sigmas:
# range 0.15 m, bearing 0.05 rad, odometry 0.02 m and rad per step of at
# most 0.25 s, first pose 0.05), its map priors 1 m off (seed 200 + N).
mrclam_as_shared() {
  local robot=$1 split=$2
  local name="mrclam6_robot${robot}_as_shared_map_1m_off"
  quietly "$build/rff_convert" --format=mrclam --input="$shared/mrclam6" \
      --mrclam_robot="$robot" --mrclam_odometry_interval=0.25 \
      --mrclam_range_sigma=0.15 --mrclam_bearing_sigma=0.05 \
      --mrclam_odom_sigma_xy_floor=0.02 --mrclam_odom_sigma_theta_floor=0.02 \
      --mrclam_odom_sigma_theta_per_s=0 --prior_sigma_xy=0.05 \
      --prior_sigma_theta=0.05 --output="$data/mrclam6_robot${robot}_as_shared.rffd"
  quietly "$build/rff_perturb" --input="$data/mrclam6_robot${robot}_as_shared.rffd" \
      --output="$data/$name.rffd" --landmark_prior_offset=1 \
      --seed=$((200 + robot))
  add "$name" "$split" mrclam
}

# Plaza 1 (converted from the raw files) with the start heading turned by
# DEG degrees and unknown (sigma pi).
plaza_heading() {
  local degrees=$1 split=$2
  [ -f "$data/plaza1_converted.rffd" ] ||
    quietly "$build/rff_convert" --format=plaza --input="$shared/plaza1" \
        --output="$data/plaza1_converted.rffd"
  quietly "$build/rff_perturb" --input="$data/plaza1_converted.rffd" \
      --output="$data/plaza1_heading_$degrees.rffd" \
      --start_heading_offset_deg="$degrees" \
      --start_heading_sigma=3.141592653589793
  add "plaza1_heading_$degrees" "$split" plaza
}

laser() {
  local seed=$1 split=$2
  quietly "$build/rff_simulate" --preset=laser_10hz --seed="$seed" \
      --output="$data/laser_10hz_s$seed.rffd"
  add "laser_10hz_s$seed" "$split" laser
}

gp_draw() {
  local seed=$1 kernel=$2 lengthscale=$3 split=$4
  local name="gp_draw_s${seed}_${kernel}_ell$lengthscale"
  quietly "$build/rff_simulate" --preset=gp_draw --seed="$seed" \
      --gp_kernel="$kernel" --gp_lengthscale="$lengthscale" \
      --output="$data/$name.rffd"
  add "$name" "$split" gp_draw
}

# A file of ../shared/data, copied as it is; PREFIX keeps its name apart
# from the generated ones (heldout/ has its own mrclam6_robot3_map_1m_off).
shared_file() {
  local path=$1 split=$2 kind=$3 prefix=${4:-}
  local name
  name="$prefix$(basename "$path" .rffd)"
  cp "$shared/$path" "$data/$name.rffd"
  add "$name" "$split" "$kind"
}

echo "heldout: generating data in $data" >&2
if [ $quick = 1 ]; then
  # One dataset of each kind, every tool used once.
  mrclam 4 score
  plaza_heading 90 score
  laser 2 score
  gp_draw 1 rbf 10 tune
  shared_file synthetic/s3_range_L50_o1.rffd score synthetic
  shared_file heldout/gp_draw_matern52_ell8.rffd score shared shared_
else
  # TUNE: what defaults may be chosen on.
  mrclam 1 tune
  mrclam 2 tune
  mrclam_as_shared 1 tune
  mrclam_as_shared 2 tune
  cp "$root/data/plaza1.rffd" "$data/plaza1.rffd"
  add plaza1 tune plaza
  laser 1 tune
  gp_draw 1 rbf 10 tune
  gp_draw 2 matern52 8 tune
  gp_draw 3 matern32 5 tune
  for seed in 1 2; do
    for odometry in 1 0; do
      shared_file "synthetic/s${seed}_rb_L50_o$odometry.rffd" tune synthetic
    done
  done
  # SCORE: what decides whether the defaults generalise.
  for robot in 3 4 5; do mrclam "$robot" score; done
  mrclam_as_shared 4 score
  mrclam_as_shared 5 score
  plaza_heading 90 score
  plaza_heading 180 score
  cp "$root/data/plaza2.rffd" "$data/plaza2.rffd"
  add plaza2 score plaza
  laser 2 score
  laser 3 score
  gp_draw 101 rbf 3 score
  gp_draw 102 rbf 10 score
  gp_draw 103 rbf 30 score
  gp_draw 104 matern52 3 score
  gp_draw 105 matern52 8 score
  gp_draw 106 matern52 30 score
  for seed in 3 4 5; do
    for kind in range bearing; do
      for odometry in 1 0; do
        shared_file "synthetic/s${seed}_${kind}_L50_o$odometry.rffd" score \
            synthetic
      done
    done
  done
  for file in plaza1_start_heading_unknown gp_draw_matern52_ell8 \
              mrclam6_robot3_map_1m_off; do
    shared_file "heldout/$file.rffd" score shared shared_
  done
fi

# ---------------------------------------------------------------------------
# (b, c) Runs, at most two at a time. Each writes runs/NAME.WHAT.* and its
# exit status to runs/NAME.WHAT.rc; a failure is a row entry, not a stop.

# The kernel of a "# truth:" line (both spellings: "kernel=rbf ..." and
# "kernel rbf ..."); empty without one.
truth_kernel() {
  sed -n 's/^# truth: *kernel[= ]\([A-Za-z0-9_]*\).*/\1/p' "$1"
}

# rff_slam with default flags (plus the true kernel for RFF on a GP draw),
# timed, then scored.
solve() {
  local name=$1 prior=$2
  local file="$data/$name.rffd" base="$runs/$name.$prior"
  local extra=() rc=0 kernel
  kernel="$(truth_kernel "$file")"
  if [ "$prior" = rff ] && [ -n "$kernel" ]; then extra=(--kernel="$kernel"); fi
  local covariance=()
  if [ "$consistency" = 1 ]; then
    extra+=(--output_covariance="$base.cov")
    covariance=(--covariance="$base.cov")
  fi
  /usr/bin/time -f %e -o "$base.time" timeout 300 "$build/rff_slam" \
      --dataset="$file" --prior="$prior" ${extra[@]+"${extra[@]}"} \
      --output_trajectory="$base.tum" --output_landmarks="$base.landmarks" \
      --summary_json="$base.json" > "$base.log" 2>&1 || rc=$?
  echo "$rc" > "$base.rc"
  if [ "$rc" = 0 ]; then
    "$build/rff_evaluate" --dataset="$file" --trajectory="$base.tum" \
        --landmarks="$base.landmarks" ${covariance[@]+"${covariance[@]}"} \
        --json="$base.eval.json" >> "$base.log" 2>&1 ||
      echo "evaluate failed" >> "$base.log"
  fi
}

dead_reckoning() {
  local name=$1
  local file="$data/$name.rffd" base="$runs/$name.dr" rc=0
  { "$build/rff_dead_reckoning" --hold_through_gaps --dataset="$file" \
        --output_trajectory="$base.tum" &&
      "$build/rff_evaluate" --dataset="$file" --trajectory="$base.tum" \
          --json="$base.eval.json"; } > "$base.log" 2>&1 || rc=$?
  echo "$rc" > "$base.rc"
}

exact_gp() {
  local name=$1
  local base="$runs/$name.exact" rc=0
  timeout 300 "$build/test/exact_gp_reference" "$data/$name.rffd" \
      > "$base.log" 2>&1 || rc=$?
  echo "$rc" > "$base.rc"
}

# Starts "$@" in the background once fewer than two jobs run.
pool() {
  while [ "$(jobs -rp | wc -l)" -ge 2 ]; do wait -n || true; done
  "$@" < /dev/null &
}

echo "heldout: solving $(wc -l < "$manifest") datasets x {rff, wnoa}" >&2
while IFS=$'\t' read -r name split kind; do
  echo "heldout:   $name ($split, $kind)" >&2
  if grep -q '^ODOM' "$data/$name.rffd"; then pool dead_reckoning "$name"; fi
  if grep -q '^# truth:' "$data/$name.rffd"; then pool exact_gp "$name"; fi
  pool solve "$name" rff
  pool solve "$name" wnoa
done < "$manifest"
wait

# ---------------------------------------------------------------------------
# (d) Table, summaries, CSV and Markdown.
python3 - "$manifest" "$runs" "$out" "$build" "$root" \
    $((SECONDS - start_seconds)) "$consistency" <<'EOF'
import csv, json, os, re, statistics, subprocess, sys

manifest, runs, out, build, root, seconds, consistency = sys.argv[1:]
consistency = consistency == "1"
# The bands a consistent covariance falls in (mean position NEES, ideal 2;
# share of poses inside their 95% ellipse).
NEES_BAND, COVERAGE_BAND = (1.5, 3.0), (0.90, 0.98)

def read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None

def load_json(path):
    text = read(path)
    return json.loads(text) if text else {}

def rms(evaluation, key):
    value = evaluation.get(key)
    return value["rms"] if isinstance(value, dict) else None

def run(name, what):
    """Exit status, APE, landmark RMS, wall time, verdict, reasons."""
    base = os.path.join(runs, f"{name}.{what}")
    rc = read(base + ".rc")
    if rc is None:
        return None
    evaluation = load_json(base + ".eval.json")
    summary = load_json(base + ".json")
    quality = summary.get("quality")
    verdict = summary.get("verdict")
    if verdict is None and isinstance(quality, dict):
        verdict = quality.get("verdict")
    if verdict is None and isinstance(quality, str):
        verdict = quality
    reasons = summary.get("quality_reasons")
    if reasons is None and isinstance(quality, dict):
        reasons = quality.get("reasons")
    time_lines = (read(base + ".time") or "").split()
    return {
        "rc": int(rc),
        "ape": rms(evaluation, "ape_trans_m"),
        "landmarks": rms(evaluation, "landmark_error_m"),
        "seconds": float(time_lines[-1]) if time_lines else None,
        "verdict": verdict,
        "reasons": "; ".join(reasons or []),
        "nees": evaluation.get("mean_position_nees"),
        "coverage": evaluation.get("position_coverage_95"),
        "rot": rms(evaluation, "ape_rot_deg"),
        "heading_nees": evaluation.get("mean_heading_nees"),
    }

def exact(name):
    base = os.path.join(runs, f"{name}.exact")
    rc = read(base + ".rc")
    if rc is None:
        return None
    match = re.search(r"APE-trans RMS ([0-9.eE+-]+) m", read(base + ".log") or "")
    return {"rc": int(rc), "ape": float(match.group(1)) if match else None}

def dr(name):
    r = read(os.path.join(runs, f"{name}.dr.rc"))
    if r is None:
        return None
    evaluation = load_json(os.path.join(runs, f"{name}.dr.eval.json"))
    return {"rc": int(r), "ape": rms(evaluation, "ape_trans_m")}

def ape_cell(r):
    """The APE, fail(rc), or fail(rc): APE when a failed run still scored
    (exact_gp_reference exits 2 when it stops short of its tolerance)."""
    if r is None:
        return "-"
    ape = "-" if r["ape"] is None else f"{r['ape']:.3f}"
    if r["rc"] == 0:
        return ape
    return f"fail({r['rc']})" + ("" if r["ape"] is None else f": {ape}")

def ok(r):
    return r is not None and r["rc"] == 0 and r["ape"] is not None

def plain(r, key, form):
    if r is None or r["rc"] != 0 or r.get(key) is None:
        return "-"
    return format(r[key], form)

rows = []
with open(manifest) as f:
    for name, split, kind in csv.reader(f, delimiter="\t"):
        rows.append({"name": name, "split": split, "kind": kind,
                     "dr": dr(name), "rff": run(name, "rff"),
                     "wnoa": run(name, "wnoa"), "exact": exact(name)})

header = ["dataset", "split", "kind", "DR APE [m]", "RFF APE [m]",
          "WNOA APE [m]", "exact-GP APE [m]", "RFF lm RMS [m]",
          "WNOA lm RMS [m]", "RFF time [s]", "WNOA time [s]", "RFF quality",
          "WNOA quality"]
if consistency:
    header += ["RFF NEES / 95%", "WNOA NEES / 95%"]

def consistency_cell(x):
    if x is None or x["rc"] != 0 or x["nees"] is None:
        return "-"
    return f"{x['nees']:.2f} / {x['coverage']:.3f}"

lines = ["| " + " | ".join(header) + " |",
         "| " + " | ".join("---" for _ in header) + " |"]
for r in rows:
    time_cell = lambda x: "-" if x is None or x["seconds"] is None \
        else f"{x['seconds']:.1f}"
    verdict = lambda x: "-" if x is None or x["rc"] != 0 \
        else (x["verdict"] or "-")
    cells = [r["name"], r["split"], r["kind"], ape_cell(r["dr"]),
             ape_cell(r["rff"]), ape_cell(r["wnoa"]), ape_cell(r["exact"]),
             plain(r["rff"], "landmarks", ".3f"),
             plain(r["wnoa"], "landmarks", ".3f"), time_cell(r["rff"]),
             time_cell(r["wnoa"]), verdict(r["rff"]), verdict(r["wnoa"])]
    if consistency:
        cells += [consistency_cell(r["rff"]), consistency_cell(r["wnoa"])]
    lines.append("| " + " | ".join(cells) + " |")

def plural(n):
    return f"{n} dataset" + ("" if n == 1 else "s")

def ratio_line(label, pairs, failures):
    ratios = sorted(a / b for a, b in pairs if b > 0)
    if not ratios:
        return f"- {label}: no pair solved ({failures} with a failed side)"
    return (f"- {label}: median {statistics.median(ratios):.2f}, worst "
            f"{ratios[-1]:.2f} over {plural(len(ratios))} "
            f"({failures} with a failed side)")

summary = []
for split in ("tune", "score"):
    mine = [r for r in rows if r["split"] == split]
    if not mine:
        continue
    failed = [f"{r['name']} ({p})" for r in mine for p in ("rff", "wnoa")
              if r[p] is not None and r[p]["rc"] != 0]
    summary.append(f"**{split}** ({plural(len(mine))}; failed solves: "
                   f"{', '.join(failed) if failed else 'none'})")
    summary.append("")
    both = [r for r in mine if ok(r["rff"]) and ok(r["wnoa"])]
    summary.append(ratio_line(
        "APE ratio RFF/WNOA",
        [(r["rff"]["ape"], r["wnoa"]["ape"]) for r in both],
        len(mine) - len(both)))
    draws = [r for r in mine if r["exact"] is not None]
    if draws:
        good = [r for r in draws if ok(r["rff"]) and ok(r["exact"])]
        summary.append(ratio_line(
            "APE ratio RFF/exact GP (GP draws)",
            [(r["rff"]["ape"], r["exact"]["ape"]) for r in good],
            len(draws) - len(good)))
    if consistency:
        for prior in ("rff", "wnoa"):
            scored = [r[prior] for r in mine
                      if r[prior] is not None and r[prior]["nees"] is not None]
            inside = [x for x in scored
                      if NEES_BAND[0] <= x["nees"] <= NEES_BAND[1] and
                      COVERAGE_BAND[0] <= x["coverage"] <= COVERAGE_BAND[1]]
            median = (f"median NEES {statistics.median(x['nees'] for x in scored):.2f}, "
                      if scored else "")
            summary.append(
                f"- {prior.upper()} consistency: {median}{len(inside)} of "
                f"{len(scored)} with NEES in [{NEES_BAND[0]}, {NEES_BAND[1]}] "
                f"and 95% coverage in [{COVERAGE_BAND[0]}, {COVERAGE_BAND[1]}]")
    summary.append("")

commit = subprocess.run(["git", "-C", root, "describe", "--always", "--dirty"],
                        capture_output=True, text=True).stdout.strip()
minutes = int(seconds) / 60
title = (f"Held-out protocol: {plural(len(rows))}, rff_slam default flags, "
         f"solver at {commit or 'unknown commit'} ({build}); "
         f"{minutes:.1f} min in all.")
text = "\n".join([title, ""] + lines + [""] + summary)
print(text)
with open(os.path.join(out, "heldout.md"), "w") as f:
    f.write("# Held-out results\n\n" + text + "\n")

with open(os.path.join(out, "heldout.csv"), "w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["dataset", "split", "kind", "dr_ape_m", "rff_ape_m",
                "wnoa_ape_m", "exact_gp_ape_m", "rff_landmark_rms_m",
                "wnoa_landmark_rms_m", "rff_seconds", "wnoa_seconds",
                "rff_rc", "wnoa_rc", "exact_gp_rc", "rff_verdict",
                "wnoa_verdict", "rff_quality_reasons", "wnoa_quality_reasons",
                "rff_position_nees", "rff_coverage_95", "wnoa_position_nees",
                "wnoa_coverage_95", "rff_ape_rot_deg", "wnoa_ape_rot_deg",
                "rff_heading_nees", "wnoa_heading_nees"])
    get = lambda x, k: "" if x is None or x.get(k) is None else x[k]
    for r in rows:
        w.writerow([r["name"], r["split"], r["kind"], get(r["dr"], "ape"),
                    get(r["rff"], "ape"), get(r["wnoa"], "ape"),
                    get(r["exact"], "ape"), get(r["rff"], "landmarks"),
                    get(r["wnoa"], "landmarks"), get(r["rff"], "seconds"),
                    get(r["wnoa"], "seconds"), get(r["rff"], "rc"),
                    get(r["wnoa"], "rc"), get(r["exact"], "rc"),
                    get(r["rff"], "verdict"), get(r["wnoa"], "verdict"),
                    get(r["rff"], "reasons"), get(r["wnoa"], "reasons"),
                    get(r["rff"], "nees"), get(r["rff"], "coverage"),
                    get(r["wnoa"], "nees"), get(r["wnoa"], "coverage"),
                    get(r["rff"], "rot"), get(r["wnoa"], "rot"),
                    get(r["rff"], "heading_nees"),
                    get(r["wnoa"], "heading_nees")])
EOF
