"""docs/python.md's code, run block by block in order, as a reader would,
from a folder where assets/ is the repository's."""

import contextlib
import io
import os
import re

import pytest

from conftest import SOURCE_DIR

TUTORIAL = SOURCE_DIR / "docs/python.md"


def python_blocks():
    return re.findall(r"```python\n(.*?)```", TUTORIAL.read_text(), re.S)


def test_the_tutorial_has_code():
    assert len(python_blocks()) >= 8


def test_every_block_of_the_tutorial_runs(tmp_path):
    (tmp_path / "assets").symlink_to(SOURCE_DIR / "assets")
    namespace = {"__name__": "tutorial"}
    printed = []
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        for i, block in enumerate(python_blocks()):
            if os.environ.get("PURKINJE_TEST_CORE_LOCKS"):
                # The coverage run (scripts/test.sh): its plain counters lose
                # updates when two threads render at once, and gcov then finds
                # negative counts. The sanitizer phase runs the block as written.
                block = block.replace("ThreadPoolExecutor(max_workers=2)", "ThreadPoolExecutor(max_workers=1)")
            output = io.StringIO()
            with contextlib.redirect_stdout(output):
                try:
                    exec(compile(block, f"docs/python.md block {i + 1}", "exec"), namespace)
                except Exception as error:
                    pytest.fail(f"block {i + 1} raised {error!r}:\n{block}")
            assert output.getvalue(), f"block {i + 1} printed nothing"
            printed.append(output.getvalue())
    finally:
        os.chdir(cwd)
    # What the comments promise.
    text = "".join(printed)
    assert "spherical: eyes[0].cornea.asphericity = -3: must be >= -1" in text
    assert "assets/scenes/no_such_scene.json: cannot read: no such file" in text
    assert namespace["image"].dtype.name == "uint8"
    assert (tmp_path / "out/python/remote_cam0.png").is_file()
    assert len(namespace["table"]) == 8
    moved = namespace["after"] - namespace["before"]
    assert (abs(moved) > 0.01).any(), "the changed cornea moved no glint"
