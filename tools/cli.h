#pragma once
// What every subcommand shares: exit codes, the number validators, the
// one place where what a command throws becomes a message and an exit
// code, and the subcommands' registration. Each command's file parses its
// options into a request and calls a study (studies/); no study logic
// lives here. Documented in docs/cli.md.

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "purkinje/studies/output_checks.h"

namespace purkinje::tools {

// The command line's exit codes (docs/cli.md), and their text for every
// command's --help.
enum ExitCode : int { kOk = 0, kBadInput = 1, kUsageError = 2, kOutputError = 3 };
extern const char* const kExitCodes;

using studies::Refusal;
using studies::check_output_file;
using studies::check_output_folder;

// CLI11's Range lets NaN through (every comparison with it is false), and
// its unsigned conversion reads "-1" as 2^64 - 1: numbers are checked as
// text first.
extern const CLI::Validator kFinite;
extern const CLI::Validator kSeed;

// A refusal with its own exit code: an output check's, or options that
// contradict each other.
class CommandError : public std::runtime_error {
 public:
  CommandError(int exit_code, const std::string& message) : std::runtime_error(message), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

// Throws CommandError when there is a refusal.
void refuse(const std::optional<Refusal>& refusal);

// Runs an output step: whatever it throws is an OutputError (exit code 3).
void writing(const std::function<void()>& write);

// Runs a command's body. What it throws goes to stderr as "purkinje NAME:
// error: WHAT" and becomes the exit code: CommandError's own, 2 for a
// refused --resume, 3 for an OutputError, 1 for anything else (bad input).
int run_command(const std::string& name, const std::function<int()>& body);

// A subcommand registered with its options; `run` is called when it is
// the one given.
struct Command {
  CLI::App* app;
  std::function<int()> run;
};

Command add_truth_command(CLI::App& app);
Command add_render_command(CLI::App& app);
Command add_track_command(CLI::App& app);
Command add_score_command(CLI::App& app);
Command add_calibrate_command(CLI::App& app);
Command add_compare_command(CLI::App& app);
Command add_generate_command(CLI::App& app);
Command add_merge_command(CLI::App& app);

}  // namespace purkinje::tools
