"""The fast mode against the reference mode, class by class (docs/benchmarks.md,
"Speed and error with a face"): for each segmentation class, the mean of
fast - reference over the reference's mean (a bias) and the RMS of it (per
pixel), glint pixels left out, and the image's relative error as the render
benchmarks define it (RMSE over the mean of non-zero reference pixels).

    PYTHONPATH=build/release/python python3 benchmarks/class_errors.py SCENE [--rays 256] [--face] [--lashes]

--face gives every eye of the scene a periocular face with every default, as
BM_RenderHeadsetFace does; --lashes gives that face default lashes
(BM_RenderHeadsetFaceLashes).
"""

import argparse
import json

import numpy as np

import purkinje

CLASSES = ["background", "skin", "sclera", "iris", "pupil", "lash", "brow"]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("scene")
    parser.add_argument("--rays", type=int, default=256, help="reference rays per pixel")
    parser.add_argument("--photons", type=int, default=1 << 22, help="reference photons per light")
    parser.add_argument("--edge-rays", type=int, default=10, help="fast mode's edge rays")
    parser.add_argument("--face", action="store_true")
    parser.add_argument("--lashes", action="store_true", help="with --face: default lashes too")
    args = parser.parse_args()

    scene = purkinje.load_scene(args.scene)
    if args.face:
        if len(scene.eyes) != 1:
            parser.error("--face gives one eye a right-side face: the scene must have one eye")
        d = json.loads(scene.to_json())
        for eye in d["eyes"]:
            eye["face"] = {"lashes": {}} if args.lashes else {}
        scene = purkinje.parse_scene(d, name=args.scene)
    fast = purkinje.render(scene, samples_per_pixel=1, edge_samples_per_pixel=args.edge_rays, noise=False)
    reference = purkinje.render(scene, mode="reference", samples_per_pixel=args.rays, edge_samples_per_pixel=0,
                                noise=False, reference_photons_per_light=args.photons, seed=12345)
    f = np.asarray(fast.electrons, dtype=float)
    g = np.asarray(reference.electrons, dtype=float)
    ids = np.asarray(reference.aov("id"))
    keep = np.asarray(reference.aov("glint")) <= 0.01
    d = f - g
    lit = g[keep & (g > 0)].mean()
    print(f"image: relative error {np.sqrt((d[keep] ** 2).mean()) / lit:.4%}")
    for c, name in enumerate(CLASSES):
        m = keep & (ids == c)
        if m.sum() == 0 or g[m].mean() <= 0:
            continue
        mean = g[m].mean()
        print(f"{name:>10}: {m.sum():7d} px, bias {d[m].mean() / mean:+.2%}, rms {np.sqrt((d[m] ** 2).mean()) / mean:.2%}")


if __name__ == "__main__":
    main()
