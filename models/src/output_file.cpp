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
#include <utility>
#include <system_error>
#include <set>

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
      throw OutputError(target.string() + ": cannot create a temporary file: " + std::strerror(errno));
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

std::string portable_file_name(std::string name) {
  for (char& c : name) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
                    c == '_' || c == '.';
    if (!ok) c = '_';
  }
  return name;
}

void remove_stale_temporaries(const std::filesystem::path& dir,
                              const std::function<bool(const std::string& target)>& own) {
  std::error_code ec;  // an unreachable folder is the writes' to report
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const std::optional<long> pid = temporary_owner(name);
    if (!pid || *pid <= 0) continue;
    if (own && !own(name.substr(1, name.rfind(".tmp.") - 1))) continue;
    const bool gone = *pid == static_cast<long>(::getpid()) ||
                      (::kill(static_cast<pid_t>(*pid), 0) != 0 && errno == ESRCH);
    if (gone) std::filesystem::remove(e.path(), ec);
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

namespace {

std::string errno_message(int error) { return std::generic_category().message(error); }

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& reason) {
  throw OutputError(file.string() + ": " + reason);
}

// Writes all of `bytes` to an open descriptor; false with errno set when
// the system refuses.
bool write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t written = ::write(fd, bytes.data(), bytes.size());
    if (written < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    bytes.remove_prefix(static_cast<std::size_t>(written));
  }
  return true;
}

}  // namespace

void write_bytes(const std::filesystem::path& file, std::string_view bytes) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) fail(file, "cannot write: " + errno_message(errno));
  auto abandon = [&](int error) {
    ::unlink(file.c_str());
    fail(file, "cannot write: " + errno_message(error));
  };
  if (!write_all(fd, bytes)) {
    const int error = errno;
    ::close(fd);
    abandon(error);
  }
  // close() reports delayed write errors on some file systems (NFS).
  if (::close(fd) != 0) abandon(errno);
}

void create_output_folder(const std::filesystem::path& folder) {
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) throw OutputError(folder.string() + ": cannot create the output folder: " + ec.message());
}

void append_to_file(const std::filesystem::path& file, std::string_view line) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (fd < 0) fail(file, std::string("cannot append: ") + errno_message(errno));
  if (!write_all(fd, line) || ::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(file, "cannot append: " + errno_message(error));
  }
  ::close(fd);
}

namespace {

std::filesystem::path directory_of(const std::filesystem::path& target) {
  return target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
}

std::string directory_label(const std::filesystem::path& directory) {
  std::string label = directory.string();
  if (label.empty() || label.back() != '/') label += '/';
  return label;
}

void check_directory(const std::filesystem::path& target) {
  const std::filesystem::path directory = directory_of(target);
  std::error_code error;
  const auto status = std::filesystem::status(directory, error);
  const std::string folder = "cannot write: the folder " + directory_label(directory);
  if (status.type() == std::filesystem::file_type::not_found) fail(target, folder + " does not exist");
  if (error) fail(target, folder + " cannot be reached: " + error.message());
  if (status.type() != std::filesystem::file_type::directory) fail(target, folder + " is not a folder");
}

// Flushes a finished temporary to the disk: a full or failing device may
// only report at this point.
void flush_to_disk(const std::filesystem::path& temporary, const std::filesystem::path& target) {
  struct stat info {};
  if (::stat(temporary.c_str(), &info) != 0 || !S_ISREG(info.st_mode))
    fail(target, "the writer left no file");
  const int fd = ::open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) fail(target, "cannot write: " + errno_message(errno));
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(target, "cannot write: " + errno_message(error));
  }
  ::close(fd);
}

// A writer's message names the temporary, which means nothing to the
// user; the target is named instead.
std::string reason_from(const std::string& what, const std::filesystem::path& temporary) {
  const std::string prefix = temporary.string() + ": ";
  if (what.compare(0, prefix.size(), prefix) == 0) return what.substr(prefix.size());
  return what;
}

}  // namespace

const std::filesystem::path& FileSet::temporary_of(const std::filesystem::path& target) const {
  for (std::size_t i = 0; i < written_.size(); ++i) {
    if (entries_[i].target == target) return written_[i];
  }
  throw std::logic_error("FileSet::temporary_of: " + target.string() + " is not written yet");
}

void FileSet::add(std::filesystem::path target, Writer writer) {
  if (!target.has_filename())
    throw OutputError(target.string() + ": names a folder, not a file");
  if (!writer) throw std::invalid_argument("FileSet: " + target.string() + ": no writer");
  for (const Entry& e : entries_) {
    if (e.target.lexically_normal() == target.lexically_normal())
      throw std::invalid_argument("FileSet: " + target.string() + " added twice");
  }
  entries_.push_back({std::move(target), std::move(writer)});
}

void FileSet::commit() {
  for (const Entry& e : entries_) {
    check_directory(e.target);
    if (const std::string why = unreplaceable(e.target); !why.empty()) fail(e.target, why);
  }

  std::vector<std::filesystem::path> temporaries;
  std::vector<std::filesystem::path> renamed;
  auto roll_back = [&] {
    for (const auto& t : temporaries) {
      ::unlink(t.c_str());
      release_temporary(t);
    }
    for (const auto& t : renamed) ::unlink(t.c_str());
  };

  try {
    temporaries.reserve(entries_.size());
    for (const Entry& e : entries_) {
      try {
        temporaries.push_back(create_temporary(e.target));
      } catch (const std::exception& error) {
        fail(e.target, reason_from(error.what(), e.target));
      }
      const std::filesystem::path& temporary = temporaries.back();
      try {
        e.writer(temporary);
      } catch (const std::exception& error) {
        fail(e.target, reason_from(error.what(), temporary));
      } catch (...) {
        fail(e.target, "the writer failed with an unknown exception");
      }
      flush_to_disk(temporary, e.target);
      written_.push_back(temporary);
      stop_point("temporary_written");
    }
    for (std::size_t i = 0; i < entries_.size(); ++i) {
      if (::rename(temporaries[i].c_str(), entries_[i].target.c_str()) != 0)
        fail(entries_[i].target, "cannot rename into place: " + errno_message(errno));
      release_temporary(temporaries[i]);
      renamed.push_back(entries_[i].target);
      stop_point("renamed");
    }
  } catch (...) {
    written_.clear();
    roll_back();
    throw;
  }
  written_.clear();

  // Make the renames durable. The set is complete and in place by now, so
  // a failure here is not reported: there is nothing left to undo.
  std::set<std::filesystem::path> directories;
  for (const Entry& e : entries_) directories.insert(directory_of(e.target));
  for (const auto& directory : directories) {
    const int fd = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd >= 0) {
      ::fsync(fd);
      ::close(fd);
    }
  }
}

void write_file_atomically(const std::filesystem::path& file, const std::string& contents) {
  FileSet set;
  set.add(file, [&contents](const std::filesystem::path& temporary) { write_bytes(temporary, contents); });
  set.commit();
}

}  // namespace purkinje
