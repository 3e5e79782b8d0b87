"""rffslam.solve's options and every error path of the API, on a small
simulated run: each bad input raises, and the interpreter carries on."""

import concurrent.futures
import math
import re

import numpy as np
import pytest

import rffslam


@pytest.fixture(scope="module")
def solved(small):
    return rffslam.solve(small, compute_covariance=True)


@pytest.fixture(scope="module")
def plain(small):
    return rffslam.solve(small)


def flagfile(tmp_path, text, name="test.flags"):
    path = tmp_path / name
    path.write_text(text)
    return path


# --- Option names and values ---------------------------------------------

def test_options_lists_the_solver_flags_only():
    options = rffslam.options()
    assert options["prior"]["default"] == "rff"
    assert options["num_features"]["type"] == "int32"
    assert "Trajectory prior" in options["prior"]["help"]
    for name in ("dataset", "output_trajectory", "flagfile", "v", "help"):
        assert name not in options


def test_an_unknown_option_is_named_with_the_nearest(small):
    with pytest.raises(ValueError, match=r"unknown option 'num_featurs' "
                                         r"\(did you mean 'num_features'"):
        rffslam.solve(small, num_featurs=12)
    with pytest.raises(ValueError, match="unknown option 'xyzzy'.*options()"):
        rffslam.solve(small, xyzzy=1)
    # glog's and gflags's flags are not solver options.
    for name in ("v", "logtostderr", "helpfull", "fromenv"):
        with pytest.raises(ValueError, match=f"unknown option '{name}'"):
            rffslam.solve(small, **{name: "1"})


@pytest.mark.parametrize("name,hint", [
    ("dataset", "first argument"), ("output_trajectory", "save_tum"),
    ("output_landmarks", "save_landmarks"),
    ("output_covariance", "compute_covariance=True"),
    ("summary_json", "Result.summary"), ("evaluate", "rffslam.evaluate"),
])
def test_the_clis_file_flags_point_to_the_python_way(small, name, hint):
    with pytest.raises(ValueError, match=f"'{name}'.*{hint}"):
        rffslam.solve(small, **{name: "x"})


@pytest.mark.parametrize("options,message", [
    ({"num_features": "many"}, "--num_features=many: not a valid int32 "
                               "value"),
    ({"num_features": 1.5}, "--num_features=1.5: not a valid int32"),
    ({"num_features": 2**40}, "--num_features=1099511627776: not a valid"),
    ({"lengthscale": "long"}, "--lengthscale=long: not a valid double"),
    ({"estimate_range_calibration": "perhaps"},
     "--estimate_range_calibration=perhaps: not a valid bool"),
    ({"prior": "gp"}, "--prior=gp: unknown prior; allowed rff, wnoa or wnoj"),
    ({"num_features": -3}, "num_features"),
    ({"lengthscale": [1.0]}, "option 'lengthscale' must be a bool, int, "
                             "float or str, got list"),
    ({"prior": None}, "option 'prior' must be"),
    ({"compute_covariance": "yes"}, "'compute_covariance' must be True or "
                                    "False"),
    ({"verbose": 1}, "'verbose' must be True or False"),
])
def test_a_bad_value_is_named(small, options, message):
    with pytest.raises(ValueError) as error:
        rffslam.solve(small, **options)
    assert message in str(error.value)


def test_values_are_spelled_as_on_the_command_line(small):
    numbers = rffslam.solve(small, lengthscale=np.float64(12.5),
                            num_features=np.int64(8),
                            estimate_range_calibration=True, seed=2)
    text = rffslam.solve(small, lengthscale="12.5", num_features="8",
                         estimate_range_calibration="true", seed="2")
    assert numbers.summary["lengthscale"] == 12.5
    assert numbers.summary["num_features"] == 8
    np.testing.assert_array_equal(numbers.poses, text.poses)


def test_options_do_not_leak_into_the_next_solve(small, plain):
    wnoa = rffslam.solve(small, prior="wnoa", lengthscale=3.0)
    assert wnoa.summary["prior"] == "wnoa"
    again = rffslam.solve(small)
    assert again.summary["prior"] == "rff"
    np.testing.assert_array_equal(again.poses, plain.poses)
    assert rffslam.options()["lengthscale"]["default"] == "10"


