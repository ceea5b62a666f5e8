"""Shared fixtures of the Python suite (run by ctest python_tests with PYTHONPATH on the build
tree's package, or by hand: PYTHONPATH=build/release/python /usr/bin/python3 -m pytest -q
python/tests)."""

import os
import pathlib

import pytest

SOURCE_DIR = pathlib.Path(
    os.environ.get("PLIANT_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2])
)
SHARED_DATA_DIR = pathlib.Path(
    os.environ.get("PLIANT_SHARED_DATA_DIR", SOURCE_DIR.parent / "shared" / "data")
)


@pytest.fixture(scope="session")
def funnel_frames():
    """The cloth-funnel frames 227 and 228 (../shared/data), or a skip."""
    frames = SHARED_DATA_DIR / "cloth-funnel" / "frames"
    t0, t1 = frames / "227.ply", frames / "228.ply"
    if not (t0.exists() and t1.exists()):
        pytest.skip(f"external data not found: {t0} and {t1}")
    return t0, t1
