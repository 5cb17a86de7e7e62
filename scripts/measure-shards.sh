#!/usr/bin/env bash
# Two shards as two processes against one process, measured in one run:
# `purkinje generate` of a bundled spec's first 2N images by one process
# (one thread), then by two processes at once (--shard 0/2 and 1/2, one
# thread each), alternated round by round so the machine's drift falls on
# both. Prints each round's seconds and the ratio of the sums (images per
# second, two processes over one); the figure goes to docs/benchmarks.md
# ("Data sets"). Start-up is included, as on a cluster. About 3 minutes.
#
#   bash scripts/measure-shards.sh [SPEC] [N] [ROUNDS]   (assets/datasets/remote.json, 20, 3)
set -euo pipefail
cd "$(dirname "$0")/.."
spec="${1:-assets/datasets/remote.json}"
n="${2:-20}"
rounds="${3:-3}"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build build/release --target purkinje > /dev/null
purkinje=build/release/tools/purkinje

seconds() {  # seconds COMMAND...: wall time of the command
  local start end
  start=$(date +%s.%N)
  "$@"
  end=$(date +%s.%N)
  python3 -c "print($end - $start)"
}
one() { "$purkinje" generate "$spec" -o "$out/one" --count $((2 * n)) --threads 1 --quiet > /dev/null; }
two() {
  "$purkinje" generate "$spec" -o "$out/two" --count $((2 * n)) --shard 0/2 --threads 1 --quiet > /dev/null &
  "$purkinje" generate "$spec" -o "$out/two" --count $((2 * n)) --shard 1/2 --threads 1 --quiet > /dev/null
  wait
}

one_total=0
two_total=0
for round in $(seq 1 "$rounds"); do
  rm -rf "$out/one" "$out/two"
  t1=$(seconds one)
  t2=$(seconds two)
  echo "round $round/$rounds: one process $t1 s, two processes $t2 s ($((2 * n)) images)"
  one_total=$(python3 -c "print($one_total + $t1)")
  two_total=$(python3 -c "print($two_total + $t2)")
done
python3 -c "print('two processes / one: %.3f (images per second)' % ($one_total / $two_total))"