def test_each_markov_prior_keeps_its_own_diffusion(small):
    # WNOJ's Q_c is a jerk's (m^2/s^5): its own option, its own summary key.
    wnoj = rffslam.solve(small, prior="wnoj", wnoj_position_qc=0.25,
                         wnoa_position_qc=4.0)
    assert wnoj.summary["prior"] == "wnoj"
    assert wnoj.summary["wnoj_position_qc"] == 0.25
    assert wnoj.summary["wnoa_position_qc"] == 4.0
    assert np.isfinite(wnoj.poses).all()
    assert len(wnoj.poses) == len(rffslam.solve(small, prior="wnoa").poses)


def test_solves_in_threads_agree(small, plain):
    # The GIL is released: the solves overlap, and share no state.
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        results = list(pool.map(lambda _: rffslam.solve(small), range(4)))
    for result in results:
        np.testing.assert_array_equal(result.poses, plain.poses)


def test_verbose_logs_the_iterations(small, capfd):
    rffslam.solve(small, verbose=True, prior="wnoa")
    assert "iteration 0: cost" in capfd.readouterr().err
    rffslam.solve(small, prior="wnoa")
    assert "iteration" not in capfd.readouterr().err


# --- Flagfiles ------------------------------------------------------------

def test_the_flagfile_is_read_first_and_keywords_override_it(small,
                                                             tmp_path):
    path = flagfile(tmp_path, "# a comment\n--prior=wnoa\n"
                              "--noestimate_range_calibration\n"
                              "--wnoa_position_qc=0.5\n")
    from_file = rffslam.solve(small, flagfile=path)
    assert from_file.summary["prior"] == "wnoa"
    assert from_file.summary["wnoa_position_qc"] == 0.5
    overridden = rffslam.solve(small, wnoa_position_qc=2.0, flagfile=path)
    assert overridden.summary["wnoa_position_qc"] == 2.0
    nested = flagfile(tmp_path, f"--flagfile={path}\n--prior=rff\n",
                      "nested.flags")
    assert rffslam.solve(small, flagfile=str(nested)).summary["prior"] == "rff"


def test_flagfile_errors_name_the_file_and_line(small, tmp_path):
    cases = [
        ("--prior=wnoa\n--num_featurs=3\n",
         ":2: unknown flag '--num_featurs'"),
        ("--prior=wnoa\n--num_features=many\n",
         ":2: illegal value in '--num_features=many'"),
        ("prior=wnoa\n", ":1: expected --name=value"),
        ("--v=2\n", ":1: unknown flag '--v'"),
        ("--output_trajectory=x.tum\n", ":1: unknown flag"),
        ("--prior=gp\n", "--prior=gp: unknown prior; allowed rff, wnoa or wnoj"),
    ]
    for i, (text, message) in enumerate(cases):
        path = flagfile(tmp_path, text, f"case{i}.flags")
        with pytest.raises(ValueError) as error:
            rffslam.solve(small, flagfile=path)
        assert message in str(error.value), text
    with pytest.raises(ValueError, match="cannot open for reading"):
        rffslam.solve(small, flagfile=tmp_path / "none.flags")
    with pytest.raises(ValueError, match=": a directory; allowed a file path"):
        rffslam.solve(small, flagfile=tmp_path)
    looped = flagfile(tmp_path, "", "loop.flags")
    looped.write_text(f"--flagfile={looped}\n")
    with pytest.raises(ValueError, match="includes itself"):
        rffslam.solve(small, flagfile=looped)
    # An empty entry of a list is an error, as on the command line (gflags
    # would skip it or exit), naming the line.
    good = flagfile(tmp_path, "--prior=wnoa\n", "good.flags")
    listed = flagfile(tmp_path, f"--flagfile={good},,{good}\n", "list.flags")
    with pytest.raises(ValueError, match=f"{listed}:1: --flagfile=.*: an "
                                         "empty file name"):
        rffslam.solve(small, flagfile=listed)
    listed.write_text(f"--flagfile={good},{good}\n")
    assert rffslam.solve(small, flagfile=listed).summary["prior"] == "wnoa"


# --- Results and queries --------------------------------------------------

def test_result_arrays(solved):
    n = len(solved.times)
    assert solved.times.dtype == np.float64 and solved.times.shape == (n,)
    assert solved.poses.shape == (n, 3)
    assert solved.landmark_ids.dtype == np.int64
    assert solved.landmarks.shape == (len(solved.landmark_ids), 2)
    assert solved.pose_covariances.shape == (n, 3, 3)
    assert solved.landmark_covariances.shape == (len(solved.landmark_ids), 2,
                                                 2)
    assert solved.has_covariance
    assert solved.summary["num_poses"] == n
    assert "60 poses" in repr(solved)


