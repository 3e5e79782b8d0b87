"""The numpy peer of bench/compare solves the model rff_slam solves with
compare.SAME_MODEL_FLAGS: the speed ratio there compares like with like.
Measured on the 60-pose fixture, D = 10 and 30: final costs equal to 3e-8
(relative), APE to 1e-5 m."""

import json
import subprocess
import sys

import pytest

from conftest import SOURCE_DIR, app, run

sys.path.insert(0, str(SOURCE_DIR / "bench" / "compare"))
import compare  # noqa: E402


@pytest.mark.parametrize("num_features", [10, 30])
def test_peer_reaches_the_same_map(small, tmp_path, num_features):
    features = f"--num_features={num_features}"
    peer = subprocess.run([sys.executable, compare.PEER, str(small), features],
                          capture_output=True, text=True, check=False)
    assert peer.returncode == 0, peer.stderr
    peer = json.loads(peer.stdout)
    summary = tmp_path / "summary.json"
    done = run(app("rff_slam"), f"--dataset={small}",
               f"--summary_json={summary}", features,
               *compare.SAME_MODEL_FLAGS)
    assert done.returncode == 0, done.stderr
    ape = [float(line.split()[3]) for line in done.stdout.splitlines()
           if line.startswith("APE translation")]
    cli = json.loads(summary.read_text())
    assert peer["final_cost"] == pytest.approx(cli["final_cost"], rel=1e-6)
    assert peer["ape_trans_m"] == pytest.approx(ape[0], abs=1e-4)


def test_peer_refuses_records_outside_its_model(tmp_path):
    path = tmp_path / "range_only.rffd"
    path.write_text("RFFD 1\nPRIOR_POSE 0 0 0 0 0.1 0.1\n"
                    "PRIOR_LANDMARK 0 1 1 1\nRANGE 0 0 1.4 0.1\n")
    done = subprocess.run([sys.executable, compare.PEER, str(path)],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert done.stderr.strip() == (
        f"{path}: RANGE records are outside this peer's model")
