"""The compare study's cost, as docs/benchmarks.md reports it (Release
build, one core: run under `taskset -c 0`; `python3
benchmarks/compare_bench.py --help`). In one process, alternated in
rounds: the geometric part (the remote rig against a spherical tracker:
9x9 displacement field, both calibrations with exact features, 9x9 gaze
grid at home and two head moves, both methods; images=False), the whole
study with images, and two renders of the remote scene as the study
renders them; and the geometric part of the hardest assumed version for
the tracker's solver, an aspheric one (the remote rig's Navarro eye
believed as it is: the pupil outline refracted through a conicoid).
Reports the seconds and the ratio (whole - geometric) / two renders per
round, and their medians.
"""

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", type=Path, default=ROOT / "build/release", help="a Release build folder")
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    sys.path.insert(0, str(args.build / "python"))
    import purkinje

    scene = purkinje.load_scene(ROOT / "assets/scenes/remote.json")
    geometric, whole, renders, ratios, aspheric = [], [], [], [], []
    for _ in range(args.rounds):
        t = time.perf_counter()
        purkinje.compare(scene, assumed_cornea=(7.8, 0), images=False)
        geometric.append(time.perf_counter() - t)
        t = time.perf_counter()
        purkinje.compare(scene, assumed_cornea=(7.8, 0))
        whole.append(time.perf_counter() - t)
        t = time.perf_counter()
        for seed in (0, 0):
            purkinje.render(scene, seed=seed)
        renders.append(time.perf_counter() - t)
        ratios.append((whole[-1] - geometric[-1]) / renders[-1])
        t = time.perf_counter()
        purkinje.compare(scene, images=False)
        aspheric.append(time.perf_counter() - t)
        print(f"geometric {geometric[-1]:.3f} s, whole {whole[-1]:.3f} s, two renders {renders[-1]:.3f} s, "
              f"(whole - geometric) / two renders {ratios[-1]:.3f}, aspheric geometric {aspheric[-1]:.3f} s", flush=True)
    print(f"median: geometric {statistics.median(geometric):.3f} s, whole {statistics.median(whole):.3f} s, "
          f"two renders {statistics.median(renders):.3f} s, ratio {statistics.median(ratios):.3f}, "
          f"aspheric geometric {statistics.median(aspheric):.3f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
