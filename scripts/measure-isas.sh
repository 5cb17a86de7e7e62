#!/usr/bin/env bash
# Speed per instruction set, measured in one run: the bars' benchmarks
# under the CPU's own kernels (native), then with Embree held to AVX2 and
# to SSE4.2 and OpenCV's dispatch capped alike, alternated round by round
# so that the machine's drift falls on every column. Prints each
# benchmark's median per column and its ratio to native; the figures go to
# docs/benchmarks.md ("Instruction sets"). About 5 minutes on 2 cores.
#
#   bash scripts/measure-isas.sh [ROUNDS] [FILTER]   (default 3 rounds, the bars' benchmarks)
set -euo pipefail
cd "$(dirname "$0")/.."
rounds="${1:-3}"
filter="${2:-BM_RenderRemotePairs/1/0|BM_RenderHeadsetPairs/1/1[02]|BM_TrackersRemote|BM_TrackersHeadset|BM_CorneaCenterHeadsetNoisy|BM_SphereGlint}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DPURKINJE_BUILD_BENCHMARKS=ON > /dev/null
cmake --build build/release --target purkinje_benchmarks > /dev/null
bench=build/release/benchmarks/purkinje_benchmarks

declare -A embree=([native]="" [avx2]="isa=avx2" [sse4.2]="isa=sse4.2")
declare -A opencv=([native]="" [avx2]="AVX512F,AVX512-SKX" [sse4.2]="AVX,AVX2,FMA3,FP16,AVX512F,AVX512-SKX")
columns=(native avx2 sse4.2)
for round in $(seq 1 "$rounds"); do
  for c in "${columns[@]}"; do
    echo "round $round/$rounds: $c" >&2
    PURKINJE_EMBREE_CONFIG="${embree[$c]}" OPENCV_CPU_DISABLE="${opencv[$c]}" "$bench" \
      --benchmark_filter="$filter" --benchmark_min_time=2 \
      --benchmark_format=json --benchmark_out="$out/$c.$round.json" > /dev/null 2>&1
  done
done

python3 - "$out" "$rounds" "${columns[@]}" <<'PY'
import json, statistics, sys
out, rounds, columns = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
times, context = {}, {}
for c in columns:
    for r in range(1, rounds + 1):
        doc = json.load(open(f"{out}/{c}.{r}.json"))
        context[c] = doc["context"]
        for b in doc["benchmarks"]:
            value = b.get("images_per_s")
            unit = "images/s" if value else b["time_unit"]
            times.setdefault(b["name"], {}).setdefault(c, []).append((value or b["real_time"], unit))
ctx = context[columns[0]]
print(f"CPU: {ctx.get('cpu_model')}; vector extensions: {ctx.get('cpu_vector_extensions')}")
for c in columns:
    print(f"  {c}: embree isa {context[c].get('embree_isa')}; OpenCV {context[c].get('opencv_cpu_features')}")
print(f"medians of {rounds} rounds, alternated; ratio = time / native time (images/s inverted)")
print("| benchmark | " + " | ".join(columns) + " | " + " | ".join(f"{c} / native" for c in columns[1:]) + " |")
print("|---" * (2 * len(columns)) + "|")
for name, by in times.items():
    med = {c: statistics.median(v for v, _ in by[c]) for c in columns}
    unit = by[columns[0]][0][1]
    ratio = lambda c: (med["native"] / med[c]) if unit == "images/s" else (med[c] / med["native"])
    cells = [f"{med[c]:.4g} {unit}" for c in columns]
    print(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(f"{ratio(c):.3f}" for c in columns[1:]) + " |")
PY
