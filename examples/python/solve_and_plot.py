"""Solves the bundled CMU Plaza 1 run with both trajectory priors and plots
the trajectories and landmarks against the ground truth to a PNG.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/solve_and_plot.py
"""

import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # Files only: no display needed.
import matplotlib.pyplot as plt  # noqa: E402

import rffslam  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
PRIORS = {  # Label: the tuned flagfile of each prior.
    "RFF": ROOT / "configs" / "plaza.flags",
    "LTV-SDE (WNOA)": ROOT / "configs" / "plaza_wnoa.flags",
}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", default=ROOT / "data" / "plaza1.rffd")
    parser.add_argument("--output", default=ROOT / "out" / "plaza1_priors.png")
    args = parser.parse_args()

    dataset = rffslam.read_dataset(args.dataset)
    figure, axes = plt.subplots(figsize=(8, 8))
    truth = dataset.ground_truth_poses
    if len(truth):
        axes.plot(truth[:, 0], truth[:, 1], color="black", lw=1,
                  label="ground truth")
        axes.scatter(*dataset.ground_truth_landmarks.T, marker="*", s=200,
                     color="black", label="true landmarks")
    for (label, flagfile), color in zip(PRIORS.items(), ("C0", "C3")):
        result = rffslam.solve(dataset, flagfile=flagfile)
        seconds = result.summary["total_seconds"]
        if len(truth):
            ape = rffslam.evaluate(dataset, result)["ape_trans_m"]["rms"]
            label += f": APE {ape:.3f} m"
        print(f"{label}, {seconds:.2f} s")
        axes.plot(result.poses[:, 0], result.poses[:, 1], color=color, lw=0.8,
                  label=label)
        axes.scatter(*result.landmarks.T, marker="x", s=80, color=color)
    axes.set_aspect("equal")
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    axes.set_title(f"{pathlib.Path(args.dataset).name}: both priors")
    axes.legend(loc="best")
    output = pathlib.Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(output, dpi=120, bbox_inches="tight")
    print(f"wrote {output}")


if __name__ == "__main__":
    main()
