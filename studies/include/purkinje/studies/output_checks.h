#pragma once
// Checks every front end (the command line, the Python package) makes of
// its outputs before any work: an output is never one of its inputs,
// never a device, FIFO or socket (as root, rename() would replace
// /dev/full with a regular file), and an output folder is never an
// existing file. A refusal is a message and its kind; nothing has been
// written. Messages name the output as the command line's -o.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace purkinje::studies {

struct Refusal {
  enum class Kind {
    input,   // an output is an input (a usage error)
    output,  // an output cannot be written there
  };
  Kind kind;
  std::string message;  // names the option, the path and the rule
};

// An output file: refused when it is one of `inputs` (the same file, by
// any path) or exists and is not a regular file.
std::optional<Refusal> check_output_file(const std::filesystem::path& file, const std::vector<std::filesystem::path>& inputs);

// An output folder: refused when it exists and is not a folder, when it is
// one of `input_folders` (its files would join the inputs a later run
// reads), or when one of the `files` the command writes in it is one of
// `inputs` or is not a regular file.
std::optional<Refusal> check_output_folder(const std::filesystem::path& folder,
                                           const std::vector<std::filesystem::path>& input_folders,
                                           const std::vector<std::string>& files,
                                           const std::vector<std::filesystem::path>& inputs);

// Removes those of `files` in `folder` that a run did not write (a
// rerun with fewer outputs must not leave the last run's beside its own,
// e.g. figures drawn from other data). Throws OutputError naming the
// file when one cannot be removed.
void remove_stale_outputs(const std::filesystem::path& folder, const std::vector<std::string>& files);

// Whether two paths name the same existing file or folder.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace purkinje::studies
