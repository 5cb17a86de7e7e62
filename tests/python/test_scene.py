"""Scenes and dataset specs from Python: the C++ readers' rules and
messages, dumps any JSON tool reads, and scenes built from keywords."""

import json

import numpy as np
import pytest

import purkinje
from conftest import SOURCE_DIR, cli_error

SCENES = ["remote", "headset", "remote_glasses", "remote_face"] + sorted(
    "hard/" + p.stem for p in (SOURCE_DIR / "assets/scenes/hard").glob("*.json"))


def test_a_loaded_scene_shows_what_its_file_says(remote_file):
    scene = purkinje.load_scene(remote_file)
    text = json.loads("\n".join(line.split("//")[0] for line in remote_file.read_text().splitlines()))
    assert scene.name == "remote"
    camera = scene.cameras[0]
    given = text["cameras"][0]
    w, h = given["resolution_px"]
    assert camera.resolution_px == (w, h)
    f_px = given["focal_length_mm"] / given["pixel_pitch_mm"]
    np.testing.assert_allclose(camera.camera_matrix, [[f_px, 0, (w - 1) / 2], [0, f_px, (h - 1) / 2], [0, 0, 1]])
    assert [l.name for l in scene.illuminators] == [l["name"] for l in text["illuminators"]]
    np.testing.assert_array_equal(scene.illuminators[0].position_mm, text["illuminators"][0]["position_mm"])
    eye = scene.eyes[0]
    # The cornea centre lies rotation_center_depth - radius in front of the rotation centre, on the optical axis.
    depth = eye.model.rotation_center_depth_mm - eye.model.cornea_radius_mm
    np.testing.assert_allclose(eye.cornea_center_mm, eye.rotation_center_mm + depth * eye.optical_axis, atol=1e-12)
    assert np.linalg.norm(eye.optical_axis) == pytest.approx(1, abs=1e-15)
    pose = eye.world_from_eye
    np.testing.assert_allclose(pose[:3, 2], eye.optical_axis, atol=1e-15)
    np.testing.assert_array_equal(pose[:3, 3], eye.cornea_center_mm)


def test_camera_project_agrees_with_the_pinhole_formula(remote_file):
    camera = purkinje.load_scene(remote_file).cameras[0]
    assert not camera.distortion.any()
    points = np.array([[10.0, -5.0, 600.0], [0.0, 0.0, -1.0], [400.0, 0.0, 600.0]])
    pixels, status = camera.project(points)
    k = camera.camera_matrix
    assert status == ["ok", "behind_camera", "outside_image"]
    np.testing.assert_allclose(pixels[0], [k[0, 0] * 10 / 600 + k[0, 2], k[1, 1] * -5 / 600 + k[1, 2]], rtol=1e-14)
    pixel, one_status = camera.project(points[0])
    np.testing.assert_array_equal(pixel, pixels[0])
    assert one_status == "ok"
    with pytest.raises(ValueError, match=r"points must have shape \(3,\) or \(n, 3\)"):
        camera.project(np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"points must have shape"):
        camera.project(np.zeros((2, 2, 3)))
    with pytest.raises(ValueError, match=r"points_mm\[1\] = \[0, nan, 600\]: must be finite"):
        camera.project([[0, 0, 600], [0, np.nan, 600]])


@pytest.mark.parametrize("name", SCENES)
def test_a_dump_is_plain_json_that_reads_back_to_the_same_scene(name):
    scene = purkinje.load_scene(SOURCE_DIR / f"assets/scenes/{name}.json")
    text = scene.to_json()
    as_dict = json.loads(text)  # Python's json reads it: no comments
    assert as_dict == scene.to_dict()
    again = purkinje.parse_scene(as_dict, name="dump.json")
    assert again.to_json() == text
    assert purkinje.truth(again).raw == purkinje.truth(scene).raw


def test_a_changed_dict_gives_a_changed_scene_checked_as_a_file(remote_file):
    scene = purkinje.load_scene(remote_file)
    d = scene.to_dict()
    d["eyes"][0]["pupil"]["radius_mm"] = 3.0
    assert purkinje.parse_scene(d).eyes[0].model.pupil_radius_mm == 3.0
    d["eyes"][0]["pupil"]["radius_mm"] = -3.0
    with pytest.raises(purkinje.SceneError) as error:
        purkinje.parse_scene(d, name="mine.json")
    assert str(error.value) == "mine.json: eyes[0].pupil.radius_mm = -3: must be > 0"
    assert isinstance(error.value, ValueError)
    d["eyes"][0]["pupil"]["radius_mm"] = float("nan")
    with pytest.raises(purkinje.SceneError, match=r"^mine.json: eyes\[0\].pupil.radius_mm = nan: must be a finite number$"):
        purkinje.parse_scene(d, name="mine.json")
    # A name with a dot in it is a key, not a path.
    d["eyes"][0]["pupil"]["radius_mm"] = 2.0
    d["illuminators"][0]["note.v2"] = float("inf")
    with pytest.raises(purkinje.SceneError, match=r"^mine.json: illuminators\[0\].note.v2 = inf: must be a finite number$"):
        purkinje.parse_scene(d, name="mine.json")
    del d["illuminators"][0]["note.v2"]
    # numpy values are taken as numbers.
    d["eyes"][0]["pupil"]["radius_mm"] = np.float32(2.5)
    d["illuminators"][0]["position_mm"] = np.array([-120.0, 0.0, 0.0])
    changed = purkinje.parse_scene(d)
    np.testing.assert_array_equal(changed.illuminators[0].position_mm, [-120, 0, 0])


