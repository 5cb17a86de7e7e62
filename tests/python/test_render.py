"""Rendering from Python: the command line's files byte for byte, arrays
equal to them, the GIL released, errors as ValueError."""

import json
import threading
import time
import zlib

import numpy as np
import pytest
from PIL import Image

import purkinje
from conftest import SOURCE_DIR, cli


@pytest.mark.parametrize("name", ["remote", "headset"])
def test_files_written_from_python_are_the_command_lines_byte_for_byte(name, tmp_path):
    file = SOURCE_DIR / f"assets/scenes/{name}.json"
    cli("render", file, "-o", tmp_path / "cli", "--seed", "7", "--samples", "2")
    scene = purkinje.load_scene(file)
    result = purkinje.render(scene, 0, seed=7, samples_per_pixel=2)
    paths = result.write(tmp_path / "py")
    assert set(paths) == {"image", "exr", "labels"}
    for kind, path in paths.items():
        assert path.parent == tmp_path / "py"
        cli_file = tmp_path / "cli" / path.name
        assert (tmp_path / "py" / cli_file.name).read_bytes() == cli_file.read_bytes(), kind


def test_a_pixel_filter_gives_the_command_lines_files(tmp_path):
    file = SOURCE_DIR / "assets/scenes/remote.json"
    cli("render", file, "-o", tmp_path / "cli", "--samples", "3", "--pixel-filter", "blackman-harris",
        "--pixel-filter-width", "2.5")
    result = purkinje.render(purkinje.load_scene(file), samples_per_pixel=3, pixel_filter="blackman-harris",
                             pixel_filter_width=2.5)
    paths = result.write(tmp_path / "py")
    for path in paths.values():
        assert path.read_bytes() == (tmp_path / "cli" / path.name).read_bytes(), path.name
    assert json.loads(paths["labels"].read_text())["render"]["pixel_filter"] == {
        "kind": "blackman-harris", "width_px": 2.5}
    box = purkinje.render(purkinje.load_scene(file), samples_per_pixel=3)
    assert not np.array_equal(box.radiance, result.radiance)


@pytest.mark.parametrize("name", ["remote", "headset"])
def test_arrays_equal_the_command_lines_png_and_exr(name, tmp_path):
    file = SOURCE_DIR / f"assets/scenes/{name}.json"
    cli("render", file, "-o", tmp_path, "--seed", "3")
    scene = purkinje.load_scene(file)
    result = purkinje.render(scene, scene.cameras[0].name, seed=3)
    stem = tmp_path / f"{scene.name}_{scene.cameras[0].name}"
    png = np.asarray(Image.open(f"{stem}.png"))
    if result.bits == 8:
        assert result.image.dtype == np.uint8
        np.testing.assert_array_equal(result.image, png)
    else:  # the PNG keeps the sensor's bits in its words' high bits
        assert result.image.dtype == np.uint16
        np.testing.assert_array_equal(result.image, png.astype(np.uint16) >> (16 - result.bits))
    exr = purkinje.read_exr(f"{stem}.exr")
    np.testing.assert_array_equal(exr["Y"], result.radiance)
    np.testing.assert_array_equal(exr["electrons"], result.electrons)
    for aov in result.aov_names:
        np.testing.assert_array_equal(exr[aov], result.aov(aov))
    np.testing.assert_array_equal(result.segmentation, result.aov("id").astype(np.uint8))
    labels = json.loads(open(f"{stem}.json").read())
    assert result.labels.raw["views"] == labels["views"]
    assert zlib.crc32(open(f"{stem}.png", "rb").read()) == int(labels["render"]["files"]["image_crc32"], 16)


def test_a_render_releases_the_gil(remote_file):
    scene = purkinje.load_scene(remote_file)
    done = threading.Event()

    def work():
        purkinje.render(scene, samples_per_pixel=4, threads=1)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    ticks = 0
    while not done.is_set():  # runs only while the render does not hold the GIL
        ticks += 1
        time.sleep(0.0005)
    thread.join()
    assert ticks > 20


def test_arrays_keep_their_render_alive(remote_file):
    scene = purkinje.load_scene(remote_file)
    result = purkinje.render(scene, seed=1)
    radiance, image = result.radiance, result.image
    total, image_sum = float(radiance.sum()), int(image.sum())
    del result
    for seed in (2, 3, 4):  # renders that would reuse the memory were it let go
        purkinje.render(scene, seed=seed, samples_per_pixel=2)
    assert float(radiance.sum()) == total and int(image.sum()) == image_sum


def test_a_render_takes_no_option_from_an_earlier_one(remote_file):
    scene = purkinje.load_scene(remote_file)
    whole = purkinje.render(scene, seed=1).radiance.copy()
    patch = purkinje.render(scene, seed=1, region=(0, 0, 8, 8))
    assert not patch.radiance[8:, 8:].any()
    del patch  # its memory may serve the next render
    np.testing.assert_array_equal(purkinje.render(scene, seed=1).radiance, whole)


