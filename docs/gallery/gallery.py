"""The gallery of docs/rendering.md: the bundled scenes, twelve images
drawn across the face's and the lashes' parameters, three of what a
real camera adds (JPEG and hot pixels, vignetting, a saccade), one of
the iris's furrows and freckles, one of dense brows, one of the skin's
and sclera's textures and two of wet eyes' highlights,
each with its labels
drawn over it (purkinje.figures.draw_labels). Rendered in the fast mode as
`purkinje render` does by default (1 ray, 16 on edges, sensor noise).

    PYTHONPATH=build/release/python python3 docs/gallery/gallery.py [STEM ...]

writes docs/gallery/*.png and the table between the gallery markers of
docs/rendering.md; with stems (`headset_wet`), only those images and
their rows.
"""

import math
import sys
from pathlib import Path

import numpy as np

import purkinje
from purkinje.figures import LABEL_COLOURS, draw_labels

HERE = Path(__file__).resolve().parent
SCENES = HERE.parent.parent / "assets" / "scenes"


def load(name):
    return purkinje.load_scene(SCENES / f"{name}.json").to_dict()


def axis(yaw_deg, pitch_deg):
    """An optical axis toward a camera on world -z (world +y down, +x the
    subject's left): `yaw_deg` toward +x, `pitch_deg` up."""
    y, p = math.radians(yaw_deg), math.radians(pitch_deg)
    return [math.sin(y) * math.cos(p), -math.sin(p), -math.cos(y) * math.cos(p)]


def with_face(d, lashes=None, face=None, lids=None, gaze=None):
    """The scene's first eye with a face (and lashes unless lashes is False),
    the lids, face and lashes keys given, turned to `gaze` (yaw, pitch)."""
    eye = d["eyes"][0]
    eye["face"] = dict(face or {})
    if lashes is not False:
        eye["face"]["lashes"] = dict(lashes or {})
    eye["eyelids"] = {**eye.get("eyelids", {}), **(lids or {})}
    if gaze is not None:
        eye["orientation"] = {"optical_axis": axis(*gaze)}
    return d


# (file stem, caption, scene dict, crop half-size in px around the first
# eye's pupil or None for the whole image)
def entries():
    bundled = [
        ("remote_face", "remote_face (bundled): both eyes, face, lids, lashes, brows", load("remote_face"), None),
        ("remote", "remote (bundled): lid sphere in a wall", load("remote"), 60),
        ("headset", "headset (bundled): lid sphere", load("headset"), None),
        ("remote_glasses", "remote_glasses (bundled): glasses, -3 D lenses in a frame; the eye seen through a lens, "
         "each lens mirroring each LED off its front and its back (ghosts)", load("remote_glasses"), 90),
    ]
    h, r = "headset", "remote"
    drawn = [
        ("headset_face", "headset, face and lashes (defaults)", with_face(load(h)), None),
        ("headset_down", "looking down 20 deg: the lid follows, lashes over the cornea",
         with_face(load(h), gaze=(0, -20)), None),
        ("headset_up", "looking up 15 deg", with_face(load(h), gaze=(0, 15)), None),
        ("headset_half_open", "lid opening 0.45", with_face(load(h), lids={"opening": 0.45}), None),
        ("headset_mascara", "mascara: dense, thick, dark lashes (6/mm, 0.15 mm, albedo 0.03)",
         with_face(load(h), lashes={"upper_per_mm": 6, "thickness_mm": 0.15, "albedo": 0.03}), None),
        ("headset_sparse", "sparse short straight lashes, no crease",
         with_face(load(h), lashes={"upper_per_mm": 1.5, "upper_length_mm": 6, "upper_curl_deg": 10},
                   face={"crease_height_mm": 0}), None),
        ("headset_tilt_brow", "canthal tilt -8 deg, brow 8 mm proud, thin margin",
         with_face(load(h), face={"canthal_tilt_deg": -8, "brow_prominence_mm": 8, "margin_thickness_mm": 1.0}),
         None),
        ("headset_nasal", "looking 25 deg toward the nose", with_face(load(h), gaze=(25, 0)), None),
        ("remote_face_crop", "remote with a face and lashes, looking at the camera", with_face(load(r), gaze=(0, 0)),
         60),
        ("remote_down", "remote, looking down 20 deg", with_face(load(r), gaze=(0, -20)), 60),
        ("remote_long_lashes", "remote, lid opening 0.6, long curled lashes (12 mm, 70 deg)",
         with_face(load(r), lids={"opening": 0.6}, lashes={"upper_length_mm": 12, "upper_curl_deg": 70},
                   gaze=(0, 0)), 60),
        ("remote_blink", "remote, a blink: lids closed, every feature hidden",
         with_face(load(r), lids={"opening": 0.0}, gaze=(0, 0)), 60),
    ]
    # What a real camera adds (the sensor's keys and an eye's motion).
    streamed = with_face(load(h))
    streamed["cameras"][0]["sensor"].update({"jpeg_quality": 40, "hot_pixel_fraction": 0.002})
    vignetted = with_face(load(h))
    vignetted["cameras"][0]["sensor"]["corner_illumination"] = 0.35
    saccade = with_face(load(r), gaze=(0, 0))
    saccade["eyes"][0]["motion"] = {"yaw_deg_s": 900}
    camera = [
        ("headset_streamed", "headset with a face, as a cheap streaming camera delivers it: JPEG quality 40, "
         "0.2% hot pixels", streamed, None),
        ("headset_vignetted", "headset with a face, a lens with 35% relative illumination at the corners",
         vignetted, None),
        ("remote_saccade", "remote with a face, a 900 deg/s saccade during the 4 ms exposure (3.6 deg): "
         "glints streak, the labels are mid-exposure's", saccade, 60),
    ]
    # Wet eyes: the sclera's highlights (distractors, cyan squares) where the
    # eye turns far enough that the sclera mirrors the LEDs, and the lids'
    # tear menisci's along the lids.
    wet_remote = with_face(load(r), gaze=(-38, 0))
    wet_remote["eyes"][0]["appearance"]["tear_film"] = {}
    wet_headset = with_face(load(h), gaze=(30, 8))
    wet_headset["eyes"][0].setdefault("appearance", {})["tear_film"] = {}
    wet_headset["cameras"][0]["sensor"]["exposure_s"] = 0.0004  # the face's lit sclera saturates at 1 ms
    textured = with_face(load(h), gaze=(20, 5))
    textured["eyes"][0].setdefault("appearance", {}).update({"skin_texture_contrast": 0.3, "sclera_vessel_contrast": 0.5})
    varied = with_face(load(h), gaze=(0, 5))
    varied["eyes"][0].setdefault("appearance", {}).update({"iris_furrow_contrast": 1.0, "iris_freckles": 8,
                                                          "iris_seed": 3})
    browed = load("remote_face")
    for eye, seed in zip(browed["eyes"], (1, 2)):
        eye["face"]["brows"] = {"hairs_per_mm2": 3, "width_mm": 12, "thickness_mm": 0.1, "albedo": 0.06, "seed": seed}
    wet = [
        ("headset_iris_variety", "headset with a face, an iris with contraction furrows (1) and 8 freckles",
         varied, None),
        ("remote_face_dense_brows", "remote_face with dense, wide, dark brows (3 hairs/mm^2, 12 mm, albedo 0.06)",
         browed, 170),
        ("headset_textured", "headset with a face, the skin's albedo textured (wrinkles, pores, blotches; contrast "
         "0.3) and the sclera's vessels (0.5), looking 20 deg aside", textured, None),
        ("remote_wet", "remote with a face, wet eyes (tear film: 2 deg of roughness, menisci of 0.3 mm on the "
         "lower lid and 0.25 mm on the upper), looking 38 deg aside: the sclera mirrors both LEDs beside the "
         "glints, and so do the lids' tear menisci", wet_remote, 60),
        ("headset_wet", "headset with a face, wet eyes, looking 30 deg aside and 8 up, exposed 0.4 ms (at 1 ms "
         "the lit sclera saturates and hides them): the sclera's highlights, wide at 35 mm, and the tear "
         "menisci's small ones along both lids", wet_headset, None),
    ]
    return bundled, drawn + camera + wet


