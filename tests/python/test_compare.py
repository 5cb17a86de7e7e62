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


def test_a_sweep_from_python_writes_what_the_command_writes(remote, tmp_path):
    names = [name for name, _, _ in purkinje.sweep_parameters()]
    assert "cornea_asphericity" in names and "led_offset_x" in names
    sweep = purkinje.sweep(remote, "cornea_radius", 7.6, 8.0, 3, noise_frames=2, grid=3, gaze_grid=3)
    assert list(sweep.about["values"]) == [7.6, 7.8, 8.0]
    glints = sweep.table[(sweep.table["quantity"] == "displacement") & sweep.table["subject"].str.startswith("glint")]
    assert (glints.groupby("value")["max"].max() > 0).all()
    assert sweep.about["noise_floor"]["frames"] == 2
    sweep.write(tmp_path / "py")
    cli("compare", Path(__file__).parents[2] / "assets/scenes/remote.json", "-o", tmp_path / "cli", "--sweep",
        "cornea_radius=7.6:8.0:3", "--noise-frames", "2", "--grid", "3", "--gaze-grid", "3", "--quiet")
    for name in ("sweep.csv", "sweep.json"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert Image.open(tmp_path / "cli" / "sweep.png").size == (1800, 500)
    # Each panel's band is the noise floor the sweep measured.
    figures = json.loads((tmp_path / "cli" / "figures.json").read_text())
    bands = [panel["noise_band"] for panel in figures["sweep.png"]["panels"]]
    floor = sweep.about["noise_floor"]
    assert bands == [floor["glint_px"], floor["pupil_px"], floor["gaze_deg"]]
    with pytest.raises(ValueError, match='unknown parameter "cornea_radios"'):
        purkinje.sweep(remote, "cornea_radios", 7, 8)


def test_eye_models_by_preset_name_or_file(remote, tmp_path):
    study = purkinje.compare(remote, assumed_eye="keratometric", grid=2, gaze_grid=2, images=False)
    assert study.gaze[study.gaze["method"] == "model-based"]["change_deg"].max() > 0
    same = tmp_path / "navarro.json"
    same.write_text('{"model": "navarro", "pupil": {"radius_mm": 2.0}}')
    # The remote rig's own anatomy, from a file: nothing moves.
    assert (purkinje.compare(remote, assumed_eye=same, grid=2, gaze_grid=2, images=False)
            .displacements["displacement_px"] == 0).all()
    with pytest.raises(FileNotFoundError, match="navaro: cannot open the eye-model file"):
        purkinje.compare(remote, assumed_eye="navaro", images=False)
