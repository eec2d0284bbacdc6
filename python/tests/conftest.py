"""What the tests share: the repository's reference data (testdata/, or
DICSTREAM_SHARED_DATA) and the CLI binary they compare with (target/release/dicstream, or
DICSTREAM_BIN). As in the Rust tests, missing data skips a test with a message, or fails it
under DICSTREAM_REQUIRE_SHARED=1 (CI)."""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def shared_data(relative):
    root = Path(os.environ.get("DICSTREAM_SHARED_DATA", REPO / "testdata"))
    path = root / relative
    if path.exists():
        return path
    message = f"shared data {path} not found"
    if os.environ.get("DICSTREAM_REQUIRE_SHARED") == "1":
        pytest.fail(f"{message}, and DICSTREAM_REQUIRE_SHARED=1 requires it")
    pytest.skip(f"skipped: {message} (set DICSTREAM_SHARED_DATA)")


@pytest.fixture(scope="session")
def cli():
    """The dicstream binary: a function running it with arguments, returning the completed
    process (stdout and stderr as text)."""
    path = binary()

    def run(*args, check=True):
        done = subprocess.run([str(path), *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"dicstream {' '.join(map(str, args))} failed: {done.stderr}")
        return done

    return run


@pytest.fixture(scope="session")
def sample5():
    """DIC Challenge sample 5: its reference and the image shifted by (0.1, 0.1) px."""
    folder = shared_data("dic-challenge/sample5")
    return folder / "Sample5 Reference.tif", folder / "Sample5-001 X0.10 Y0.10 N2 C100 R20.tif"


def binary():
    """The dicstream binary (target/release/dicstream, or DICSTREAM_BIN)."""
    path = Path(os.environ.get("DICSTREAM_BIN", REPO / "target" / "release" / "dicstream"))
    if not path.exists():
        pytest.fail(f"{path} not found: build it (cargo build --release) or set DICSTREAM_BIN")
    return path
