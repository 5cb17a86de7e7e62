#!/usr/bin/env bash
# Fuzzes the file readers (tests/fuzz): builds the libFuzzer targets with
# clang++ under ASan+UBSan in build/fuzz, then runs each for SECONDS on a
# fresh copy of its corpus, one per core at a time. New inputs go to the copy
# (build/fuzz/corpus/), never to the tree; a finding stops the run (once the
# targets fuzzed beside it end) with a non-zero exit, its input saved in
# build/fuzz/findings/.
#
#   bash scripts/fuzz.sh [SECONDS [TARGET...]]   (60 s; scene obj labels detections dataset_spec)
set -euo pipefail
cd "$(dirname "$0")/.."
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"  # cache hits across checkouts

seconds="${1:-60}"
[ $# -gt 0 ] && shift
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scene obj labels detections dataset_spec)
build=build/fuzz

bash scripts/install-deps.sh  # clang and its libFuzzer runtime among them
# Tests and benchmarks off: they need no clang build. The fuzzers link the
# models library only (tests/fuzz/CMakeLists.txt), and nothing else is built.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ \
  -DPURKINJE_FUZZ=ON -DPURKINJE_BUILD_TESTS=OFF -DPURKINJE_BUILD_BENCHMARKS=OFF
cmake --build "$build" --target "${targets[@]/%/_fuzzer}"

mkdir -p "$build/findings" "$build/logs"
# One target per core at a time: each fuzzer is one process on one core.
fuzz_one() {
  local target="$1"
  local corpus="$build/corpus/$target"
  local log="$build/logs/$target.log"  # libFuzzer writes a line per new input: megabytes a minute
  rm -rf "$corpus"
  mkdir -p "$corpus"
  cp tests/fuzz/corpus/"$target"/* "$corpus"/
  echo "fuzz: $target for ${seconds} s (log: $log)"
  # -max_len: the corpus holds reproducers of 200 KB (deep nesting); left
  # to itself libFuzzer would mutate inputs that long and run 15 times
  # slower. Those are replayed whole by fuzz_replay_tests; here they are
  # cut to 16 KB, four times the largest real scene. -timeout: an input
  # taking 10 s is a hang (a FIFO once blocked the scene reader forever).
  if ! "$build/tests/fuzz/${target}_fuzzer" -max_total_time="$seconds" -max_len=16384 -timeout=10 \
      -print_final_stats=1 -artifact_prefix="$build/findings/$target-" "$corpus" >"$log" 2>&1; then
    tail -n 60 "$log" >&2  # the report, and the file the input was saved to
    echo "fuzz: the $target target failed; its input is in $build/findings/ (replay it with" \
         "$build/tests/fuzz/${target}_fuzzer FILE; add it to tests/fuzz/corpus/$target/ once the reader is fixed)" >&2
    return 1
  fi
  # Executions, coverage (cov: edges, ft: features) and speed.
  grep -E '^#[0-9]+[[:space:]]+DONE|^stat::(number_of_executed_units|average_exec_per_sec|peak_rss_mb)' "$log" |
    sed "s/^/$target: /" || true
}
failed=0
cores="$(nproc)"
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT  # no fuzzer outlives the script
for ((first = 0; first < ${#targets[@]}; first += cores)); do
  pids=()
  for target in "${targets[@]:first:cores}"; do
    fuzz_one "$target" &
    pids+=($!)
  done
  for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
  [ "$failed" -eq 0 ] || exit 1  # a finding stops the run after its batch
done
echo "fuzz: ${targets[*]}: no findings in ${seconds} s each"