def test_bad_options_raise_value_errors_naming_them(remote_file):
    scene = purkinje.load_scene(remote_file)
    with pytest.raises(ValueError, match='camera "cam9": the scene has no camera of that name'):
        purkinje.render(scene, "cam9")
    with pytest.raises(ValueError, match="camera index 3"):
        purkinje.render(scene, 3)
    with pytest.raises(ValueError, match="samples_per_pixel = 0"):
        purkinje.render(scene, samples_per_pixel=0)
    with pytest.raises(ValueError, match='mode = "exact": must be "fast" or "reference"'):
        purkinje.render(scene, mode="exact")
    with pytest.raises(KeyError, match='no AOV "albedo"'):
        purkinje.render(scene, region=(0, 0, 8, 8)).aov("albedo")
    with pytest.raises(TypeError, match="camera must be a camera's index .int. or name .str., not float"):
        purkinje.render(scene, 1.5)
    with pytest.raises(ValueError, match="threads = 2000: must be from 0 .all. to 1024"):
        purkinje.render(scene, threads=2000)
    with pytest.raises(ValueError, match='pixel_filter = "mitchell": must be "box", "gaussian" or "blackman-harris"'):
        purkinje.render(scene, pixel_filter="mitchell")
    with pytest.raises(ValueError, match="pixel_filter width_px = 20: must be 0"):
        purkinje.render(scene, pixel_filter_width=20)


def test_files_are_refused_as_the_command_line_refuses_them(remote_file, tmp_path):
    result = purkinje.render(purkinje.load_scene(remote_file), region=(0, 0, 8, 8))
    (tmp_path / "file").write_text("x")
    with pytest.raises(purkinje.OutputError, match="exists and is not a folder: not replaced"):
        result.write(tmp_path / "file")
    for stem in ("../escaped", "", ".."):
        with pytest.raises(ValueError, match="must be a file name, without a folder"):
            result.write(tmp_path / "out", stem=stem)
    assert not (tmp_path / "out").exists() and not (tmp_path / "escaped.png").exists()
    with pytest.raises(FileNotFoundError, match="no_such.exr"):
        purkinje.read_exr(tmp_path / "no_such.exr")
    with pytest.raises(ValueError):
        purkinje.read_exr(tmp_path / "file")


def test_lashes_are_a_class_and_labels_say_what_hides_a_point():
    d = purkinje.load_scene(SOURCE_DIR / "assets/scenes/headset.json").to_dict()
    # Half open: the upper lid hides the pupil's top, its lashes some of
    # the points below the margin (4 of 36 at this seed).
    d["eyes"][0]["eyelids"]["opening"] = 0.5
    d["eyes"][0]["face"] = {"lashes": {}}
    result = purkinje.render(purkinje.parse_scene(d))
    assert (result.segmentation == 5).any()
    view = result.labels.views[0]
    border = view.pupil.border
    assert all(p.occluded_by is None for p in border if p.status != "occluded")
    assert {"skin", "lash"} <= {p.occluded_by for p in border if p.status == "occluded"}
    # The gallery's overlay draws every feature with a pixel, by what hid it.
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from purkinje.figures import draw_labels
    fig, ax = plt.subplots()
    drawn = draw_labels(ax, view)
    plt.close(fig)
    features = view.glints + border
    for key in ("ok", "skin", "lash"):
        assert drawn.get(key, 0) == sum(1 for f in features if (f.occluded_by or f.status) == key) > 0, key
    # Hidden points are drawn where they would be seen: their pixels are labelled.
    assert all(p.u_px is not None for p in border if p.status == "occluded")


def test_a_sensors_realism_reaches_the_image_and_its_labels(tmp_path):
    d = purkinje.load_scene(SOURCE_DIR / "assets/scenes/headset.json").to_dict()
    d["cameras"][0]["sensor"].update({"hot_pixel_fraction": 0.002, "hot_pixel_e_per_s": 1e7})
    raw = purkinje.render(purkinje.parse_scene(d), noise=False)
    d["cameras"][0]["sensor"].update({"corner_illumination": 0.5, "jpeg_quality": 30})
    scene = purkinje.parse_scene(d)
    sensor = scene.cameras[0].sensor
    assert (sensor.corner_illumination, sensor.hot_pixel_fraction, sensor.jpeg_quality) == (0.5, 0.002, 30)
    result = purkinje.render(scene, noise=False)
    hot = json.loads(result.write(tmp_path)["labels"].read_text())["render"]["hot_pixels"]
    assert len(hot) > 100
    # 1e7 e/s over 1 ms, 0.5 to 1.5 times: 5000 to 15000 electrons, saturated
    # above the full well (10000 e = 255 DN) and well above the dark rim.
    assert all(raw.image[p["y_px"], p["x_px"]] >= min(255, p["dark_e"] * 255 / 1e4) - 1 for p in hot)
    # Darker corners; a JPEG's blocks change pixels the hot ones leave alone.
    assert result.electrons[0, 0] == pytest.approx(raw.electrons[0, 0] * 0.5, rel=0.01)
    assert (result.image != raw.image).mean() > 0.3
    # A saccade: the eye says how it turns, the labels too.
    d["eyes"][0]["motion"] = {"yaw_deg_s": 600}
    moving = purkinje.parse_scene(d)
    assert moving.eyes[0].motion == (600, 0)
    labels = json.loads(purkinje.render(moving, noise=False).write(tmp_path / "m")["labels"].read_text())
    assert labels["eyes"][0]["motion"] == {"yaw_deg_s": 600, "pitch_deg_s": 0}


