"""Fixtures of the rffslam tests: the source tree, the apps built beside the
module, the bundled Plaza 1 file and a small simulated dataset."""

import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BINARY_DIR = pathlib.Path(os.environ.get("RFF_BINARY_DIR",
                                         SOURCE_DIR / "build"))
PLAZA = SOURCE_DIR / "data" / "plaza1.rffd"
PLAZA_FLAGS = SOURCE_DIR / "configs" / "plaza.flags"
PLAZA_WNOA_FLAGS = SOURCE_DIR / "configs" / "plaza_wnoa.flags"


def app(name):
    """Path of a built app; skips the test when it has not been built."""
    path = BINARY_DIR / name
    if not path.exists():
        pytest.skip(f"{path} is not built")
    return path


def run(*args):
    """Runs an app, returning its completed process (never raising)."""
    return subprocess.run([str(a) for a in args], capture_output=True,
                          text=True, check=False)


@pytest.fixture(scope="session")
def small(tmp_path_factory):
    """Path of a 60-pose range-bearing run with odometry and ground truth."""
    path = tmp_path_factory.mktemp("small") / "small.rffd"
    done = run(app("rff_simulate"), "--num_steps=60", "--landmarks=8",
               "--seed=3", f"--output={path}")
    assert done.returncode == 0, done.stderr
    return path
