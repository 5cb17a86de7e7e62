"""The calibration study from Python is `purkinje calibrate`'s."""

import json

import numpy as np
import pytest

import purkinje
from conftest import SOURCE_DIR, cli, cli_error


def test_calibrate_returns_what_the_command_line_writes(remote_file, tmp_path):
    cli("calibrate", remote_file, "-o", tmp_path, "--grid", "2", "--noise-frames", "0", "--head-move", "0,0,50",
        "--tracker-cornea", "7.8,0", "--quiet")
    calls = []
    study = purkinje.calibrate(purkinje.load_scene(remote_file), grid=2, noise_frames=0, head_moves=[(0, 0, 50)],
                               tracker_cornea=(7.8, 0), progress=lambda done, total: calls.append(total))
    assert study.runs == json.loads((tmp_path / "calibration.json").read_text())["runs"]
    assert study.frames_csv == (tmp_path / "frames.csv").read_text()
    assert study.text == (tmp_path / "calibration.txt").read_text()
    assert len(calls) == 9 + 2 * 4 and set(calls) == {17}
    assert [p.title for p in study.panels][0] == "home" and len(study.panels) == 2
    panel = study.panels[0]
    assert panel.targets_mm.shape == (4, 2) and set(panel.estimates_mm) == {"model-based", "polynomial"}
    frames = study.frames()
    assert len(frames) == 2 * 4  # a row per test frame, both methods' columns in it
    # The panel's estimates are the frames' (home, model-based).
    assert np.isfinite(panel.estimates_mm["model-based"].compressed()).all()


def test_a_rig_it_cannot_calibrate_is_refused_with_the_command_lines_message(tmp_path):
    scene = purkinje.load_scene(SOURCE_DIR / "assets/scenes/headset.json")
    d = scene.to_dict()
    d.pop("screen", None)
    no_screen = purkinje.parse_scene(d)
    (tmp_path / "noscreen.json").write_text(no_screen.to_json())
    with pytest.raises(ValueError) as error:
        purkinje.calibrate(no_screen)
    # The command line names the rig's file, Python the scene; the rule is one.
    python_name, python_rule = str(error.value).split(": ", 1)
    cli_name, cli_rule = cli_error("calibrate", tmp_path / "noscreen.json", "-o", tmp_path / "out").split(": ", 1)
    assert (python_name, cli_name, python_rule) == ("headset", str(tmp_path / "noscreen.json"), cli_rule)
    with pytest.raises(ValueError, match="calibration: grid = 70: must be from 1 to 64"):
        purkinje.calibrate(scene, grid=70)
    with pytest.raises(ValueError, match=r"tracker_cornea = \(7.8, -2\): must be"):
        purkinje.calibrate(scene, tracker_cornea=(7.8, -2))


def test_displacement_field_is_zero_for_one_model_and_names_what_moves(remote_file):
    scene = purkinje.load_scene(remote_file)
    same = purkinje.displacement_field(scene, scene, grid=3)
    assert len(same) == 9 * 4 and (same["du_px"].dropna() == 0).all() and same["du_px"].notna().sum() >= 9 * 3
    d = scene.to_dict()
    d["eyes"][0]["cornea"]["asphericity"] = 0.0  # the tracker's classic sphere against Navarro's Q = -0.26
    sphere = purkinje.parse_scene(d)
    field = purkinje.displacement_field(scene, sphere, grid=3)
    glints = field[field.feature.str.startswith("glint.")]
    assert glints["displacement_px"].max() > 0.01
    assert set(field.feature) == {"glint.led_left", "glint.led_right", "pupil_center", "pupil_ellipse"}
    with pytest.raises(ValueError, match="compare: grid = 0"):
        purkinje.displacement_field(scene, sphere, grid=0)


def test_a_tracker_rig_moves_the_estimates_not_the_frames(remote_file):
    scene = purkinje.load_scene(remote_file)
    d = scene.to_dict()
    d["illuminators"][0]["position_mm"][0] += 5
    believed = purkinje.parse_scene(d)
    right = purkinje.calibrate(scene, grid=2, noise_frames=0)
    wrong = purkinje.calibrate(scene, grid=2, noise_frames=0, tracker_rig=believed)
    assert wrong.frames()["glint_error_rms_px"].tolist() == right.frames()["glint_error_rms_px"].tolist()
    assert wrong.frames()["model_error_deg"].mean() > right.frames()["model_error_deg"].mean()
