"""The compare study from Python (docs/compare.md): purkinje.compare gives
what `purkinje compare` writes, and writes the same files and figures."""

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import purkinje

from conftest import cli


@pytest.fixture(scope="module")
def remote():
    return purkinje.load_scene(Path(__file__).parents[2] / "assets/scenes/remote.json")


def test_identical_versions_change_nothing(remote):
    study = purkinje.compare(remote, grid=3, gaze_grid=3, seed=4)
    assert (study.displacements["displacement_px"] == 0).all()
    assert (study.gaze["change_deg"] == 0).all()
    assert (study.gaze["error_believing_world_deg"] == study.gaze["error_believing_assumed_deg"]).all()
    assert np.array_equal(study.world.image, study.assumed.image)
    assert np.array_equal(study.world.electrons, study.assumed.electrons)
    assert study.calibration_skipped == ""


def test_a_spherical_tracker_on_the_navarro_eye_writes_what_the_command_writes(remote, tmp_path):
    steps = []
    study = purkinje.compare(remote, assumed_cornea=(7.8, 0), grid=3, gaze_grid=3, seed=2,
                             progress=lambda done, total: steps.append((done, total)))
    assert steps and steps[-1][0] == steps[-1][1]
    model = study.gaze[study.gaze["method"] == "model-based"]
    assert model["change_deg"].max() > 0.05
    # The polynomial believes nothing about the rig: the same estimates.
    assert (study.gaze[study.gaze["method"] == "polynomial"]["change_deg"] == 0).all()
    written = study.write(tmp_path / "py")
    assert all(f.exists() for f in written)
    cli("compare", Path(__file__).parents[2] / "assets/scenes/remote.json", "-o", tmp_path / "cli",
        "--assumed-cornea", "7.8,0", "--grid", "3", "--gaze-grid", "3", "--seed", "2", "--quiet", "--no-figures")
    for name in ("summary.txt", "summary.json", "displacements.csv", "gaze.csv", "world.png", "assumed.exr"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # The figures: their sizes, and each gaze panel's arrows scaled by its
    # own longest, recomputed here from the table.
    assert Image.open(tmp_path / "py" / "gaze_change.png").size == (1200, 1260)
    assert Image.open(tmp_path / "py" / "displacements.png").size == (1800, 840)
    figures = json.loads((tmp_path / "py" / "figures.json").read_text())
    for panel in figures["gaze_change.png"]["panels"]:
        method, position = panel["title"].split(", ", 1)
        rows = study.gaze[(study.gaze["method"] == method) & (study.gaze["position"] == position)]
        longest = np.hypot(rows["believing_assumed_x_mm"] - rows["believing_world_x_mm"],
                           rows["believing_assumed_y_mm"] - rows["believing_world_y_mm"]).max()
        assert panel["longest_arrow"] == pytest.approx(longest, rel=1e-12, abs=0)
        if longest > 0:
            assert panel["arrow_scale_per_axis_unit"] == pytest.approx(longest / (0.9 * min(518, 324) / 3), rel=1e-9)  # the grid spacing: the screen is 518 x 324 mm


def test_versions_that_cannot_be_compared_are_refused(remote):
    headset = purkinje.load_scene(Path(__file__).parents[2] / "assets/scenes/headset.json")
    with pytest.raises(ValueError, match="compare: the versions must have the same cameras and lights"):
        purkinje.compare(remote, headset, images=False)
    with pytest.raises(ValueError, match="samples"):
        purkinje.compare(remote, samples=0)
