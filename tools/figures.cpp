// Runs purkinje.figures: see figures.h.

#include "figures.h"

#include "cli.h"

#include <spawn.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

extern char** environ;

namespace purkinje::tools {

std::optional<std::string> draw_figures(const std::string& study, const std::filesystem::path& folder) {
#ifndef PURKINJE_PYTHON_EXECUTABLE
  (void)study, (void)folder;
  return std::string("this build has no Python package (-DPURKINJE_PYTHON=OFF), which draws them");
#else
  const std::string python = PURKINJE_PYTHON_EXECUTABLE;
  // The package this build made, before any installed one; the rest of
  // the environment as it is.
  std::vector<std::string> environment;
  std::string python_path;
  if (std::filesystem::exists(std::filesystem::path(PURKINJE_PYTHON_PACKAGE_DIR) / "purkinje")) {
    python_path = PURKINJE_PYTHON_PACKAGE_DIR;
  }
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry = *e;
    if (entry.starts_with("PYTHONPATH=")) {
      const std::string given = entry.substr(11);
      if (!given.empty()) python_path += (python_path.empty() ? "" : ":") + given;
    } else {
      environment.push_back(entry);
    }
  }
  if (!python_path.empty()) environment.push_back("PYTHONPATH=" + python_path);
  std::vector<std::string> arguments = {python, "-m", "purkinje.figures", study, folder.string()};
  std::vector<char*> argv, envp;
  for (std::string& a : arguments) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : environment) envp.push_back(e.data());
  envp.push_back(nullptr);
  pid_t child = 0;
  const std::string command = python + " -m purkinje.figures " + study + " " + folder.string();
  if (const int error = posix_spawn(&child, python.c_str(), nullptr, nullptr, argv.data(), envp.data())) {
    throw std::runtime_error("figures: cannot run " + python + ": " + std::strerror(error));
  }
  int status = 0;
  while (waitpid(child, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("figures: waiting for `" + command + "`: " + std::strerror(errno));
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("figures: `" + command + "` failed (" +
                             (WIFEXITED(status) ? "exit code " + std::to_string(WEXITSTATUS(status))
                                                : std::string("killed by a signal")) +
                             ", its messages above); the data files are written, the figures not all. They "
                             "need Debian's python3-matplotlib, python3-pandas and python3-pil (scripts/install-deps)");
  }
  return std::nullopt;
#endif
}

std::optional<std::string> draw_figures_unless(bool skip, const std::string& study,
                                               const std::filesystem::path& folder) {
  if (skip) return std::string("--no-figures");
  std::optional<std::string> not_drawn;
  writing([&] { not_drawn = draw_figures(study, folder); });
  return not_drawn;
}

}  // namespace purkinje::tools
