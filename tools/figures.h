#pragma once
// The figures of `calibrate` and `compare` are drawn by the Python
// package's purkinje.figures (matplotlib) from the files the command has
// written: this runs it. docs/compare.md says why matplotlib.

#include <filesystem>
#include <optional>
#include <string>

namespace purkinje::tools {

// Runs `python3 -m purkinje.figures STUDY FOLDER` with the package this
// build made first on PYTHONPATH (an installed one otherwise). Returns why
// no figures were drawn, for a build without the Python package; throws
// std::runtime_error when the drawing fails (its messages on stderr).
std::optional<std::string> draw_figures(const std::string& study, const std::filesystem::path& folder);

// A command's figures: none with --no-figures (`skip`; then "--no-figures"
// is why), else draw_figures as an output step (its failure an
// OutputError, exit code 3).
std::optional<std::string> draw_figures_unless(bool skip, const std::string& study,
                                               const std::filesystem::path& folder);

}  // namespace purkinje::tools
