"""Truth from Python is `purkinje truth`'s, number for number."""

import json

import numpy as np
import pytest

import purkinje
from conftest import SOURCE_DIR, cli, cli_error

SCENES = ["remote", "headset", "remote_glasses", "remote_face"] + sorted(
    "hard/" + p.stem for p in (SOURCE_DIR / "assets/scenes/hard").glob("*.json"))


@pytest.mark.parametrize("name", SCENES)
def test_truth_equals_the_command_lines(name):
    file = SOURCE_DIR / f"assets/scenes/{name}.json"
    scene = purkinje.load_scene(file)
    assert purkinje.truth(scene).raw == json.loads(cli("truth", file).stdout)
    assert purkinje.truth_csv(scene, pupil_border_points=12) == cli("truth", file, "--format", "csv",
                                                                    "--pupil-points", "12").stdout


def test_typed_labels_hold_the_files_values(remote_file):
    labels = purkinje.truth(purkinje.load_scene(remote_file))
    raw = labels.raw
    view = labels.view("cam0", 0)
    assert view is labels.views[0]
    for glint, given in zip(view.glints, raw["views"][0]["glints"]):
        assert glint.status == given["status"] == "ok"
        np.testing.assert_array_equal(glint.pixel_px, [given["u_px"], given["v_px"]])
        np.testing.assert_array_equal(glint.normal, given["normal"])
    np.testing.assert_array_equal(view.glints_px.data, [[g["u_px"], g["v_px"]] for g in raw["views"][0]["glints"]])
    e = raw["views"][0]["pupil"]["ellipse"]
    assert view.pupil.ellipse.center_u_px == e["center_u_px"]
    assert len(view.pupil.border) == 36
    assert labels.eyes[0].cornea_radius_mm == raw["eyes"][0]["cornea_radius_mm"]
    with pytest.raises(KeyError, match="no view of camera 'cam9'"):
        labels.view("cam9")


def test_values_a_path_lacks_are_none_and_masked_never_nan(remote_file):
    d = purkinje.load_scene(remote_file).to_dict()
    d["illuminators"][0]["position_mm"] = [0, 0, 1200]  # behind the eye: no reflection reaches the camera
    view = purkinje.truth(purkinje.parse_scene(d)).views[0]
    glint = view.glints[0]
    assert glint.status == "no_solution"
    assert glint.u_px is None and glint.pixel_px is None and glint.point_mm is None
    assert view.glints_px.mask.tolist() == [[True, True], [False, False]]
    np.testing.assert_array_equal(view.glints_px[1], view.glints[1].pixel_px)


def test_pupil_border_points_are_checked_as_the_command_line_does(remote_file):
    scene = purkinje.load_scene(remote_file)
    assert len(purkinje.truth(scene, pupil_border_points=0).views[0].pupil.border) == 0
    with pytest.raises(ValueError, match="pupil_border_points = 100001: must be between 0 and 100000"):
        purkinje.truth(scene, pupil_border_points=100001)
