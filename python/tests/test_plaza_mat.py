"""scripts/plaza_mat_to_text.py: the raw Plaza text files from a MATLAB 5
MAT-file as GTSAM ships them (compressed double matrices)."""

import struct
import subprocess
import sys
import zlib

import numpy as np

from conftest import SOURCE_DIR

SCRIPT = SOURCE_DIR / "scripts" / "plaza_mat_to_text.py"


def element(kind, payload, pad=True):
    """One MAT-file data element: type, size, data, padded to 8 bytes."""
    data = struct.pack("<II", kind, len(payload)) + payload
    return data + b"\0" * (-len(data) % 8 if pad else 0)


def matrix(name, values):
    """A compressed miMATRIX of doubles, column-major as MATLAB stores it."""
    values = np.asarray(values, dtype="<f8")
    body = (element(6, struct.pack("<II", 6, 0)) +  # array flags: double
            element(5, struct.pack("<ii", *values.shape)) +
            element(1, name.encode()) +
            element(9, values.T.tobytes()))
    return element(15, zlib.compress(element(14, body)), pad=False)


def write_mat(path, variables):
    header = b"MATLAB 5.0 MAT-file, test".ljust(116) + b"\0" * 8
    header += struct.pack("<H", 0x0100) + b"IM"
    path.write_bytes(header + b"".join(matrix(k, v)
                                       for k, v in variables.items()))


def test_writes_each_matrix_as_text(tmp_path):
    rng = np.random.default_rng(1)
    variables = {"DR": rng.normal(size=(5, 3)), "GT": rng.normal(size=(6, 4)),
                 "TD": rng.normal(size=(3, 4)), "TL": rng.normal(size=(4, 3))}
    write_mat(tmp_path / "Plaza9_.mat", variables)
    done = subprocess.run([sys.executable, str(SCRIPT),
                           str(tmp_path / "Plaza9_.mat"), str(tmp_path / "out")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    for key, values in variables.items():
        text = np.loadtxt(tmp_path / "out" / f"Plaza9_{key}.txt", ndmin=2)
        np.testing.assert_allclose(text, values, rtol=1e-9)


def test_refuses_a_file_that_is_no_mat_file(tmp_path):
    (tmp_path / "x.mat").write_text("1 2 3\n")
    done = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path / "x.mat"),
                           str(tmp_path / "out")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert "not a MATLAB 5 MAT-file" in done.stderr
    assert not (tmp_path / "out").exists()


def test_names_the_matrices_it_lacks(tmp_path):
    write_mat(tmp_path / "Plaza9_.mat", {"DR": np.ones((2, 3))})
    done = subprocess.run([sys.executable, str(SCRIPT),
                           str(tmp_path / "Plaza9_.mat"), str(tmp_path / "out")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert "no GT, TD, TL matrix" in done.stderr


def test_names_a_truncated_file(tmp_path):
    write_mat(tmp_path / "Plaza9_.mat", {"DR": np.ones((200, 3))})
    data = (tmp_path / "Plaza9_.mat").read_bytes()
    (tmp_path / "Plaza9_.mat").write_bytes(data[:len(data) - 40])
    done = subprocess.run([sys.executable, str(SCRIPT),
                           str(tmp_path / "Plaza9_.mat"), str(tmp_path / "out")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert "truncated or corrupt MAT-file" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out").exists()


def test_names_a_missing_input_and_an_output_that_is_a_file(tmp_path):
    done = subprocess.run([sys.executable, str(SCRIPT),
                           str(tmp_path / "none.mat"), str(tmp_path / "out")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert "none.mat: cannot read" in done.stderr
    write_mat(tmp_path / "Plaza9_.mat", {k: np.ones((2, 3))
                                         for k in ("DR", "GT", "TD", "TL")})
    (tmp_path / "taken").write_text("x")
    done = subprocess.run([sys.executable, str(SCRIPT),
                           str(tmp_path / "Plaza9_.mat"), str(tmp_path / "taken")],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 1
    assert "cannot create the output directory" in done.stderr
    assert (tmp_path / "taken").read_text() == "x"