def test_residual_drift_comes_with_the_covariance(small, solved, plain):
    # Both values of every range-bearing row, in whole batches of 16 of a
    # landmark's sightings (10 here: too few to call a drift).
    sightings = {}
    for line in small.read_text().splitlines():
        fields = line.split()
        if fields and fields[0] == "RANGE_BEARING":
            sightings[fields[2]] = sightings.get(fields[2], 0) + 1
    batches = sum(count // 16 for count in sightings.values())
    drift = solved.summary["residual_drift"]
    assert sorted(d["kind"] for d in drift) == ["bearing", "range"]
    for d in drift:
        assert d["batches"] == batches
        assert 0.0 < d["ratio"] <= 16.0
        assert d["drifts"] is False
    assert plain.summary["residual_drift"] == []


def test_pose_at_the_solves_times_is_its_poses(solved):
    np.testing.assert_array_equal(solved.pose_at(solved.times), solved.poses)
    for i in (0, 17, len(solved.times) - 1):
        np.testing.assert_array_equal(solved.pose_at(solved.times[i]),
                                      solved.poses[i])
    np.testing.assert_array_equal(solved.pose_at(list(solved.times[:3])),
                                  solved.poses[:3])
    assert solved.pose_at(np.array([])).shape == (0, 3)


def test_pose_at_interpolates_between_the_times(solved):
    t = solved.times
    middle = 0.5 * (t[10] + t[11])
    pose = solved.pose_at(middle)
    assert pose.shape == (3,)
    np.testing.assert_allclose(pose[:2],
                               0.5 * (solved.poses[10, :2] +
                                      solved.poses[11, :2]), rtol=1e-12)
    turn = math.remainder(solved.poses[11, 2] - solved.poses[10, 2],
                          2 * math.pi)
    expected = math.remainder(solved.poses[10, 2] + 0.5 * turn, 2 * math.pi)
    assert abs(math.remainder(pose[2] - expected, 2 * math.pi)) < 1e-12
    many = solved.pose_at(np.linspace(t[0], t[-1], 101))
    assert many.shape == (101, 3)


def test_pose_covariance_at(solved):
    covariances = solved.pose_covariance_at(solved.times)
    np.testing.assert_array_equal(covariances, solved.pose_covariances)
    one = solved.pose_covariance_at(0.5 * (solved.times[3] + solved.times[4]))
    assert one.shape == (3, 3)
    np.testing.assert_allclose(one, 0.5 * (covariances[3] + covariances[4]),
                               rtol=1e-12)
    np.testing.assert_allclose(one, one.T, rtol=0, atol=1e-12 * one.max())
    assert np.all(np.linalg.eigvalsh(one) > 0)


def test_covariance_needs_compute_covariance(plain, tmp_path):
    assert not plain.has_covariance
    assert plain.pose_covariances is None
    assert plain.landmark_covariances is None
    for query in (lambda: plain.pose_covariance_at(plain.times[0]),
                  lambda: plain.save_covariance(tmp_path / "x.cov")):
        with pytest.raises(ValueError, match="compute_covariance=True"):
            query()


@pytest.mark.parametrize("t,message", [
    (-100.0, "lie outside the trajectory's time span"),
    ([0.0, 1e9], "1 of 2 query times"),
    (float("nan"), "finite"),
    ([[0.0, 1.0]], "1-D array"),
    ("soon", "real numbers, got str128"),
])
def test_bad_query_times_raise(solved, t, message):
    for query in (solved.pose_at, solved.pose_covariance_at):
        with pytest.raises(ValueError, match=message):
            query(t)


def test_saving(solved, small, tmp_path):
    solved.save_tum(tmp_path / "a.tum")
    lines = (tmp_path / "a.tum").read_text().splitlines()
    assert len(lines) == len(solved.times)
    solved.save_landmarks(str(tmp_path / "a.landmarks"))
    rows = (tmp_path / "a.landmarks").read_text().splitlines()
    assert len(rows[0].split()) == 6  # id x y sxx sxy syy
    solved.save_covariance(tmp_path / "a.cov")
    assert len((tmp_path / "a.cov").read_text().splitlines()) == len(lines)
    with pytest.raises(ValueError, match="does not exist"):
        solved.save_tum(tmp_path / "no" / "such" / "dir.tum")
    before = small.read_bytes()
    with pytest.raises(ValueError,
                       match="the same file as the input .*, never overwritten"):
        solved.save_tum(small)
    assert small.read_bytes() == before


# --- evaluate -------------------------------------------------------------

def test_evaluate(small, solved):
    metrics = rffslam.evaluate(small, solved)
    assert metrics["ape_trans_m"]["count"] == len(solved.times)
    assert metrics["aligned"] is False
    assert "mean_position_nees" in metrics  # Covariances were computed.
    aligned = rffslam.evaluate(rffslam.read_dataset(small), solved,
                               align=True)
    assert aligned["aligned"] is True
    assert aligned["ape_trans_m"]["rms"] <= metrics["ape_trans_m"]["rms"]
    for key in ("dataset", "trajectory", "landmarks", "covariance"):
        assert key not in metrics


def test_evaluate_errors(solved, tmp_path):
    no_truth = tmp_path / "no_truth.rffd"
    no_truth.write_text("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\n")
    with pytest.raises(ValueError, match="no GT_POSE record"):
        rffslam.evaluate(no_truth, solved)
    far = tmp_path / "far.rffd"
    far.write_text("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nGT_POSE 500 0 0 0\n")
    with pytest.raises(ValueError, match="outside the trajectory"):
        rffslam.evaluate(far, solved)
    with pytest.raises(TypeError):
        rffslam.evaluate(far, "not a result")


def test_align_is_true_or_false(small, solved):
    for bad in (None, 1, "yes"):
        with pytest.raises(ValueError, match="'align' must be True or False"):
            rffslam.evaluate(small, solved, align=bad)


def test_a_nul_in_an_option_or_an_empty_flagfile_is_refused(small):
    # gflags would read each up to the NUL, or skip the empty name.
    with pytest.raises(ValueError, match="option 'prior' holds a NUL"):
        rffslam.solve(small, prior="wnoa\0zzz")
    with pytest.raises(ValueError, match="an option name holds a NUL"):
        rffslam.solve(small, **{"prior\0zzz": "wnoa"})
    for empty in ("", ","):
        with pytest.raises(ValueError, match="an empty file name"):
            rffslam.solve(small, flagfile=empty)


def test_an_array_is_no_option_value(small):
    with pytest.raises(ValueError, match="'num_features' must be a single "
                                         r"value, got an array of shape \(1, 1\)"):
        rffslam.solve(small, num_features=np.array([[6]]))
    with pytest.raises(ValueError, match="'verbose' must be a single value"):
        rffslam.solve(small, verbose=np.array([True]))


@pytest.mark.parametrize("t, name", [
    ("0.5", "str96"), (True, "bool"), (np.array([0.5 + 7j]), "complex128"),
    (np.datetime64(1, "s"), "datetime64[s]"), (None, "object"),
])
def test_query_times_must_be_real_numbers(solved, t, name):
    with pytest.raises(ValueError, match=f"times must be real numbers, got "
                                         f"{re.escape(name)} values"):
        solved.pose_at(t)


def test_a_failed_solve_is_a_runtime_error(tmp_path):
    empty = tmp_path / "empty.rffd"
    empty.write_text("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\n")
    with pytest.raises(RuntimeError, match=f"{empty}: .*nothing to estimate"):
        rffslam.solve(empty)


def test_the_range_reading_is_in_the_summary(small, plain):
    # The simulator's ranges are distances: judged so from the range-bearing
    # rows (those beyond 5 robust sigmas left out), and a reading given is
    # not judged.
    rows = sum(1 for line in small.read_text().splitlines()
               if line.split()[:1] == ["RANGE_BEARING"])
    assert plain.summary["range_bearing_ranges"] == "distance"
    evidence = plain.summary["depth_evidence"]
    assert 0 < evidence["rows"] <= rows
    assert abs(evidence["t"]) < 10.0
    given = rffslam.solve(small, range_bearing_ranges="depth")
    assert given.summary["range_bearing_ranges"] == "depth"
    assert given.summary["depth_evidence"] is None
    with pytest.raises(ValueError, match="--range_bearing_ranges=depths: "
                                         "unknown reading of the ranges"):
        rffslam.solve(small, range_bearing_ranges="depths")