def build_remote_like(**eye_changes):
    return purkinje.build_scene(
        name="built",
        cameras=[purkinje.camera(name="cam0", resolution_px=(640, 480), focal_length_mm=16, pixel_pitch_mm=0.006,
                                 position_mm=(0, 0, 0), look_at_mm=(0, 0, 600))],
        illuminators=[purkinje.illuminator(name="led_left", position_mm=(-100, 0, 0)),
                      purkinje.illuminator(name="led_right", position_mm=np.array([100, 0, 0]))],
        eyes=[purkinje.eye(model="navarro", position={"rotation_center_mm": (30, 0, 610)},
                           orientation={"gaze_target_mm": (0, -150, 0)}, **eye_changes)],
        screen=purkinje.screen(center_mm=(0, -182, 0), size_mm=(518, 324)),
    )


def test_keywords_build_the_scene_the_same_text_would():
    built = build_remote_like(pupil={"radius_mm": 2.5})
    text = """{ "format": 1, "name": "built",
      "cameras": [ { "name": "cam0", "resolution_px": [640, 480], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                     "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
      "illuminators": [ { "name": "led_left", "position_mm": [-100, 0, 0] },
                        { "name": "led_right", "position_mm": [100, 0, 0] } ],
      "eyes": [ { "model": "navarro", "pupil": { "radius_mm": 2.5 },
                  "position": { "rotation_center_mm": [30, 0, 610] },
                  "orientation": { "gaze_target_mm": [0, -150, 0] } } ],
      "screen": { "center_mm": [0, -182, 0], "size_mm": [518, 324] } }"""
    assert built.to_json() == purkinje.parse_scene(text).to_json()


def test_a_face_is_a_keyword_as_in_the_file():
    built = build_remote_like(eyelids={}, face={"side": "left", "canthal_tilt_deg": 6})
    face = json.loads(built.to_json())["eyes"][0]["face"]
    assert face["side"] == "left" and face["canthal_tilt_deg"] == 6 and face["crease_height_mm"] == 7
    with pytest.raises(purkinje.SceneError, match=r"eyes\[0\].face = \{\}: only used with eyelids"):
        build_remote_like(face={})
    lashed = build_remote_like(eyelids={}, face={"lashes": {"albedo": 0.03, "upper_curl_deg": 60}})
    lashes = json.loads(lashed.to_json())["eyes"][0]["face"]["lashes"]
    assert lashes["albedo"] == 0.03 and lashes["upper_curl_deg"] == 60 and lashes["upper_length_mm"] == 9.5


def test_keywords_are_checked_with_the_file_formats_messages():
    with pytest.raises(purkinje.SceneError) as error:
        build_remote_like(cornea={"radius_mm": -7.8})
    assert str(error.value) == "build_scene: eyes[0].cornea.radius_mm = -7.8: must be > 0"
    with pytest.raises(purkinje.SceneError, match=r"eyes\[0\].pupil.radius = 2: unknown key \(valid keys here: "
                                                  r"decentration_mm, radius_mm\)"):
        build_remote_like(pupil={"radius": 2})
    with pytest.raises(TypeError):  # a misspelt keyword is Python's own error
        purkinje.camera(resolution_px=(64, 48), position_mm=(0, 0, 0), focal_lenght_mm=16)


# Every malformed scene of the C++ tests: Python's exception carries the
# very message the command line prints.
MALFORMED = sorted((SOURCE_DIR / "tests/data/malformed").glob("*.json"))


@pytest.mark.parametrize("file", MALFORMED, ids=[f.stem for f in MALFORMED])
def test_a_malformed_scene_raises_the_command_lines_message(file):
    with pytest.raises(ValueError) as error:
        purkinje.load_scene(file)
    assert str(error.value) == cli_error("truth", file)


def test_a_missing_scene_is_file_not_found_with_the_command_lines_message(tmp_path):
    missing = tmp_path / "nope.json"
    with pytest.raises(FileNotFoundError) as error:
        purkinje.load_scene(missing)
    assert str(error.value) == cli_error("truth", missing)
    with pytest.raises(FileNotFoundError):
        purkinje.load_dataset_spec(tmp_path / "nope_spec.json")


def test_a_dataset_spec_draws_and_builds_its_images_scenes():
    spec = purkinje.load_dataset_spec(SOURCE_DIR / "assets/datasets/remote.json")
    assert spec.count > 0 and "pupil_radius_mm" in spec.parameters
    draw = spec.draw(3)
    assert list(draw) == spec.parameters
    assert spec.draw(3) == draw  # a pure function of the index
    scene = spec.scene_for_image(3)
    assert scene.eyes[0].model.pupil_radius_mm == draw["pupil_radius_mm"]
    with pytest.raises(IndexError, match="beyond the set's"):
        spec.draw(spec.count)
    with pytest.raises(purkinje.DatasetSpecError) as error:
        purkinje.parse_dataset_spec({"dataset_format": 1, "scene": "../scenes/remote.json", "count": 0},
                                    name="spec.json", folder=SOURCE_DIR / "assets/datasets")
    assert str(error.value).startswith("spec.json: count = 0: ")


def test_presets_are_listed_with_their_anatomy():
    assert purkinje.eye_model_presets() == ["keratometric", "le_grand", "navarro"]
    navarro = purkinje.eye_model("navarro")  # docs/eye-models.md: Navarro 1985
    assert (navarro.cornea_radius_mm, navarro.cornea_asphericity) == (7.72, -0.26)
    assert navarro.posterior_cornea["radius_mm"] == 6.5
    assert purkinje.eye_model("keratometric").posterior_cornea is None
    with pytest.raises(ValueError, match='"nav": unknown eye model'):
        purkinje.eye_model("nav")
