#pragma once
// Checks every command makes of its outputs before any work: an output
// is never one of the command's inputs, never a device, FIFO or socket
// (as root, rename() would replace /dev/full with a regular file), and
// an output folder is never an existing file. A refusal is a message for
// stderr and an exit code; nothing has been written.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace purkinje::tools {

// The command line's exit codes (docs/cli.md).
enum ExitCode : int { kOk = 0, kBadInput = 1, kUsageError = 2, kOutputError = 3 };

struct Refusal {
  int exit_code;        // kUsageError: an output is an input; kOutputError: it cannot be written
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

// Whether two paths name the same existing file or folder.
bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

}  // namespace purkinje::tools
