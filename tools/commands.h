#pragma once
// The subcommands that read images and score detectors (`purkinje track`,
// `purkinje score`): argument parsing stays in purkinje.cpp.

#include <string>
#include <vector>

namespace purkinje::tools {

enum ExitCode : int { kOk = 0, kBadInput = 1, kUsageError = 2, kOutputError = 3 };

struct ScoreOutput {
  std::vector<std::string> inputs;  // labels files, images beside their labels, or folders of them
  std::string output_dir;
  int overlays = 10;               // the worst this many images, drawn
  double match_radius_px = 5;
};

struct TrackRequest : ScoreOutput {
  std::string scene_file;  // the tracker's rig and nominal eye, for glint identity (empty: none)
};

struct ScoreRequest : ScoreOutput {
  std::string detections_file;
};

int run_track(const TrackRequest& request);
int run_score(const ScoreRequest& request);

}  // namespace purkinje::tools
