"""examples/python/solve_and_plot.py runs and writes its PNG."""

import subprocess
import sys

import pytest

from conftest import SOURCE_DIR


def test_solve_and_plot_writes_a_png(tmp_path):
    pytest.importorskip("matplotlib")
    output = tmp_path / "plaza1.png"
    done = subprocess.run(
        [sys.executable, str(SOURCE_DIR / "examples" / "python" /
                             "solve_and_plot.py"), f"--output={output}"],
        capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    assert "RFF: APE" in done.stdout and "LTV-SDE (WNOA): APE" in done.stdout
    assert output.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
