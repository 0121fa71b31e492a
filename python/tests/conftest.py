"""Shared fixtures of the Python tests (run: PYTHONPATH=<build>/python /usr/bin/python3 -m pytest python/tests)."""

import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

import medspring as ms

REPO = Path(__file__).resolve().parents[2]


def data_file(name: str) -> Path:
    """A real-anatomy file from $MEDSPRING_DATA or ../shared/data beside the repository; fails loudly
    when it is missing (never skips)."""
    folder = Path(os.environ.get("MEDSPRING_DATA") or REPO.parent / "shared" / "data")
    path = folder / name
    assert path.is_file(), f"data file {name} not found in {folder} (set MEDSPRING_DATA)"
    return path


def parse_reference(text: str) -> dict:
    """Blocks '<name> <rows> <cols>' followed by rows of hexadecimal floats (exact)."""
    out, lines, i = {}, text.splitlines(), 0
    while i < len(lines):
        name, rows, cols = lines[i].split()
        rows, cols = int(rows), int(cols)
        values = [[float.fromhex(v) for v in lines[i + 1 + r].split()] for r in range(rows)]
        out[name] = np.array(values, dtype=np.float64).reshape(rows, cols)
        i += 1 + rows
    return out


@pytest.fixture(scope="session")
def reference():
    """The C++ reference runs (python/tests/reference_run.cpp), built next to the module in a CMake build
    tree as <build>/python/medspring_python_reference (or $MEDSPRING_REFERENCE_EXE)."""
    exe = os.environ.get("MEDSPRING_REFERENCE_EXE")
    exe = Path(exe) if exe else Path(ms._medspring.__file__).resolve().parents[1] / "medspring_python_reference"
    assert exe.is_file(), (
        f"C++ reference executable {exe} not found: build the target medspring_python_reference "
        "(it is built with the Python module) or set MEDSPRING_REFERENCE_EXE"
    )
    run = subprocess.run([str(exe)], check=True, capture_output=True, text=True, timeout=120)
    return parse_reference(run.stdout)


def bits(a) -> np.ndarray:
    """The IEEE-754 bit patterns of a float64 array (for bit-for-bit comparisons)."""
    return np.ascontiguousarray(a, dtype=np.float64).view(np.uint64)


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a test of several seconds (real Dask clusters); -m 'not slow' skips it")
