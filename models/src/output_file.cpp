#include "purkinje/models/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <charconv>
#include <atomic>
#include <cerrno>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>

namespace purkinje {

namespace {

// The temporaries alive now, for the signal handler: fixed storage, since
// a handler may neither allocate nor take a lock. A slot is free (0),
// being filled (1) or holds a live temporary's path (2). More temporaries
// at once than slots (a render writes three per camera) are still
// written, only not removed by a signal.
constexpr std::size_t kSlots = 128;
constexpr std::size_t kPathBytes = 4096;
struct Slot {
  std::atomic<int> state{0};
  char path[kPathBytes];
};
std::array<Slot, kSlots> g_slots;

// Registered before the file exists, so that no moment leaves a created
// temporary unknown to the handler (unlinking a name not yet created is
// harmless).
Slot* register_temporary(const std::filesystem::path& temporary) {
  const std::string& text = temporary.native();
  if (text.size() >= kPathBytes) return nullptr;
  for (Slot& slot : g_slots) {
    int expected = 0;
    if (!slot.state.compare_exchange_strong(expected, 1)) continue;
    std::memcpy(slot.path, text.c_str(), text.size() + 1);
    slot.state.store(2);
    return &slot;
  }
  return nullptr;
}

// Removes the temporaries, then dies by the signal itself (default action,
// raised again): the parent sees a process the signal ended, so a shell
// loop stops on Ctrl-C and reports 130 or 143.
extern "C" void remove_temporaries_and_die(int signal) {
  for (Slot& slot : g_slots) {
    if (slot.state.load() == 2) ::unlink(slot.path);  // async-signal-safe
  }
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

std::atomic<unsigned> g_counter{0};

}  // namespace

std::filesystem::path create_temporary(const std::filesystem::path& target) {
  const std::filesystem::path directory = target.has_parent_path() ? target.parent_path() : ".";
  for (int attempt = 0;; ++attempt) {
    // Appended piecewise: GCC 12 warns falsely (-Wrestrict) on a chain of operator+.
    std::string name = ".";
    name += target.filename().string();
    name += ".tmp.";
    name += std::to_string(::getpid());
    name += '.';
    name += std::to_string(g_counter++);
    const std::filesystem::path temporary = directory / name;
    Slot* slot = register_temporary(temporary);
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd >= 0) {
      ::close(fd);
      return temporary;
    }
    if (slot) slot->state.store(0);  // not ours: another process's file, or none
    if (errno != EEXIST || attempt > 100) {
      throw std::runtime_error(target.string() + ": cannot create a temporary file: " + std::strerror(errno));
    }
  }
}

void release_temporary(const std::filesystem::path& temporary) {
  for (Slot& slot : g_slots) {
    if (slot.state.load() == 2 && temporary.native() == slot.path) {
      slot.state.store(0);
      return;
    }
  }
}

std::optional<long> temporary_owner(std::string_view name) {
  // ".NAME.tmp.PID.N": a hidden name, then ".tmp.", digits, '.', digits.
  if (name.size() < 2 || name.front() != '.') return std::nullopt;
  const auto digits_from = [&](std::size_t at, std::size_t end) {
    if (at >= end) return false;
    for (std::size_t i = at; i < end; ++i) {
      if (name[i] < '0' || name[i] > '9') return false;
    }
    return true;
  };
  const std::size_t last_dot = name.rfind('.');
  if (last_dot == std::string_view::npos || last_dot == 0 || !digits_from(last_dot + 1, name.size())) {
    return std::nullopt;
  }
  const std::size_t pid_dot = name.rfind('.', last_dot - 1);
  if (pid_dot == std::string_view::npos || !digits_from(pid_dot + 1, last_dot)) return std::nullopt;
  if (!(pid_dot >= 5 && name.substr(pid_dot - 4, 4) == ".tmp" && pid_dot - 4 > 1)) return std::nullopt;
  long pid = 0;
  const auto [end, error] = std::from_chars(name.data() + pid_dot + 1, name.data() + last_dot, pid);
  if (error != std::errc() || end != name.data() + last_dot) return std::nullopt;  // beyond any process id
  return pid;
}

void remove_temporaries_on_signals() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old {};
    ::sigaction(signal, nullptr, &old);
    // A signal the parent ignores (a background job's SIGINT) stays ignored.
    if (old.sa_handler == SIG_IGN) continue;
    struct sigaction action {};
    action.sa_handler = &remove_temporaries_and_die;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
  }
}

