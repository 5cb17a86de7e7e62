"""Shared fixtures of the Python package's tests (run by CTest through
pytest; tests/CMakeLists.txt sets the environment)."""

import fcntl
import os
import subprocess
from pathlib import Path

import pytest


def _take_a_core():
    """One core for this test process, as tests/one_core.cpp takes one for
    the C++ tests under the coverage run (scripts/test.sh): before the
    package starts its threads, which then number one (TBB's default is the
    process's cores; no test asks the package for more)."""
    folder = os.environ.get("PURKINJE_TEST_CORE_LOCKS")
    if not folder:
        return None
    for cpu in sorted(os.sched_getaffinity(0)):
        try:
            fd = os.open(os.path.join(folder, f"core-{cpu}.lock"), os.O_RDWR | os.O_CREAT, 0o644)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        for task in os.listdir("/proc/self/task"):  # every thread, not only this one
            try:
                os.sched_setaffinity(int(task), {cpu})
            except OSError:  # a thread that has ended since
                pass
        return fd  # held until the process ends
    return None


_CORE = _take_a_core()

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
