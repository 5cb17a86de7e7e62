#pragma once
// Reading an input file whole, with a type check and a size limit: a
// scene, mesh, labels or detections file that is a FIFO, a device such as
// /dev/zero, or larger than any real one of its kind is refused with a
// message instead of blocking forever or filling the memory.

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace purkinje {

// Limits per kind of file: far above any real one, far below the memory.
inline constexpr std::uintmax_t kMaxSceneFileBytes = std::uintmax_t{64} << 20;
inline constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t{512} << 20;
inline constexpr std::uintmax_t kMaxLabelsFileBytes = std::uintmax_t{64} << 20;
inline constexpr std::uintmax_t kMaxDetectionsFileBytes = std::uintmax_t{1} << 30;
inline constexpr std::uintmax_t kMaxImageFileBytes = std::uintmax_t{1} << 30;

// what(): "FILE: reason"; reason() alone for messages that name the file
// their own way.
class InputFileError : public std::runtime_error {
 public:
  InputFileError(const std::filesystem::path& file, std::string reason)
      : std::runtime_error(file.string() + ": " + reason), reason_(std::move(reason)) {}
  const std::string& reason() const { return reason_; }

 private:
  std::string reason_;
};

// Why `file` cannot be read as a regular file of at most `max_bytes`
// ("no such file", "is a FIFO (named pipe), not a scene file", "is 2.1 GB,
// more than the 64 MB a scene file may have"), or empty when it can.
// `kind` names the file's kind ("a scene file"). Reads none of its contents.
std::string unreadable_input(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view kind);

// The whole contents of a regular file of at most `max_bytes`. Never
// blocks on a FIFO and never reads more than max_bytes + 64 KB (files in
// /proc report no size). Throws InputFileError.
std::string read_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view kind);

// A file's size and CRC-32 (zlib's): what a labels file records of its
// image files, so that a reader tells a complete unit from a stale or
// partly replaced one (an interrupted run's new PNG beside old labels).
struct FileCheck {
  std::uintmax_t bytes = 0;
  std::uint32_t crc32 = 0;
  bool operator==(const FileCheck&) const = default;
};
FileCheck file_check_of(std::string_view contents);
// The same of a regular file, read in pieces and of any size (outputs of
// our own are checked, not limited). Throws InputFileError.
FileCheck file_check_of_file(const std::filesystem::path& file);
// The CRC as labels write it: eight lower-case hexadecimal digits.
std::string crc32_text(std::uint32_t crc32);

}  // namespace purkinje