void stop_point(const char* event) {
  // Read once: "EVENT:N:SIGNAL".
  struct Plan {
    std::string event;
    unsigned count = 0;
    int signal = 0;
  };
  static const Plan plan = [] {
    Plan p;
    const char* text = std::getenv("PURKINJE_STOP_AT");
    if (!text) return p;
    const std::string spec = text;
    const std::size_t a = spec.find(':'), b = spec.find(':', a == std::string::npos ? a : a + 1);
    if (a == std::string::npos || b == std::string::npos) return p;
    p.event = spec.substr(0, a);
    p.count = static_cast<unsigned>(std::strtoul(spec.c_str() + a + 1, nullptr, 10));
    const std::string name = spec.substr(b + 1);
    p.signal = name == "KILL" ? SIGKILL : name == "TERM" ? SIGTERM : name == "INT" ? SIGINT : 0;
    return p;
  }();
  if (plan.signal == 0 || plan.event != event) return;
  static std::atomic<unsigned> seen{0};
  if (++seen == plan.count) ::raise(plan.signal);
}

std::string unreplaceable(const std::filesystem::path& file) {
  struct stat status {};
  if (::lstat(file.c_str(), &status) != 0) return {};  // absent (or unreachable: the write will say)
  if (S_ISREG(status.st_mode)) return {};
  if (S_ISLNK(status.st_mode)) return "is a symbolic link: not replaced";
  if (S_ISDIR(status.st_mode)) return "is a folder: not replaced";
  if (S_ISCHR(status.st_mode)) return "is a character device: not replaced";
  if (S_ISBLK(status.st_mode)) return "is a block device: not replaced";
  if (S_ISFIFO(status.st_mode)) return "is a FIFO (named pipe): not replaced";
  if (S_ISSOCK(status.st_mode)) return "is a socket: not replaced";
  return "is not a regular file: not replaced";
}

void write_file_atomically(const std::filesystem::path& file, const std::string& contents) {
  auto fail = [&file](const std::string& what, int error) {
    throw std::runtime_error(file.string() + ": " + what + ": " + std::strerror(error));
  };
  if (const std::string why = unreplaceable(file); !why.empty()) throw std::runtime_error(file.string() + ": " + why);

  const std::filesystem::path directory = file.has_parent_path() ? file.parent_path() : ".";
  const std::filesystem::path temporary = create_temporary(file);
  int fd = ::open(temporary.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  auto abandon = [&](const std::string& what) {
    const int error = errno;
    if (fd >= 0) ::close(fd);
    ::unlink(temporary.c_str());
    release_temporary(temporary);
    fail(what, error);
  };
  if (fd < 0) abandon("cannot open a temporary file");
  const char* data = contents.data();
  std::size_t left = contents.size();
  while (left > 0) {
    const ssize_t written = ::write(fd, data, left);
    if (written < 0) {
      if (errno == EINTR) continue;
      abandon("cannot write");
    }
    data += written;
    left -= static_cast<std::size_t>(written);
  }
  if (::fsync(fd) != 0) abandon("cannot flush to disk");
  const int closed = ::close(fd);
  fd = -1;
  if (closed != 0) abandon("cannot close");
  stop_point("temporary_written");
  if (::rename(temporary.c_str(), file.c_str()) != 0) abandon("cannot replace");
  release_temporary(temporary);
  // Make the rename itself durable; a failure here loses nothing written.
  if (const int dir = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dir >= 0) {
    ::fsync(dir);
    ::close(dir);
  }
}

}  // namespace purkinje
