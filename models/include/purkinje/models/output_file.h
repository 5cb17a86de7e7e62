#pragma once
// Writing output files so that nothing is ever lost or half written:
// every output goes to a hidden temporary beside its target, is flushed
// and renamed into place; nothing is renamed over anything but a regular
// file; temporaries are removed on failure and, once
// remove_temporaries_on_signals() is installed, on SIGINT and SIGTERM.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace purkinje {

// An output could not be written; what() names the file and the reason.
// What a caller tells apart from bad input (the command line's exit code 3).
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Writes `contents` to a temporary file in the same directory, flushes it
// to disk and renames it over `file`, so readers see the old file or the
// whole new one, never a part. Throws OutputError naming the path
// and the system's reason; no temporary file is left behind. Refuses
// (before writing anything) a `file` that unreplaceable() names.
void write_file_atomically(const std::filesystem::path& file, const std::string& contents);

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

// The bytes into `file` (created or truncated): a FileSet's writer. On
// failure removes what it wrote and throws OutputError naming `file` and
// the system's reason.
void write_bytes(const std::filesystem::path& file, std::string_view bytes);

// Creates `folder` and its parents where missing; throws OutputError
// naming it and the system's reason ("cannot create the output folder").
void create_output_folder(const std::filesystem::path& folder);

// Appends `line` to an existing file and flushes it to the disk (an index
// that grows as a long run goes). Throws OutputError naming the file.
void append_to_file(const std::filesystem::path& file, std::string_view line);

// Why an output may not be renamed over `file`: it exists and is not a
// regular file ("is a character device", for /dev/full; a FIFO, socket,
// folder or symbolic link alike). Empty when `file` is absent or a
// regular file. Run as root, rename() would replace a device node.
std::string unreplaceable(const std::filesystem::path& file);

// A new, empty, hidden temporary beside `target`, created exclusively:
// ".NAME.tmp.PID.N" in the target's folder (the same file system, so
// renaming it onto the target is atomic). It is registered for removal
// on SIGINT/SIGTERM until release_temporary(). Throws OutputError
// naming the target when the folder does not take it.
std::filesystem::path create_temporary(const std::filesystem::path& target);
// The temporary was renamed into place or removed: no longer the signal
// handler's to remove.
void release_temporary(const std::filesystem::path& temporary);
// The process that made `name` (a file name) when it is one of
// create_temporary()'s, of any process: what a resumed run may remove
// once that process is gone.
std::optional<long> temporary_owner(std::string_view name);
inline bool is_temporary_name(std::string_view name) { return temporary_owner(name).has_value(); }

// `name` with every character but letters, digits, '-', '_' and '.'
// replaced by '_': file names that every file system and shell take.
std::string portable_file_name(std::string name);

// Removes the hidden temporaries in `dir` that a dead process left: one
// whose process is gone, or whose process id is this process's own (a
// retried container's process is PID 1 again). Call it before this
// process makes a temporary in `dir`. With `own`, only the temporaries of
// the targets it accepts (by file name): another process, on another
// machine, may be writing beside them.
void remove_stale_temporaries(const std::filesystem::path& dir,
                              const std::function<bool(const std::string& target)>& own = {});

// Installs handlers for SIGINT, SIGTERM and SIGHUP (those not ignored
// already) that remove every registered temporary, then end the process by
// the signal itself, which a shell reports as 130, 143 and 129. For the
// command line; a library leaves signals to its host.
void remove_temporaries_on_signals();

// A point where a test may stop the process, as a kill at that moment
// would: when PURKINJE_STOP_AT is "EVENT:N:SIGNAL" (e.g. "renamed:7:KILL",
// "temporary_written:3:TERM") the N-th call with that event raises the
// signal. Unset, it costs a load and a comparison.
void stop_point(const char* event);

}  // namespace purkinje
