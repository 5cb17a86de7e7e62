"""The fuzzers' corpora (tests/fuzz/corpus: seeds and every reproducer
found) through the bindings: each input is read or refused with a Python
exception of the kinds docs/python.md lists; the interpreter never
crashes (a crash ends this test's process, which CTest reports)."""

import os
from pathlib import Path

import pytest

import purkinje
from conftest import SOURCE_DIR

CORPUS = SOURCE_DIR / "tests/fuzz/corpus"
REFUSALS = (ValueError, FileNotFoundError, OSError)

SQUARE_OBJ = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"
MESH_SCENE = """{ "format": 1,
  "cameras": [ { "resolution_px": [64, 48], "focal_length_mm": 16, "pixel_pitch_mm": 0.006,
                 "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600] } ],
  "eyes": [ { "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": {} } ],
  "meshes": [ { "file": "fuzzed.obj", "albedo": 0.5 } ] }"""


def corpus(name):
    files = sorted((CORPUS / name).iterdir())
    assert files, f"no corpus for {name}"
    return files


@pytest.fixture
def folder(tmp_path):
    """What the C++ targets give their inputs to name: square.obj and a FIFO."""
    (tmp_path / "square.obj").write_text(SQUARE_OBJ)
    os.mkfifo(tmp_path / "fifo.obj")
    return tmp_path


@pytest.mark.parametrize("file", corpus("scene"), ids=lambda f: f.name)
def test_scene_inputs(file, folder):
    try:
        scene = purkinje.parse_scene(file.read_bytes(), name="fuzzed.json", folder=folder)
    except REFUSALS:
        return
    assert scene.eyes and scene.cameras
    purkinje.parse_scene(scene.to_json())  # a scene read is one a dump reads back


@pytest.mark.parametrize("file", corpus("obj"), ids=lambda f: f.name)
def test_obj_inputs(file, folder):
    (folder / "fuzzed.obj").write_bytes(file.read_bytes())
    try:
        scene = purkinje.parse_scene(MESH_SCENE, name="fuzzed.json", folder=folder)
    except REFUSALS:
        return
    assert len(scene.meshes[0].triangles) > 0


@pytest.mark.parametrize("file", corpus("dataset_spec"), ids=lambda f: f.name)
def test_dataset_spec_inputs(file, folder):
    (folder / "scene.json").write_text((SOURCE_DIR / "assets/scenes/remote.json").read_text())
    try:
        spec = purkinje.parse_dataset_spec(file.read_bytes(), name="fuzzed.json", folder=folder)
    except REFUSALS:
        return
    if spec.count:
        try:
            spec.scene_for_image(0)
        except purkinje.DatasetSpecError:  # a draw no eye can have: named, as generate names it
            pass


@pytest.mark.parametrize("file", corpus("labels"), ids=lambda f: f.name)
def test_labels_inputs(file, tmp_path):
    labels = tmp_path / "fuzzed.json"
    labels.write_bytes(file.read_bytes())
    scorer = purkinje.Scorer()
    try:
        scorer.add("fuzzed.png", labels, purkinje.Detections())
    except REFUSALS:
        return
    scorer.score()


@pytest.mark.parametrize("file", corpus("detections"), ids=lambda f: f.name)
def test_detections_inputs(file, tmp_path):
    detections = tmp_path / "fuzzed.csv"
    detections.write_bytes(file.read_bytes())
    try:
        found = purkinje.read_detections(detections)
    except REFUSALS:
        return
    assert all(isinstance(d, purkinje.Detections) for d in found.values())
