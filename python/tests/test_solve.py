"""rffslam against the command line on CMU Plaza 1: the same options give
the same solve (files equal to 1e-12), the same summary and the same metrics
as rff_slam and rff_evaluate, for both priors."""

import json
import math

import numpy as np
import pytest

import rffslam
from conftest import PLAZA, PLAZA_FLAGS, PLAZA_WNOA_FLAGS, app, run

# Keys whose values are wall times, which differ from run to run.
TIMES = ("mean_seconds", "learning_seconds", "ceres_seconds", "total_seconds",
         "update_seconds_mean", "update_seconds_max")
# rff_evaluate's input file names, which evaluate() has no use for.
INPUTS = ("dataset", "trajectory", "landmarks", "covariance")


def assert_same(python, cli, where="", tolerance=1e-12):
    """Equal structure; numbers within `tolerance` (relative), others equal."""
    if isinstance(cli, dict):
        assert sorted(python) == sorted(cli), where
        for key in cli:
            assert_same(python[key], cli[key], f"{where}.{key}", tolerance)
    elif isinstance(cli, list):
        assert len(python) == len(cli), where
        for i, (a, b) in enumerate(zip(python, cli)):
            assert_same(a, b, f"{where}[{i}]", tolerance)
    elif isinstance(cli, float) or isinstance(python, float):
        assert math.isclose(python, cli, rel_tol=tolerance,
                            abs_tol=tolerance), (where, python, cli)
    else:
        assert python == cli, (where, python, cli)


class Cli:
    """rff_slam's outputs and rff_evaluate's metrics of one solve."""

    def __init__(self, directory, flagfile, covariance):
        self.tum = directory / "cli.tum"
        self.landmarks = directory / "cli.landmarks"
        self.covariance = directory / "cli.cov" if covariance else None
        self.summary_json = directory / "cli.json"
        args = [app("rff_slam"), f"--flagfile={flagfile}",
                f"--dataset={PLAZA}", f"--output_trajectory={self.tum}",
                f"--output_landmarks={self.landmarks}",
                f"--summary_json={self.summary_json}"]
        if covariance:
            args.append(f"--output_covariance={self.covariance}")
        done = run(*args)
        assert done.returncode == 0, done.stderr
        self.summary = json.loads(self.summary_json.read_text())

    def evaluate(self, directory, align):
        path = directory / f"evaluate_{align}.json"
        args = [app("rff_evaluate"), f"--dataset={PLAZA}",
                f"--trajectory={self.tum}", f"--landmarks={self.landmarks}",
                f"--json={path}"]
        if self.covariance:
            args.append(f"--covariance={self.covariance}")
        if align:
            args.append("--align")
        done = run(*args)
        assert done.returncode == 0, done.stderr
        metrics = json.loads(path.read_text())
        return {k: v for k, v in metrics.items() if k not in INPUTS}


CASES = {
    # The RFF prior with covariances, the LTV-SDE prior without.
    "rff": (PLAZA_FLAGS, True),
    "wnoa": (PLAZA_WNOA_FLAGS, False),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def both(request, tmp_path_factory):
    flagfile, covariance = CASES[request.param]
    directory = tmp_path_factory.mktemp(request.param)
    cli = Cli(directory, flagfile, covariance)
    result = rffslam.solve(str(PLAZA), flagfile=str(flagfile),
                           compute_covariance=covariance)
    return directory, cli, result


def test_the_files_are_the_clis(both):
    # Equal to 1e-12, not byte for byte: the dense BLAS kernels that
    # covariances (and sparse Cholesky) go through may round differently
    # with the alignment of their arrays, which differs between processes.
    directory, cli, result = both
    files = [("tum", result.save_tum, cli.tum),
             ("landmarks", result.save_landmarks, cli.landmarks)]
    if cli.covariance:
        files.append(("cov", result.save_covariance, cli.covariance))
    for suffix, save, expected in files:
        path = directory / f"py.{suffix}"
        save(path)
        actual = np.loadtxt(path, ndmin=2)
        wanted = np.loadtxt(expected, ndmin=2)
        tolerance = 1e-12 * np.abs(wanted) + 1e-15
        if suffix == "cov":
            # Rows are `t sxx sxy sxt syy syt stt`: a cross term left small
            # by cancellation is held to 1e-10 of its pose's largest variance.
            largest = np.abs(wanted[:, 1:]).max(axis=1, keepdims=True)
            tolerance = np.maximum(tolerance, 1e-10 * largest)
        np.testing.assert_array_less(np.abs(actual - wanted), tolerance,
                                     err_msg=suffix)


def test_the_arrays_are_the_clis_outputs(both):
    _, cli, result = both
    tum = np.loadtxt(cli.tum)
    np.testing.assert_allclose(result.times, tum[:, 0], rtol=1e-12, atol=0)
    np.testing.assert_allclose(result.poses[:, :2], tum[:, 1:3], rtol=1e-12,
                               atol=1e-12)
    heading = 2 * np.arctan2(tum[:, 6], tum[:, 7])
    turn = np.remainder(result.poses[:, 2] - heading + np.pi, 2 * np.pi)
    assert np.max(np.abs(turn - np.pi)) < 1e-12
    landmarks = np.loadtxt(cli.landmarks, ndmin=2)
    np.testing.assert_array_equal(result.landmark_ids,
                                  landmarks[:, 0].astype(np.int64))
    np.testing.assert_allclose(result.landmarks, landmarks[:, 1:3],
                               rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(result.pose_at(result.times), result.poses)


def test_the_summary_is_the_clis(both):
    _, cli, result = both
    python = {k: v for k, v in result.summary.items() if k not in TIMES}
    expected = {k: v for k, v in cli.summary.items() if k not in TIMES}
    # The Gauss-Newton decrease is a difference of costs: it rounds at the
    # cost's scale, with the alignment of the dense arrays it goes through.
    decrease = "predicted_decrease"
    assert abs(python.pop(decrease) - expected.pop(decrease)) <= (
        1e-12 * expected["final_cost"])
    assert_same(python, expected)


@pytest.mark.parametrize("align", [False, True])
def test_the_metrics_are_rff_evaluates(both, align):
    directory, cli, result = both
    expected = cli.evaluate(directory, align)
    metrics = rffslam.evaluate(PLAZA, result, align=align)
    assert_same(metrics, expected)
    ape = metrics["ape_trans_m"]["rms"]
    assert abs(ape - expected["ape_trans_m"]["rms"]) < 1e-9
    # The solve itself: well below dead reckoning's 1.97 m.
    assert ape < 0.4


def test_covariance_queries_on_plaza(both):
    _, cli, result = both
    if not cli.covariance:
        assert not result.has_covariance
        return
    t = np.linspace(result.times[0], result.times[-1], 7)
    covariances = result.pose_covariance_at(t)
    assert covariances.shape == (7, 3, 3)
    for covariance in covariances:
        assert np.all(np.linalg.eigvalsh(0.5 * (covariance + covariance.T))
                      > 0)
    assert result.pose_at(t).shape == (7, 3)
