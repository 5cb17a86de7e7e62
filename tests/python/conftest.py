"""Shared fixtures of the Python package's tests (run by CTest through
pytest; tests/CMakeLists.txt sets the environment)."""

import os
import subprocess
from pathlib import Path

import pytest

SOURCE_DIR = Path(os.environ["PURKINJE_SOURCE_DIR"])
EXECUTABLE = os.environ["PURKINJE_EXECUTABLE"]


def cli(*args: str, check: bool = True) -> subprocess.CompletedProcess:
    """Runs the purkinje command line; text output."""
    return subprocess.run([EXECUTABLE, *map(str, args)], capture_output=True, text=True, check=check)


def cli_error(*args: str) -> str:
    """The message of a command that fails: stderr less "purkinje CMD: error: "."""
    run = cli(*args, check=False)
    assert run.returncode != 0, f"{args} succeeded"
    line = run.stderr.strip().splitlines()[-1]
    return line.split(": error: ", 1)[1]


@pytest.fixture
def source_dir() -> Path:
    return SOURCE_DIR


@pytest.fixture
def remote_file() -> Path:
    return SOURCE_DIR / "assets/scenes/remote.json"
