"""Trackers from Python: purkinje's detectors on numpy images find what
`purkinje track` finds, and scoring gives `purkinje track`'s score."""

import csv
import json

import numpy as np
import pytest
from PIL import Image

import purkinje
from conftest import SOURCE_DIR, cli


def read_sensor_png(file, bits):
    pixels = np.asarray(Image.open(file))
    return pixels if bits == 8 else (pixels.astype(np.uint16) >> (16 - bits)).astype(np.uint16)


@pytest.mark.parametrize("name", ["remote", "headset"])
def test_tracker_and_scorer_agree_with_the_command_line(name, tmp_path):
    scene_file = SOURCE_DIR / f"assets/scenes/{name}.json"
    cli("render", scene_file, "-o", tmp_path / "set", "--variations", "4", "--seed", "5")
    cli("track", tmp_path / "set", "-o", tmp_path / "track", "--scene", scene_file, "--overlays", "0", "--quiet")

    scene = purkinje.load_scene(scene_file)
    tracker = purkinje.Tracker(scene, scene.cameras[0].name)
    scorer = purkinje.Scorer()
    found = {}
    for labels_file in sorted((tmp_path / "set").glob("*_v*.json")):
        labels = json.loads(labels_file.read_text())
        image_name = labels["render"]["files"]["image"]
        image = read_sensor_png(tmp_path / "set" / image_name, labels["render"]["sensor"]["bits"])
        found[image_name] = tracker.track(image, bits=labels["render"]["sensor"]["bits"])
        scorer.add(image_name, labels_file, found[image_name])
    assert len(found) == 4

    rows = list(csv.DictReader(open(tmp_path / "track/detections.csv")))
    for row in rows:
        detections = found[row["image"]]
        if row["feature"] == "glint":
            match = [g for g in detections.glints if g.u_px == float(row["u_px"]) and g.v_px == float(row["v_px"])]
            assert len(match) == 1, row
            assert match[0].illuminator == (int(row["illuminator"]) if row["illuminator"] else -1)
        else:
            (pupil,) = detections.pupils
            assert (pupil.u_px, pupil.v_px) == (float(row["u_px"]), float(row["v_px"]))
            assert pupil.confidence == float(row["confidence"])
    assert len(rows) == sum(len(d.glints) + len(d.pupils) for d in found.values())

    score = scorer.score()
    assert score.summary == json.loads((tmp_path / "track/score.json").read_text())
    assert score.csv == (tmp_path / "track/score.csv").read_text()


def test_detectors_on_a_render_find_its_labels(remote_file):
    result = purkinje.render(purkinje.load_scene(remote_file), seed=2)
    view = result.labels.views[0]
    glints = purkinje.detect_glints(result)
    assert len(glints) == 2
    for glint in glints:
        assert min(np.linalg.norm(glint.center_px - g.pixel_px) for g in view.glints) < 0.1
    pupil = purkinje.detect_pupil(result, glints)
    assert np.linalg.norm(pupil.center_px - view.pupil.ellipse.center_px) < 0.5
    assert 0 < pupil.confidence <= 1
    # A strided view (every other row and column) is read as it is.
    half = purkinje.detect_glints(result.image[::2, ::2])
    assert len(half) == 2


def test_user_detections_are_scored_alike(remote_file):
    result = purkinje.render(purkinje.load_scene(remote_file), seed=2)
    view = result.labels.views[0]
    mine = purkinje.Detections(
        glints=[purkinje.Glint(g.u_px + 0.5, g.v_px, illuminator=g.illuminator) for g in view.glints],
        pupils=[purkinje.Pupil(*view.pupil.ellipse.center_px + [3.0, 4.0])])
    scorer = purkinje.Scorer(match_radius_px=5)
    scorer.add("mine.png", result, mine)
    summary = scorer.score().summary
    assert summary["glints"]["within_px"]["1"] == 1.0 and summary["glints"]["error_px"]["max"] == pytest.approx(0.5)
    assert summary["pupils"]["within_px"]["5"] == 1.0 and summary["pupils"]["error_px"]["max"] == pytest.approx(5.0)
    assert summary["pupils"]["within_px"]["2"] == 0.0
    assert summary["glints"]["identity_rate"] == 1.0


def test_user_detections_are_checked_as_a_detections_file_is(remote_file):
    result = purkinje.render(purkinje.load_scene(remote_file), region=(0, 0, 8, 8))
    scorer = purkinje.Scorer()
    with pytest.raises(ValueError, match=r"^image a.png: glints\[1\].u_px = inf: must be a finite number$"):
        scorer.add("a.png", result, purkinje.Detections(glints=[purkinje.Glint(1, 2), purkinje.Glint(float("inf"), 3)]))
    with pytest.raises(TypeError, match=r"pupils\[0\].u_px = None: must be a number"):
        scorer.add("a.png", result, purkinje.Detections(pupils=[purkinje.Pupil(None, 3)]))
    bad_ellipse = purkinje.Ellipse(1, 2, -5, 3, 0)
    with pytest.raises(ValueError, match=r"pupils\[0\].ellipse.semi_axis_1_px = -5: must be > 0"):
        scorer.add("a.png", result, purkinje.Detections(pupils=[purkinje.Pupil(1, 2, bad_ellipse)]))
    with pytest.raises(ValueError, match=r"pupils\[0\].confidence = 1.5: must be in \[0, 1\], or None"):
        scorer.add("a.png", result, purkinje.Detections(pupils=[purkinje.Pupil(1, 2, None, 1.5)]))
    assert scorer.score().summary["images"] == 0  # nothing half added


def test_a_rig_tracker_reads_its_cameras_bits(source_dir):
    headset = purkinje.load_scene(source_dir / "assets/scenes/headset.json")
    d = headset.to_dict()
    d["cameras"][0]["sensor"]["bits"] = 12
    scene = purkinje.parse_scene(d)
    result = purkinje.render(scene, seed=3)
    assert result.image.dtype == np.uint16 and result.image.max() > 255
    tracker = purkinje.Tracker(scene)
    with pytest.raises(ValueError, match='Tracker: camera "cam9": the scene has no camera of that name'):
        purkinje.Tracker(scene, "cam9")
    from_array = tracker.track(result.image)
    assert len(from_array.glints) > 0
    assert [g.center_px.tolist() for g in from_array.glints] == [g.center_px.tolist() for g in tracker.track(result).glints]


def test_bad_images_and_settings_are_named():
    with pytest.raises(ValueError, match=r"must be a 2D uint8 or uint16 array \(height, width\), not float64"):
        purkinje.detect_glints(np.zeros((4, 4)))
    with pytest.raises(ValueError, match="bits = 12: must be from 1 to 8 for a uint8 image"):
        purkinje.detect_glints(np.zeros((4, 4), np.uint8), bits=12)
    with pytest.raises(TypeError, match="unknown setting 'thresold'; did you mean 'threshold'"):
        purkinje.detect_glints(np.zeros((4, 4), np.uint8), thresold=0.1)
    with pytest.raises(ValueError, match="threshold"):
        purkinje.detect_glints(np.zeros((8, 8), np.uint8), threshold=-1)
    with pytest.raises(TypeError, match="threshold = 'abc': must be a number"):
        purkinje.detect_glints(np.zeros((8, 8), np.uint8), threshold="abc")
    with pytest.raises(ValueError, match="rays"):
        purkinje.detect_pupil(np.zeros((8, 8), np.uint8), rays=3)
