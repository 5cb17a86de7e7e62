// One core per test process, under the coverage build's test run
// (scripts/test.sh sets PURKINJE_TEST_CORE_LOCKS to a folder): before
// main, the process takes a core no other test holds and runs on it alone
// (all its threads, and its children), and TBB runs one thread at most,
// whatever an arena asks for: the coverage build's plain counters
// (CMakeLists.txt) lose updates when two threads run the same code, even
// on one core.
// A core is held by a lock on its file in the folder (flock: let go when
// the process ends; children that exec do not inherit it, forked ones share
// it until they end). Without a free core the process still runs one
// thread, on the shared cores; without the variable, as it would.

#include <fcntl.h>
#include <sched.h>
#include <sys/file.h>
#include <unistd.h>

#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace {

// Pins every thread of this process to `cpu`.
void pin(int cpu) {
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  // Every thread: libraries start some of theirs before main (the threads
  // started later inherit the core).
  std::error_code error;
  std::filesystem::directory_iterator task("/proc/self/task", error), end;
  for (; !error && task != end; task.increment(error)) {
    ::sched_setaffinity(static_cast<pid_t>(std::stol(task->path().filename().string())), sizeof one, &one);
  }
  ::sched_setaffinity(0, sizeof one, &one);
}

bool take_a_core() {
  const char* folder = std::getenv("PURKINJE_TEST_CORE_LOCKS");
  if (folder == nullptr || *folder == '\0') return false;
  // One thread at most, core or not (never deleted: it holds until the
  // process ends).
  new tbb::global_control(tbb::global_control::max_allowed_parallelism, 1);
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (::sched_getaffinity(0, sizeof allowed, &allowed) == 0) {
    for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
      if (!CPU_ISSET(cpu, &allowed)) continue;
      const std::string lock = std::string(folder) + "/core-" + std::to_string(cpu) + ".lock";
      const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
      if (fd < 0) continue;
      if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        ::close(fd);
        continue;
      }
      pin(cpu);
      return true;  // fd stays open: the core is this process's until it ends
    }
  }
  std::fprintf(stderr, "one_core: no free core in %s; running on the shared ones\n", folder);
  return false;
}

[[maybe_unused]] const bool on_one_core = take_a_core();

}  // namespace
