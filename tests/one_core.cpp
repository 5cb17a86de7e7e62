// One core per test process, under the coverage build's test run
// (scripts/test.sh sets PURKINJE_TEST_CORE_LOCKS to a folder): before
// main, the process takes a core no other test holds and runs on it alone
// (all its threads, and its children), and TBB runs one thread at most,
// whatever an arena asks for: the coverage build's plain counters
// (CMakeLists.txt) lose updates when two threads run the same code, even
// on one core.
// A core is held by a lock on its file in the folder (flock: let go when
// the process ends, and not passed to children, which may outlive it).
// Without a free core (or the variable) the process runs as it would.

#include <fcntl.h>
#include <sched.h>
#include <sys/file.h>
#include <unistd.h>

#include <tbb/global_control.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

namespace {

bool take_a_core() {
  const char* folder = std::getenv("PURKINJE_TEST_CORE_LOCKS");
  if (folder == nullptr || *folder == '\0') return false;
  cpu_set_t allowed;
  CPU_ZERO(&allowed);
  if (::sched_getaffinity(0, sizeof allowed, &allowed) != 0) return false;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(cpu, &allowed)) continue;
    const std::string lock = std::string(folder) + "/core-" + std::to_string(cpu) + ".lock";
    const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd);
      continue;
    }
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    // Every thread: libraries start some of theirs before main (the
    // threads they start later inherit the core).
    std::error_code error;
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task", error)) {
      ::sched_setaffinity(static_cast<pid_t>(std::stol(task.path().filename().string())), sizeof one, &one);
    }
    ::sched_setaffinity(0, sizeof one, &one);
    // Never deleted: it holds until the process ends.
    new tbb::global_control(tbb::global_control::max_allowed_parallelism, 1);
    return true;  // fd stays open: the core is this process's until it ends
  }
  return false;
}

[[maybe_unused]] const bool on_one_core = take_a_core();

}  // namespace
