#!/usr/bin/env bash
# Speed before and after a change, measured in one run: the benchmarks of
# two builds (the given revision's, built in a temporary worktree, and
# this tree's build/release) alternated round by round so that the
# machine's drift falls on both columns. Prints each benchmark's median
# per build and the ratio new / old (images/s inverted: above 1 is
# slower). Issue 22's bar ("within 3% of before") is read from it.
#
# MODE=instructions counts instructions instead (valgrind's callgrind,
# one process per benchmark, each run for one iteration): no drift at
# all, so a few percent show where wall-clock medians on a shared VM
# swing by 15%; it sees neither cache misses nor threads' overlap.
#
#   bash scripts/compare-builds.sh OLD_REVISION [ROUNDS] [FILTER]
#   MODE=instructions bash scripts/compare-builds.sh OLD_REVISION 1 [FILTER]
#   (OLD_BENCH=path/to/purkinje_benchmarks skips building the old revision)
set -euo pipefail
cd "$(dirname "$0")/.."
old_revision="${1:?usage: compare-builds.sh OLD_REVISION [ROUNDS] [FILTER]}"
rounds="${2:-3}"
filter="${3:-BM_RenderRemotePairs/1/0|BM_RenderHeadsetPairs/1/1[02]|BM_TrackersRemote|BM_TrackersHeadset|BM_CorneaCenterHeadsetNoisy|BM_SphereGlint|BM_TruthRemoteScene|BM_GazeCalibrationModelBased$}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

old="${OLD_BENCH:-}"
if [[ -z "$old" ]]; then
  tree="$out/old"
  git worktree add --detach "$tree" "$old_revision" > /dev/null 2>&1
  trap 'git worktree remove --force "$tree" > /dev/null 2>&1 || true; rm -rf "$out"' EXIT
  cmake -S "$tree" -B "$tree/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DPURKINJE_BUILD_BENCHMARKS=ON \
    -DPURKINJE_BUILD_TESTS=OFF > /dev/null
  cmake --build "$tree/build" --target purkinje_benchmarks > /dev/null
  old="$tree/build/benchmarks/purkinje_benchmarks"
fi
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DPURKINJE_BUILD_BENCHMARKS=ON > /dev/null
cmake --build build/release --target purkinje_benchmarks > /dev/null
new=build/release/benchmarks/purkinje_benchmarks

if [[ "${MODE:-time}" == instructions ]]; then
  echo "| benchmark | old instructions | new instructions | new / old |"
  echo "|---|---|---|---|"
  for name in $("$new" --benchmark_list_tests --benchmark_filter="$filter"); do
    exact="^${name}\$"  # benchmark names hold no regex metacharacters but $
    declare -A count=()
    for column in old new; do
      bench="$old"
      [[ "$column" == new ]] && bench="$new"
      log="$out/$column.callgrind.log"
      valgrind --tool=callgrind --callgrind-out-file=/dev/null "$bench" --benchmark_filter="$exact" \
        --benchmark_min_time=0.000001 > "$log" 2>&1
      count[$column]=$(sed -n 's/.*I *refs: *//p' "$log" | tr -d ,)
      iterations=$(awk -v n="$name" '$1 == n {print $6}' "$log" | head -1)
      [[ "$iterations" == 1 ]] || echo "warning: $name ran $iterations iterations in $column" >&2
    done
    python3 -c "import sys; o, n = int(sys.argv[2]), int(sys.argv[3]); print(f'| {sys.argv[1]} | {o:,} | {n:,} | {n / o:.4f} |')" \
      "$name" "${count[old]}" "${count[new]}"
  done
  exit 0
fi

for round in $(seq 1 "$rounds"); do
  for column in old new; do
    echo "round $round/$rounds: $column" >&2
    bench="$old"
    [[ "$column" == new ]] && bench="$new"
    "$bench" --benchmark_filter="$filter" --benchmark_min_time=2 \
      --benchmark_format=json --benchmark_out="$out/$column.$round.json" > /dev/null 2>&1
  done
done

python3 - "$out" "$rounds" "$old_revision" "$(git rev-parse --short HEAD)" <<'PY'
import json, statistics, sys
out, rounds, old_name, new_name = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
times, context = {}, None
for c in ("old", "new"):
    for r in range(1, rounds + 1):
        doc = json.load(open(f"{out}/{c}.{r}.json"))
        context = doc["context"]
        for b in doc["benchmarks"]:
            value = b.get("images_per_s")
            unit = "images/s" if value else b["time_unit"]
            times.setdefault(b["name"], {}).setdefault(c, []).append((value or b["real_time"], unit))
print(f"CPU: {context.get('cpu_model')}; vector extensions: {context.get('cpu_vector_extensions')}; "
      f"embree isa {context.get('embree_isa')}")
print(f"old: {old_name}, new: {new_name}; medians of {rounds} rounds, alternated; "
      "ratio = new time / old time (images/s inverted)")
print("| benchmark | old | new | new / old |")
print("|---|---|---|---|")
for name, by in times.items():
    if "old" not in by or "new" not in by:
        continue
    med = {c: statistics.median(v for v, _ in by[c]) for c in ("old", "new")}
    unit = by["old"][0][1]
    ratio = med["old"] / med["new"] if unit == "images/s" else med["new"] / med["old"]
    print(f"| {name} | {med['old']:.4g} {unit} | {med['new']:.4g} {unit} | {ratio:.3f} |")
PY
