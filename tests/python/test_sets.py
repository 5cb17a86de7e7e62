"""Data sets from Python: generate and merge write the command line's
bytes; the table in pandas and the PyTorch dataset hold the labels."""

import filecmp
import json

import numpy as np
import pytest

import purkinje
import purkinje.data
from conftest import SOURCE_DIR, cli, cli_error

SPEC = SOURCE_DIR / "assets/datasets/remote.json"


def same_folders(a, b):
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    match, mismatch, errors = filecmp.cmpfiles(a, b, names, shallow=False)
    assert (mismatch, errors) == ([], [])


def test_generate_and_merge_write_the_command_lines_bytes(tmp_path):
    cli("generate", SPEC, "-o", tmp_path / "cli", "--count", "4", "--quiet")
    calls = []
    outcome = purkinje.generate(SPEC, tmp_path / "whole", count=4, progress=lambda done, total: calls.append((done, total)))
    assert outcome["rendered"] == 4 and outcome["resumed"] == 0
    assert calls == [(1, 4), (2, 4), (3, 4), (4, 4)]
    same_folders(tmp_path / "cli", tmp_path / "whole")
    for i in range(2):
        purkinje.generate(SPEC, tmp_path / "sharded", count=4, shard=(i, 2), threads=1)
    with pytest.raises(FileNotFoundError, match="no table.csv .shard tables: table.shard-0-of-2.csv, table.shard-1-of-2.csv"):
        purkinje.data.load_table(tmp_path / "sharded")
    assert purkinje.merge(tmp_path / "sharded")["shards"] == 2
    for name in ("table.csv", "manifest.json"):
        assert (tmp_path / "sharded" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    resumed = purkinje.generate(SPEC, tmp_path / "whole", count=4, resume=True)
    assert (resumed["rendered"], resumed["resumed"]) == (0, 4)


def test_generate_refuses_as_the_command_line_does(tmp_path):
    with pytest.raises(FileNotFoundError) as error:
        purkinje.generate(tmp_path / "nope.json", tmp_path / "out")
    assert str(error.value) == cli_error("generate", tmp_path / "nope.json", "-o", tmp_path / "out")
    (tmp_path / "file").write_text("x")
    with pytest.raises(purkinje.OutputError) as error:
        purkinje.generate(SPEC, tmp_path / "file", count=1)
    assert str(error.value) == cli_error("generate", SPEC, "-o", tmp_path / "file", "--count", "1")
    with pytest.raises(ValueError, match="shard"):
        purkinje.generate(SPEC, tmp_path / "out", count=1, shard=(2, 2))
    bad = tmp_path / "bad.json"
    bad.write_text(SPEC.read_text().replace('"count": ', '"count": -'))
    (tmp_path / "scenes").mkdir()
    with pytest.raises(purkinje.DatasetSpecError) as error:
        purkinje.generate(bad, tmp_path / "out")
    assert str(error.value) == cli_error("generate", bad, "-o", tmp_path / "out")


def test_reading_errors_are_python_exceptions_with_the_command_lines_messages(tmp_path):
    with pytest.raises(FileNotFoundError) as error:
        purkinje.merge(tmp_path / "nowhere")
    assert str(error.value) == cli_error("merge", tmp_path / "nowhere")
    with pytest.raises(ValueError) as error:
        purkinje.merge(tmp_path)
    assert str(error.value) == cli_error("merge", tmp_path)
    with pytest.raises(FileNotFoundError):
        purkinje.track_set(tmp_path / "nowhere")
    with pytest.raises(ValueError) as error:
        purkinje.track_set(tmp_path)
    assert str(error.value) == cli_error("track", tmp_path, "-o", tmp_path / "out")


def test_ctrl_c_stops_a_run_between_images(tmp_path):
    import signal

    def interrupt(done, total):
        if done == 1:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        purkinje.generate(SPEC, tmp_path, count=3, threads=1, progress=interrupt)
    assert len(list(tmp_path.glob("*.json"))) == 1  # the first image whole, nothing after it
    assert not (tmp_path / "table.csv").exists()
    assert purkinje.generate(SPEC, tmp_path, count=3, resume=True)["resumed"] == 1


@pytest.fixture(scope="module")
def small_set(tmp_path_factory):
    folder = tmp_path_factory.mktemp("set")
    purkinje.generate(SPEC, folder, count=6, threads=1)
    return folder


def test_the_table_is_the_labels_in_pandas(small_set):
    table = purkinje.data.load_table(small_set)
    assert len(table) == 6 and list(table["index"]) == list(range(6))
    spec = purkinje.load_dataset_spec(SPEC)
    for _, row in table.iterrows():
        labels = purkinje.data.image_labels(small_set, row)
        assert labels.dataset["index"] == row["index"]
        assert row["pupil_radius_mm"] == spec.draw(int(row["index"]))["pupil_radius_mm"]
        view = labels.views[0]
        for glint in view.glints:
            assert row[f"glint.{glint.illuminator_name}.status"] == glint.status
        if view.pupil.ellipse is not None:
            assert row["pupil.ellipse.u_px"] == view.pupil.ellipse.center_u_px
    assert purkinje.data.load_manifest(small_set)["count"] == 6


def test_the_torch_dataset_serves_images_and_labels_through_workers(small_set):
    import torch
    import purkinje.torch
    from PIL import Image

    dataset = purkinje.torch.EyeDataset(small_set, segmentation=True)
    table = purkinje.data.load_table(small_set)
    image, target = dataset[2]
    png = np.asarray(Image.open(small_set / table["image"][2]))
    np.testing.assert_array_equal(image[0].numpy(), png.astype(np.float32) / np.float32(255))
    assert target["index"] == 2
    assert dataset.parameter(target, "pupil_radius_mm") == table["pupil_radius_mm"][2]
    assert target["parameters"].tolist() == table.loc[2, dataset.parameters].astype(float).tolist()
    for k, light in enumerate(dataset.lights):
        ok = table[f"glint.{light}.status"][2] == "ok"
        assert bool(target["glints_ok"][k]) == ok
        if ok:
            assert target["glints_px"][k, 0] == np.float32(table[f"glint.{light}.u_px"][2])
    raw, _ = purkinje.torch.EyeDataset(small_set, as_float=False)[2]
    assert raw.dtype == torch.uint8
    np.testing.assert_array_equal(raw[0].numpy(), png)
    classes = np.asarray(Image.open(small_set / table["segmentation"][2]))
    np.testing.assert_array_equal(target["segmentation"].numpy(), classes)

    loader = torch.utils.data.DataLoader(dataset, batch_size=4, num_workers=2)
    seen = []
    for images, targets in loader:
        assert images.shape[1:] == (1, 480, 640) and images.dtype == torch.float32
        assert not torch.isnan(targets["glints_px"]).any() and not torch.isnan(targets["pupil_ellipse"]).any()
        seen += targets["index"].tolist()
        assert dataset.parameter(targets, "pupil_radius_mm").tolist() == \
            table["pupil_radius_mm"][targets["index"].numpy()].tolist()
    assert seen == list(range(6))
    with pytest.raises(ValueError, match="camera 'cam7' is not in the set"):
        purkinje.torch.EyeDataset(small_set, camera="cam7")


def test_the_torch_dataset_scales_deeper_sensors_by_their_png(tmp_path):
    import purkinje.torch
    from PIL import Image

    spec = tmp_path / "deep.json"
    spec.write_text(json.dumps({"dataset_format": 1, "name": "deep", "count": 2,
                                "scene": str(SOURCE_DIR / "assets/scenes/headset.json"),
                                "parameters": {"bits": {"choice": [10, 12]}}}))
    purkinje.generate(spec, tmp_path, count=2, threads=1)
    dataset = purkinje.torch.EyeDataset(tmp_path)
    image, target = dataset[1]
    png = np.asarray(Image.open(tmp_path / purkinje.data.load_table(tmp_path)["image"][1]))
    assert png.max() > 255  # 16-bit: the sensor's bits in the words' high bits (PIL reads them as int32)
    np.testing.assert_array_equal(image[0].numpy(), png.astype(np.float32) / np.float32(65535))
    assert 0 < float(image.max()) <= 1


def test_track_set_is_purkinje_track(small_set, tmp_path):
    scene_file = SOURCE_DIR / "assets/scenes/remote.json"
    cli("track", small_set, "-o", tmp_path, "--scene", scene_file, "--overlays", "0", "--quiet")
    score, detections = purkinje.track_set(small_set, purkinje.load_scene(scene_file))
    assert score.summary == json.loads((tmp_path / "score.json").read_text())
    assert score.csv == (tmp_path / "score.csv").read_text()
    assert len(detections) == 6