def draw(stem, caption, d, half, out):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    result = purkinje.render(purkinje.parse_scene(d, name=stem))
    image = np.asarray(result.image, dtype=float)
    labels = result.labels
    views = [v for v in labels.views if v.camera == 0]
    if half is None:
        x0, y0, x1, y1 = 0, 0, image.shape[1], image.shape[0]
    else:
        c = views[0].pupil.ellipse
        u, v = round(c.center_u_px), round(c.center_v_px)
        x0, y0 = max(0, u - half), max(0, v - round(0.75 * half))
        x1, y1 = min(image.shape[1], u + half), min(image.shape[0], v + round(0.75 * half))
    crop = image[y0:y1, x0:x1]
    size = 3.6  # inches at 100 dpi: 360 px wide
    fig = plt.figure(figsize=(size, size * crop.shape[0] / crop.shape[1]))
    ax = fig.add_axes([0, 0, 1, 1])
    ax.imshow(crop, cmap="gray", vmin=0, vmax=255 if result.bits == 8 else 2 ** result.bits - 1,
              extent=(-0.5, crop.shape[1] - 0.5, crop.shape[0] - 0.5, -0.5), interpolation="nearest")
    counts = {}
    for view in views:
        for key, n in draw_labels(ax, view, origin=(x0, y0)).items():
            counts[key] = counts.get(key, 0) + n
    ax.set_xlim(-0.5, crop.shape[1] - 0.5)
    ax.set_ylim(crop.shape[0] - 0.5, -0.5)
    ax.axis("off")
    fig.savefig(out / f"{stem}.png", dpi=100)
    plt.close(fig)
    seen = ", ".join(f"{n} {LABEL_COLOURS[k][1]}" for k, n in sorted(counts.items()))
    return f"| ![{stem}](gallery/{stem}.png) | {caption}. Features: {seen}. |"


def main(stems):
    bundled, drawn = entries()
    doc = HERE.parent / "rendering.md"
    text = doc.read_text()
    begin, end = "<!-- gallery: written by docs/gallery/gallery.py -->\n", "<!-- /gallery -->"
    before, rest = text.split(begin)
    table, after = rest.split(end)
    unknown = set(stems) - {entry[0] for entry in bundled + drawn}
    if unknown:
        print(f"gallery.py: no gallery image named {', '.join(sorted(unknown))}", file=sys.stderr)
        return 2
    old_rows = {row.split("](")[0][4:]: row for row in table.splitlines() if row.startswith("| ![")}
    rows = ["| image | what it shows |", "| --- | --- |"]
    for entry in bundled + drawn:
        if stems and entry[0] not in stems and entry[0] in old_rows:
            rows.append(old_rows[entry[0]])
            continue
        rows.append(draw(*entry, HERE))
        print(rows[-1], flush=True)
    doc.write_text(before + begin + "\n".join(rows) + "\n" + end + after)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
