#pragma once
// Overall progress of a long command on stderr: "label: k/N, R per s, ETA
// m:ss". On a terminal one line, redrawn at most ten times a second and
// cleared at the end; otherwise (a log, CI) one line per step, or per
// percent beyond 100 steps. Quiet: nothing.

#include <chrono>
#include <cstddef>
#include <string>

namespace purkinje::tools {

class Progress {
 public:
  Progress(std::string label, std::size_t total, bool quiet);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  // One more step done.
  void step();

 private:
  void show(bool final_line);

  std::string label_;
  std::size_t total_;
  std::size_t done_ = 0;
  bool quiet_;
  bool terminal_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_, last_shown_;
};

}  // namespace purkinje::tools
