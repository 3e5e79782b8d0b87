#!/usr/bin/python3
"""rff_slam against the numpy peer (numpy_dense_lm.py) on the same data.

Usage: compare.py BUILD_DIR [DATASET.rffd ...] [--repeats=3] [--num_features=100]

Without datasets it simulates the paper's setting (rff_simulate --preset=paper,
300 steps, range-bearing with odometry, seeds 1-3) into a temporary directory.
For each dataset it times, best of --repeats, whole processes (start, read,
solve, write; Python's start and numpy's import count for the peer):

- peer: the numpy dense LM of one global Hilbert map (RBF, lengthscale 5 s,
  variance 100 m^2 / 0.25 rad^2, D features, dead-reckoning mean);
- same model: rff_slam with the flags that make that model
  (SAME_MODEL_FLAGS), whose final cost and APE it prints beside the peer's;
- default: rff_slam --num_features=D and default flags otherwise, which
  learns its hyperparameters;
- default, no learning: the same with --learn_hyperparameters=off.

Prints a Markdown table with each time's ratio to the peer (peer / rff_slam:
above 1, rff_slam is faster).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
PEER = os.path.join(HERE, "numpy_dense_lm.py")
SAME_MODEL_FLAGS = [
    "--prior_mean=odometry", "--features=hilbert", "--segment_length=0",
    "--kernel=rbf", "--lengthscale=5", "--kernel_variance=100",
    "--heading_kernel_variance=0.25", "--learn_hyperparameters=off",
    "--loss=none", "--odometry_loss=none",
]


def timed(command):
    """Wall seconds of one process and its stdout; exits on failure."""
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
    return seconds, done.stdout


def best(command, repeats):
    runs = [timed(command) for _ in range(repeats)]
    return min(runs, key=lambda run: run[0])


def solve(build, dataset, flags, repeats, summary):
    command = [os.path.join(build, "rff_slam"), f"--dataset={dataset}",
               f"--summary_json={summary}", "--logtostderr=false",
               "--minloglevel=1"] + flags
    seconds, out = best(command, repeats)
    ape = None
    for line in out.splitlines():
        if line.startswith("APE translation"):
            ape = float(line.split()[3])
    with open(summary, encoding="utf-8") as f:
        return seconds, json.load(f), ape


def simulate(build, directory):
    paths = []
    for seed in (1, 2, 3):
        path = os.path.join(directory, f"paper_rb_s{seed}.rffd")
        timed([os.path.join(build, "rff_simulate"), "--preset=paper",
               "--kind=range_bearing", f"--seed={seed}", f"--output={path}"])
        paths.append(path)
    return paths


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("build")
    parser.add_argument("datasets", nargs="*")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--num_features", type=int, default=100)
    args = parser.parse_args()
    if args.repeats < 1 or args.num_features < 1:
        sys.exit("--repeats and --num_features must be 1 or more")
    d = f"--num_features={args.num_features}"
    with tempfile.TemporaryDirectory() as directory:
        datasets = args.datasets or simulate(args.build, directory)
        summary = os.path.join(directory, "summary.json")
        print("| dataset | peer [s] | same model [s] | ratio | default [s] "
              "| ratio | default, no learning [s] | ratio | iterations peer / "
              "same model | final cost peer / same model | APE [m] peer / "
              "same model / default |")
        print("| --- " * 11 + "|")
        for dataset in datasets:
            peer_s, out = best([sys.executable, PEER, dataset, d], args.repeats)
            peer = json.loads(out)
            same_s, same, same_ape = solve(args.build, dataset,
                                           SAME_MODEL_FLAGS + [d],
                                           args.repeats, summary)
            default_s, _, default_ape = solve(args.build, dataset, [d],
                                              args.repeats, summary)
            fixed_s, _, _ = solve(args.build, dataset,
                                  [d, "--learn_hyperparameters=off"],
                                  args.repeats, summary)
            costs = f"{peer['final_cost']:.3f} / {same['final_cost']:.3f}"
            if abs(peer["final_cost"] - same["final_cost"]) > 1e-6 * abs(
                    same["final_cost"]):
                costs += " (not the same optimum)"
                print(f"compare.py: {dataset}: the peer and rff_slam end at "
                      "different costs", file=sys.stderr)
            apes = " / ".join("-" if a is None else f"{a:.4f}" for a in
                              (peer["ape_trans_m"], same_ape, default_ape))
            print(f"| {os.path.basename(dataset)} | {peer_s:.3f} "
                  f"| {same_s:.3f} | {peer_s / same_s:.2f} "
                  f"| {default_s:.3f} | {peer_s / default_s:.2f} "
                  f"| {fixed_s:.3f} | {peer_s / fixed_s:.2f} "
                  f"| {peer['iterations']} / {same['iterations']} "
                  f"| {costs} "
                  f"| {apes} |")


if __name__ == "__main__":
    main()
