"""The iris's radiance near the limbus, fast mode against the reference mode,
and the reference mode's convergence (docs/benchmarks.md, "Iris radiance
near the limbus").

An eye facing the camera on its axis, no lids, a flat iris of one albedo,
two LEDs symmetric about the axis: the iris's radiance depends on the
distance from the axis alone, so images are compared ring by ring (2 px of
image radius) over the pixels that are iris through and through. The
reference mode's own converged image (--converged samples per pixel, other
seed) is the yardstick.

--face gives the eye lids and a periocular face with every default (no
lashes): the lids hem the iris in and light it, so the radiance is no longer
a function of the radius alone, but each ring still compares the same
pixels (those that are iris through and through in both images).

    PYTHONPATH=build/release/python python3 benchmarks/limbus_radiometry.py [--converged 4096] [--face]
"""

import argparse
import time

import numpy as np

import purkinje

SCENE = """{ "format": 1, "name": "facing",
  "cameras": [ { "name": "cam", "resolution_px": [120, 120], "focal_length_mm": 30, "pixel_pitch_mm": 0.006,
                 "sensor": { "noise": false }, "position_mm": [0, 0, 0], "look_at_mm": [0, 0, 600], "up": [0, -1, 0] } ],
  "illuminators": [
    { "name": "left",  "position_mm": [-100, 0, 0], "radiant_intensity_w_sr": 0.3, "wavelength_nm": 850 },
    { "name": "right", "position_mm": [ 100, 0, 0], "radiant_intensity_w_sr": 0.3, "wavelength_nm": 850 } ],
  "eyes": [ { "model": "MODEL", "pupil": { "radius_mm": 2.0 },
              "position": { "cornea_center_mm": [0, 0, 600] }, "orientation": { "optical_axis": [0, 0, -1] },
              "appearance": { "iris_albedo": 0.2, "iris_texture_contrast": 0, "fundus_reflectance": 0 } } ] }"""


def render(scene, **options):
    start = time.perf_counter()
    result = purkinje.render(scene, noise=False, edge_samples_per_pixel=0, **options)
    return np.array(result.radiance, dtype=np.float64), np.array(result.aov("iris")) == 1, time.perf_counter() - start


def rings(image, mask):
    h, w = image.shape
    y, x = np.mgrid[0:h, 0:w]
    r = np.hypot(x - (w - 1) / 2, y - (h - 1) / 2)
    out = {}
    for inner in range(0, int(r.max()), 2):
        m = mask & (r >= inner) & (r < inner + 2)
        if m.sum() >= 40:
            out[inner] = image[m].mean()
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--converged", type=int, default=4096, help="the converged reference's samples per pixel")
    parser.add_argument("--face", action="store_true", help="the eye with a periocular face")
    args = parser.parse_args()
    for model in ("navarro", "keratometric"):
        text = SCENE.replace("MODEL", model)
        if args.face:
            text = text.replace('"fundus_reflectance": 0 }', '"fundus_reflectance": 0 }, "eyelids": {}, "face": {}')
        scene = purkinje.parse_scene(text)
        truth, truth_mask, seconds = render(scene, mode="reference", samples_per_pixel=args.converged, seed=99)
        print(f"{model}: reference at {args.converged} samples per pixel, {seconds:.0f} s")
        truth_rings = rings(truth, truth_mask)
        fast, fast_mask, seconds = render(scene, samples_per_pixel=64)
        errors = {r: v / truth_rings[r] - 1 for r, v in rings(fast, fast_mask & truth_mask).items() if r in truth_rings}
        print(f"  fast, 64 samples ({seconds:.2f} s): worst ring {max(abs(e) for e in errors.values()) * 100:.2f}%")
        print("    " + " ".join(f"{r}:{e * 100:+.2f}" for r, e in errors.items()))
        print("  reference: samples, seconds, RMS over the iris's pixels, worst ring")
        for samples in (4, 16, 64, 256, 1024):
            if samples >= args.converged:
                break
            image, mask, seconds = render(scene, mode="reference", samples_per_pixel=samples, seed=5)
            both = mask & truth_mask
            rms = np.sqrt(np.mean((image[both] / truth[both] - 1) ** 2))
            rms_own = rms / np.sqrt(1 + samples / args.converged)  # less the converged image's own noise
            worst = max(abs(v / truth_rings[r] - 1) for r, v in rings(image, both).items() if r in truth_rings)
            print(f"    {samples:5d} {seconds:7.1f} {rms_own * 100:6.3f}% {worst * 100:6.3f}%")


if __name__ == "__main__":
    main()
