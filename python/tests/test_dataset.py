"""rffslam.read_dataset: the arrays of a .rffd file, and the CLI's message
for a bad one."""

import os
import pathlib

import numpy as np
import pytest

import rffslam
from conftest import PLAZA, app, run


def records(path, kind):
    with open(path) as f:
        return [line.split()[1:] for line in f if line.startswith(kind + " ")]


def test_plaza_arrays_hold_the_file():
    dataset = rffslam.read_dataset(str(PLAZA))
    truth = np.array(records(PLAZA, "GT_POSE"), dtype=float)
    truth = truth[np.argsort(truth[:, 0], kind="stable")]
    assert dataset.path == str(PLAZA)
    assert dataset.ground_truth_times.dtype == np.float64
    np.testing.assert_array_equal(dataset.ground_truth_times, truth[:, 0])
    np.testing.assert_array_equal(dataset.ground_truth_poses, truth[:, 1:4])
    landmarks = np.array(records(PLAZA, "GT_LANDMARK"), dtype=float)
    assert dataset.ground_truth_landmark_ids.dtype == np.int64
    np.testing.assert_array_equal(dataset.ground_truth_landmark_ids,
                                  landmarks[:, 0].astype(np.int64))
    np.testing.assert_array_equal(dataset.ground_truth_landmarks,
                                  landmarks[:, 1:3])
    observations = sum(len(records(PLAZA, kind))
                       for kind in ("RANGE", "BEARING", "RANGE_BEARING"))
    assert dataset.num_observations == observations
    assert dataset.observation_times.shape == (observations,)
    assert np.all(np.diff(dataset.observation_times) >= 0)
    assert dataset.num_odometry == len(records(PLAZA, "ODOM"))
    assert dataset.landmark_priors.shape == (len(dataset.landmark_prior_ids),
                                             2)
    assert isinstance(dataset.metadata, dict)
    assert "plaza1.rffd" in repr(dataset)


def test_paths_may_be_pathlike_or_bytes():
    for path in (PLAZA, bytes(PLAZA)):
        assert rffslam.read_dataset(path).num_odometry > 0


def test_a_malformed_file_gives_the_clis_message(tmp_path):
    lines = PLAZA.read_text().splitlines()
    bad = next(i for i, line in enumerate(lines) if line.startswith("RANGE "))
    lines[bad] = "RANGE 3900.5 1 not_a_number 0.1"
    path = tmp_path / "bad.rffd"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(ValueError) as error:
        rffslam.read_dataset(str(path))
    message = str(error.value)
    assert message.startswith(f"{path}:{bad + 1}: ")
    cli = run(app("rff_slam"), f"--dataset={path}")
    assert cli.returncode == 1
    assert cli.stderr.strip() == "rff_slam: error: " + message
    # solve() reads it the same way.
    with pytest.raises(ValueError, match=f"{path}:{bad + 1}: "):
        rffslam.solve(str(path))


@pytest.mark.parametrize("content", [
    "", "GARBAGE 1 2 3\n", "\x00\x01\x02\n", "RFFD 1\nRANGE 1e400 1 2 3\n",
    "RFFD 1\nPRIOR_POSE 0 0 0 0 1e308 nan\n", "RFFD 1\nODOM 1 0 0 0 0 1 1 1\n",
    "RFFD 1\n" + "\xff" * 100000, "RFFD 1\nRANGE_BEARING " + "9" * 5000,
])
def test_hostile_files_raise_value_error(tmp_path, content):
    path = tmp_path / "hostile.rffd"
    path.write_bytes(content.encode("latin-1"))
    with pytest.raises(ValueError):
        rffslam.read_dataset(path)


def test_missing_file_and_directory_raise_value_error(tmp_path):
    with pytest.raises(ValueError, match="none.rffd"):
        rffslam.read_dataset(tmp_path / "none.rffd")
    with pytest.raises(ValueError):
        rffslam.read_dataset(tmp_path)


def test_a_path_of_the_wrong_type_is_a_type_error():
    with pytest.raises(TypeError):
        rffslam.read_dataset(42)
    with pytest.raises(TypeError):
        rffslam.solve(None)


def test_the_module_is_the_one_built_here():
    # Not an installed copy: ctest points PYTHONPATH at the build tree.
    binary_dir = os.environ.get("RFF_BINARY_DIR")
    if binary_dir:
        module = pathlib.Path(rffslam.__file__).resolve()
        assert module.parent == pathlib.Path(binary_dir).resolve() / "python"
    assert rffslam.__version__


def test_a_nul_or_empty_path_is_refused_not_cut_short():
    # open() refuses both; the C library would read the file before the NUL.
    for bad in (str(PLAZA) + "\0garbage", bytes(PLAZA) + b"\0x", ""):
        with pytest.raises(ValueError, match="embedded null byte|empty path"):
            rffslam.read_dataset(bad)
    with pytest.raises(ValueError, match="embedded null byte"):
        rffslam.solve(str(PLAZA) + "\0garbage")


def test_names_and_comments_that_are_no_utf8_are_read(tmp_path):
    path = os.fsencode(tmp_path) + b"/\xff.rffd"
    with open(path, "wb") as f:
        f.write(b"# key: \xfe\xff\nRFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\n")
    dataset = rffslam.read_dataset(path)
    assert os.fsencode(dataset.path) == path
    assert os.fsencode(dataset.metadata["key"]) == b"\xfe\xff"
