// One TBB thread per process under the coverage build's test run
// (scripts/test.sh sets PURKINJE_TEST_CORE_LOCKS), for the processes the
// tests start that are no test binaries: the purkinje command (the CLI
// tests' children, the Slurm test's jobs, which slurmd starts on any core)
// and the Python package's module (a Python test without a free core).
// Linked into them only in a coverage build (CMakeLists.txt): its plain
// counters lose updates when two threads run the same code, and gcov then
// finds negative counts. Test binaries take a core as well
// (tests/one_core.cpp). Without the variable a process runs as it would.

#include <tbb/global_control.h>

#include <cstdlib>

namespace {

bool one_thread() {
  const char* folder = std::getenv("PURKINJE_TEST_CORE_LOCKS");
  if (folder == nullptr || *folder == '\0') return false;
  // Never deleted: it holds until the process ends, whatever an arena asks for.
  new tbb::global_control(tbb::global_control::max_allowed_parallelism, 1);
  return true;
}

[[maybe_unused]] const bool capped = one_thread();

}  // namespace