def test_a_wet_scleras_highlights_are_labelled_and_imaged():
    d = purkinje.load_scene(SOURCE_DIR / "assets/scenes/headset.json").to_dict()
    # Turned 25 deg aside and 10 up: the sclera mirrors several LEDs.
    d["eyes"][0]["orientation"] = {"yaw_deg": 25, "pitch_deg": 10}
    d["eyes"][0]["appearance"]["tear_film"] = {"sclera_roughness_deg": 1.5}
    result = purkinje.render(purkinje.parse_scene(d), noise=False)
    labels = result.labels.views[0].distractors
    seen = [x for x in labels if x.status == "ok"]
    assert len(seen) >= 2 and all(x.kind == "sclera" for x in labels)
    assert all(x.pixel_px is not None for x in seen)
    assert [x["illuminator"] for x in result.distractors] == [x.illuminator for x in labels]
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from purkinje.figures import draw_labels
    fig, ax = plt.subplots()
    assert draw_labels(ax, result.labels.views[0])["distractor"] == len(seen)
    plt.close(fig)
    # The mask's share of the light is what the highlights carry.
    share = float((result.aov("distractor") * result.electrons).sum())
    assert share == pytest.approx(sum(x["electrons"] for x in result.distractors), rel=1e-4)
    assert all(x["spread_cov_px2"][0] > 0 for x in result.distractors if x["status"] == "ok")
    # A dry sclera has neither.
    del d["eyes"][0]["appearance"]["tear_film"]
    dry = purkinje.render(purkinje.parse_scene(d), noise=False)
    assert dry.labels.views[0].distractors == [] and dry.distractors == []
    assert "distractor" not in dry.aov_names


def test_a_wet_faces_tear_meniscus_highlights_are_labelled_and_imaged():
    d = purkinje.load_scene(SOURCE_DIR / "assets/scenes/hard/headset_face.json").to_dict()
    d["eyes"][0]["appearance"]["tear_film"] = {}
    result = purkinje.render(purkinje.parse_scene(d), noise=False)
    labels = result.labels.views[0].distractors
    for kind in ("tear_meniscus", "upper_tear_meniscus"):
        seen = [x for x in labels if x.kind == kind and x.status == "ok"]
        assert len(seen) >= 2, kind
    share = float((result.aov("distractor") * result.electrons).sum())
    assert share == pytest.approx(sum(x["electrons"] for x in result.distractors), rel=1e-4)
    # Without menisci, the sclera's highlights alone.
    d["eyes"][0]["appearance"]["tear_film"] = {"meniscus_radius_mm": 0, "upper_meniscus_radius_mm": 0}
    flat = purkinje.render(purkinje.parse_scene(d), noise=False)
    assert all(x.kind == "sclera" for x in flat.labels.views[0].distractors)


def test_glasses_ghosts_are_labelled_by_lens_and_imaged():
    d = purkinje.load_scene(SOURCE_DIR / "assets/scenes/remote_glasses.json").to_dict()
    result = purkinje.render(purkinje.parse_scene(d), noise=False)
    ghosts = [x for x in result.labels.views[0].distractors if x.spectacle_lens is not None]
    # Two lenses, two surfaces, two LEDs, every ghost in view.
    assert len(ghosts) == 8
    assert {x.kind for x in ghosts} == {"spectacle_lens_front", "spectacle_lens_back"}
    assert {x.spectacle_lens_name for x in ghosts} == {"right_lens", "left_lens"}
    share = float((result.aov("distractor") * result.electrons).sum())
    assert share == pytest.approx(sum(x["electrons"] for x in result.distractors), rel=1e-4)
    # Without the lenses, none; the glints move (the lens refracts them).
    del d["spectacle_lenses"]
    bare = purkinje.render(purkinje.parse_scene(d), noise=False)
    assert not bare.labels.views[0].distractors
    moved = [abs(a.u_px - b.u_px) for a, b in zip(result.labels.views[0].glints, bare.labels.views[0].glints)]
    assert min(moved) > 0.05


def test_import_leaves_open_image_io_unloaded_until_a_file_is_touched():
    import subprocess
    import sys

    code = ("import purkinje, sys\n"
            "maps = open('/proc/self/maps').read()\n"
            "sys.exit(1 if 'libOpenImageIO.so' in maps else 0)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0
