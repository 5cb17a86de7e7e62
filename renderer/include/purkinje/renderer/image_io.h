#pragma once
// Image files through OpenImageIO, written atomically as a set: every file
// goes to a temporary name beside its target and is renamed into place
// only when all of them were written, so a failure (unwritable folder,
// full disk) leaves no partial image or label file behind.

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/renderer/image.h"

namespace purkinje::renderer {

// A file could not be written; what() names the file and the reason.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// PNG of the sensor image: 8-bit for bits = 8, otherwise 16-bit with the
// values shifted to the most significant bits (so a 12-bit image looks
// right in any viewer; value >> (16 - bits) recovers the DN).
void write_png(const std::filesystem::path& file, const SensorImage& image);
// OpenEXR, 32-bit float, zip, one channel per plane. OpenEXR stores the
// channels sorted by name, so readers see them in that (or their own)
// order, not the given one. Planes must share one size and have distinct,
// non-empty names; NaN is rejected (infinity is kept). Both writers throw
// std::invalid_argument for bad input and OutputError when writing fails,
// and put no date or software name in the file: equal inputs give equal
// bytes.
void write_exr(const std::filesystem::path& file, const std::vector<NamedPlane>& planes);

// Reads a PNG written by write_png back (for tests and tools); DN values
// as written, before any bit shift is undone. Throws OutputError on failure.
SensorImage read_png(const std::filesystem::path& file);
// Reads every channel of an EXR file. Throws OutputError on failure.
std::vector<NamedPlane> read_exr(const std::filesystem::path& file);

// Writes several files all-or-nothing. Add each file with the function that
// writes it to a given (temporary) path; commit() runs them all to
// temporaries, then renames each into place. On any failure it removes
// every temporary (and any file it already renamed) and throws
// OutputError naming the target file and the reason.
class FileSet {
 public:
  FileSet() = default;
  // Writers may hold the set (temporary_of): it stays where it was made.
  FileSet(const FileSet&) = delete;
  FileSet& operator=(const FileSet&) = delete;
  using Writer = std::function<void(const std::filesystem::path& temporary)>;
  void add(std::filesystem::path target, Writer writer);
  // Runs the writers in the order added, then renames in that order: a
  // file added last is in place only when all the others are.
  void commit();
  // During commit(), for a writer: the temporary of a target added before
  // it, already written and flushed (labels record their images'
  // checksums from them). Throws std::logic_error otherwise.
  const std::filesystem::path& temporary_of(const std::filesystem::path& target) const;

 private:
  struct Entry {
    std::filesystem::path target;
    Writer writer;
  };
  std::vector<Entry> entries_;
  std::vector<std::filesystem::path> written_;  // during commit(): the temporaries written so far
};

}  // namespace purkinje::renderer
