#include "purkinje/models/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace purkinje {

namespace {

std::string bytes_text(std::uintmax_t bytes) {
  std::ostringstream s;
  s << std::setprecision(3);
  if (bytes >= (std::uintmax_t{1} << 30)) s << static_cast<double>(bytes) / (1 << 30) << " GB";
  else if (bytes >= (std::uintmax_t{1} << 20)) s << static_cast<double>(bytes) / (1 << 20) << " MB";
  else s << bytes << " bytes";
  return s.str();
}

// What a file of this mode is, when it is not a regular file.
const char* not_regular(mode_t mode) {
  if (S_ISDIR(mode)) return "is a directory";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe)";
  if (S_ISCHR(mode)) return "is a character device";
  if (S_ISBLK(mode)) return "is a block device";
  if (S_ISSOCK(mode)) return "is a socket";
  return S_ISREG(mode) ? nullptr : "is not a regular file";
}

std::string too_large(std::uintmax_t size, std::uintmax_t max_bytes, std::string_view kind) {
  std::string rule = "is " + bytes_text(size) + ", more than the " + bytes_text(max_bytes) + " ";
  rule += kind;
  return rule + " may have";
}

std::string reason(int fd, std::uintmax_t max_bytes, std::string_view kind) {
  struct stat status {};
  if (::fstat(fd, &status) != 0) return std::string("cannot be examined: ") + std::strerror(errno);
  if (const char* what = not_regular(status.st_mode)) return std::string(what) + ", not " + std::string(kind);
  if (static_cast<std::uintmax_t>(status.st_size) > max_bytes) {
    return too_large(static_cast<std::uintmax_t>(status.st_size), max_bytes, kind);
  }
  return {};
}

// Opens without blocking (a FIFO with no writer would block open()).
int open_input(const std::filesystem::path& file, std::string& why) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int error = errno;
    why = error == ENOENT ? "no such file" : std::string("cannot be opened: ") + std::strerror(error);
  }
  return fd;
}

}  // namespace

std::string unreadable_input(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view kind) {
  std::string why;
  const int fd = open_input(file, why);
  if (fd < 0) return why;
  why = reason(fd, max_bytes, kind);
  ::close(fd);
  return why;
}

std::string read_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view kind) {
  const auto fail = [&](const std::string& why) { throw InputFileError(file, why); };
  std::string why;
  const int fd = open_input(file, why);
  if (fd < 0) fail(why);
  why = reason(fd, max_bytes, kind);
  if (!why.empty()) {
    ::close(fd);
    fail(why);
  }
  // A regular file: reads do not block, O_NONBLOCK or not.
  std::string contents;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      ::close(fd);
      fail(std::string("cannot be read: ") + std::strerror(error));
    }
    if (got == 0) break;
    contents.append(buffer, static_cast<std::size_t>(got));
    if (contents.size() > max_bytes) {
      ::close(fd);
      std::string rule = "holds more than the " + bytes_text(max_bytes) + " ";
      rule += kind;
      fail(rule + " may have");
    }
  }
  ::close(fd);
  return contents;
}

FileCheck file_check_of(std::string_view contents) {
  // zlib's crc32 takes at most 4 GB per call (uInt lengths).
  uLong crc = ::crc32(0L, Z_NULL, 0);
  std::size_t at = 0;
  while (at < contents.size()) {
    const std::size_t n = std::min<std::size_t>(contents.size() - at, std::size_t{1} << 30);
    crc = ::crc32(crc, reinterpret_cast<const Bytef*>(contents.data() + at), static_cast<uInt>(n));
    at += n;
  }
  return {contents.size(), static_cast<std::uint32_t>(crc)};
}

FileCheck file_check_of_file(const std::filesystem::path& file) {
  std::string why;
  const int fd = open_input(file, why);
  if (fd < 0) throw InputFileError(file, why);
  why = reason(fd, std::numeric_limits<std::uintmax_t>::max(), "a file");
  if (!why.empty()) {
    ::close(fd);
    throw InputFileError(file, why);
  }
  uLong crc = ::crc32(0L, Z_NULL, 0);
  FileCheck check;
  unsigned char buffer[1 << 16];
  for (;;) {
    const ssize_t got = ::read(fd, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      const int error = errno;
      ::close(fd);
      throw InputFileError(file, std::string("cannot be read: ") + std::strerror(error));
    }
    if (got == 0) break;
    crc = ::crc32(crc, buffer, static_cast<uInt>(got));
    check.bytes += static_cast<std::uintmax_t>(got);
  }
  ::close(fd);
  check.crc32 = static_cast<std::uint32_t>(crc);
  return check;
}

std::string crc32_text(std::uint32_t crc32) {
  char text[9];
  std::snprintf(text, sizeof text, "%08x", crc32);
  return text;
}

}  // namespace purkinje
