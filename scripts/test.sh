#!/usr/bin/env bash
# Build purkinje (Debug) and run every test; exits non-zero if any fails.
# PURKINJE_TEST_COVERAGE=ON builds with gcov line coverage (CI reports it
# from this run instead of building and testing a third time).
set -euo pipefail
cd "$(dirname "$0")/.."
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$PWD}"  # cache hits across checkouts

bash scripts/install-deps.sh
cmake -S . -B build/debug -G Ninja -DCMAKE_BUILD_TYPE=Debug -DPURKINJE_COVERAGE="${PURKINJE_TEST_COVERAGE:-OFF}"
cmake --build build/debug
find build/debug -name '*.gcda' -delete  # counts of an earlier run would inflate coverage
# With coverage, each test process takes a core of its own (tests/one_core.cpp,
# tests/python/conftest.py): one thread a test, so that the coverage build's
# plain counters are never updated by two threads (CMakeLists.txt).
if [ "${PURKINJE_TEST_COVERAGE:-OFF}" = ON ]; then
  export PURKINJE_TEST_CORE_LOCKS="$PWD/build/debug/core-locks"
  mkdir -p "$PURKINJE_TEST_CORE_LOCKS"
fi
ctest --test-dir build/debug --output-on-failure --no-tests=error -j "$(nproc)"
