"""The numpy peer of bench/compare solves the model rff_slam solves with
compare.SAME_MODEL_FLAGS, so the speed ratio there compares like with like.
Measured: on the 60-pose fixture (D = 10, 30) the final costs agree to 3e-9
(relative); on the paper's 300-pose seed 3 (D = 100, five range-bearing
records closer than two range sigmas, which take the near-landmark form) to
2e-11. The APE agrees to 5e-6 m in both."""

import json
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR, app, run

sys.path.insert(0, str(SOURCE_DIR / "bench" / "compare"))
import compare  # noqa: E402


@pytest.fixture(scope="module")
def paper_seed_3(tmp_path_factory):
    path = tmp_path_factory.mktemp("paper") / "paper_rb_s3.rffd"
    done = run(app("rff_simulate"), "--preset=paper", "--seed=3",
               f"--output={path}")
    assert done.returncode == 0, done.stderr
    near = [line for line in path.read_text().splitlines()
            if line.startswith("RANGE_BEARING")
            and float(line.split()[3]) < 2.0 * float(line.split()[5])]
    assert len(near) == 5  # The near-landmark form is exercised.
    return path


def peer(path, *args):
    return subprocess.run([sys.executable, compare.PEER, str(path), *args],
                          capture_output=True, text=True, check=False)


def assert_same_map(dataset, tmp_path, num_features):
    features = f"--num_features={num_features}"
    done = peer(dataset, features)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout)
    summary = tmp_path / "summary.json"
    done = run(app("rff_slam"), f"--dataset={dataset}",
               f"--summary_json={summary}", features,
               *compare.SAME_MODEL_FLAGS)
    assert done.returncode == 0, done.stderr
    ape = [float(line.split()[3]) for line in done.stdout.splitlines()
           if line.startswith("APE translation")]
    cli = json.loads(summary.read_text())
    assert result["num_parameters"] == cli["num_parameters"]
    assert result["final_cost"] == pytest.approx(cli["final_cost"], rel=1e-8)
    assert result["ape_trans_m"] == pytest.approx(ape[0], abs=1e-5)


@pytest.mark.parametrize("num_features", [10, 30])
def test_peer_reaches_the_same_map(small, tmp_path, num_features):
    assert_same_map(small, tmp_path, num_features)


def test_peer_reaches_the_same_map_with_near_landmarks(paper_seed_3,
                                                       tmp_path):
    assert_same_map(paper_seed_3, tmp_path, 100)


GOOD = ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nPRIOR_LANDMARK 0 1 1 1\n"
        "RANGE_BEARING 0 0 1.4 0.7 0.1 0.1\nODOM 0 1 1 0 0 0.1 0.1 0.1\n")


@pytest.mark.parametrize("content, message", [
    ("PRIOR_POSE 0 0 0 0 0.1 0.1\n",
     ":1: the first record must be the header RFFD 1"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nRANGE 0 0 1.4 0.1\n",
     ":3: RANGE records are outside this peer's model"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 nan\n",
     ":2: a field is not a finite number: PRIOR_POSE 0 0 0 0 0.1 nan"),
    ("RFFD 1\nPRIOR_LANDMARK 0 1 1 0\n",
     ":2: a sigma is not positive: PRIOR_LANDMARK 0 1 1 0"),
    ("RFFD 1\nPRIOR_LANDMARK 1.5 1 1 1\n",
     ":2: a landmark id must be a non-negative integer: "
     "PRIOR_LANDMARK 1.5 1 1 1"),
    (GOOD + "PRIOR_LANDMARK 0 1 1 1\n", ": a duplicate landmark prior"),
    (GOOD.replace("0.1 0.1\nPRIOR_LANDMARK", "0.1 0.6\nPRIOR_LANDMARK"),
     ": a start heading sigma above 0.5 rad, which rff_slam re-estimates "
     "first and this peer does not"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1\n",
     ":2: not a record this peer reads: PRIOR_POSE 0 0 0 0 0.1"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 x 0.1 0.1\n",
     ":2: a field is not a number: PRIOR_POSE 0 0 0 x 0.1 0.1"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nPRIOR_LANDMARK 0 1 1 1\n"
     "RANGE_BEARING 0 0 1.4 0.7 0.1 0.1\n",
     ": needs ODOM records (the peer's mean is the dead reckoning, and every "
     "landmark needs a prior)"),
    ("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nPRIOR_LANDMARK 0 1 1 1\n"
     "RANGE_BEARING 0 1 1.4 0.7 0.1 0.1\nODOM 0 1 1 0 0 0.1 0.1 0.1\n",
     ": landmark 1 is observed but has no PRIOR_LANDMARK"),
])
def test_peer_refuses_what_is_outside_its_model(tmp_path, content, message):
    path = tmp_path / "bad.rffd"
    path.write_text(content)
    done = peer(path)
    assert done.returncode == 1
    assert done.stderr.strip() == f"numpy_dense_lm.py: {path}{message}"


def test_peer_refuses_odometry_that_is_not_one_chain(tmp_path):
    path = tmp_path / "gap.rffd"
    path.write_text("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\nPRIOR_LANDMARK 0 1 1 1\n"
                    "RANGE_BEARING 0 0 1.4 0.7 0.1 0.1\n"
                    "ODOM 0 1 1 0 0 0.1 0.1 0.1\nODOM 2 3 1 0 0 0.1 0.1 0.1\n")
    done = peer(path)
    assert done.returncode == 1
    assert done.stderr.strip() == (
        f"numpy_dense_lm.py: {path}: the ODOM records must form one chain "
        "starting at the earliest PRIOR_POSE")


def test_missing_file_is_named(tmp_path):
    done = peer(tmp_path / "none.rffd")
    assert done.returncode == 1
    assert done.stderr.startswith(
        f"numpy_dense_lm.py: {tmp_path / 'none.rffd'}: cannot read:")


def test_peer_refuses_a_mean_turned_past_first_order(tmp_path):
    # A start heading 20 degrees off with sigma 0.3 rad: rff_slam turns its
    # mean exactly (twice) and solves again; the peer's turn stays linear.
    simulated, turned = tmp_path / "s4.rffd", tmp_path / "turned.rffd"
    done = run(app("rff_simulate"), "--preset=paper", "--seed=4",
               f"--output={simulated}")
    assert done.returncode == 0, done.stderr
    done = run(app("rff_perturb"), f"--input={simulated}",
               f"--output={turned}", "--start_heading_offset_deg=20",
               "--start_heading_sigma=0.3")
    assert done.returncode == 0, done.stderr
    done = peer(turned, "--num_features=20")
    assert done.returncode == 1
    assert done.stderr.startswith(
        f"numpy_dense_lm.py: {turned}: the mean turned by -0.2167")
    assert done.stderr.strip().endswith(
        "beyond its first-order form, where rff_slam turns it exactly and "
        "solves again")
