"""The Python package's costs, measured as docs/benchmarks.md reports them
(Release build; `python3 benchmarks/python_bench.py --help`):

- import: `import purkinje` in a fresh interpreter, median of 7;
- render: the remote scene rendered from Python against the C++
  benchmark's same render (BM_RenderRemote/1/16: 1 sample per pixel, 16 on
  edges, no noise, 2^20 photons), alternated in rounds, as a ratio per round;
- loader: a DataLoader with 2 workers over a generated set (made if
  missing), images per second with PNG decoding, images as float32 and as
  the PNG's values (as_float=False), each on its second pass (the first
  warms the page cache).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def import_seconds(build: Path) -> float:
    code = "import time; t = time.perf_counter(); import purkinje; print(time.perf_counter() - t)"
    env = dict(os.environ, PYTHONPATH=str(build / "python"))
    runs = [float(subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                                 check=True).stdout) for _ in range(7)]
    return statistics.median(runs)


def cpp_render_ms(build: Path, seconds: float) -> float:
    run = subprocess.run([str(build / "benchmarks/purkinje_benchmarks"), "--benchmark_filter=^BM_RenderRemote/1/16/real_time$",
                          f"--benchmark_min_time={seconds}", "--benchmark_format=json"],
                         capture_output=True, text=True, check=True)
    (bench,) = json.loads(run.stdout)["benchmarks"]
    assert bench["time_unit"] == "ms"
    return bench["real_time"]


def python_render_ms(purkinje, scene, seconds: float) -> float:
    options = dict(samples_per_pixel=1, edge_samples_per_pixel=16, noise=False, reference_photons_per_light=1 << 20)
    purkinje.render(scene, **options)  # warm: caches, pools
    count, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        result = purkinje.render(scene, **options)
        del result  # as a loop over images lets each go
        count += 1
    return (time.perf_counter() - start) / count * 1000


def loader_rate(purkinje, build: Path, folder: Path, count: int) -> dict:
    import torch
    import purkinje.torch

    if not (folder / "table.csv").is_file():
        purkinje.generate(ROOT / "assets/datasets/remote.json", folder, count=count)
    rates = {}
    for as_float in (True, False):
        dataset = purkinje.torch.EyeDataset(folder, as_float=as_float)
        loader = torch.utils.data.DataLoader(dataset, batch_size=32, num_workers=2)
        for _ in loader:  # the first pass warms the page cache
            pass
        start = time.perf_counter()
        images = sum(len(batch[0]) for batch in loader)
        rates["float32" if as_float else "png values"] = round(images / (time.perf_counter() - start))
    return {"images": images, "images_per_s": rates}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", type=Path, default=ROOT / "build/release")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=3.0, help="per render measurement")
    parser.add_argument("--set", type=Path, default=ROOT / "out/bench_set_1000")
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--skip-loader", action="store_true")
    args = parser.parse_args()
    sys.path.insert(0, str(args.build / "python"))
    import purkinje

    print(f"import purkinje: {import_seconds(args.build):.3f} s (median of 7)")
    scene = purkinje.load_scene(ROOT / "assets/scenes/remote.json")
    ratios = []
    for k in range(args.rounds):
        cpp = cpp_render_ms(args.build, args.seconds)
        py = python_render_ms(purkinje, scene, args.seconds)
        ratios.append(py / cpp)
        print(f"round {k + 1}: C++ {cpp:.1f} ms, Python {py:.1f} ms per remote image: ratio {py / cpp:.3f}")
    print(f"render from Python / C++ benchmark: median {statistics.median(ratios):.3f}")
    if not args.skip_loader:
        print("DataLoader (2 workers, batch 32):", loader_rate(purkinje, args.build, args.set, args.count))


if __name__ == "__main__":
    main()
