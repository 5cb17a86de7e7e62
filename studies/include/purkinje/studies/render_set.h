#pragma once
// Rendering a scene's cameras to files, or a set of random variations of
// its eye (gaze and pupil) that a killed run can resume: what `purkinje
// render` does, callable from any front end. Every unit (a scene's cameras,
// or one variation's) is written all or nothing, its labels last with
// their images' checks; a set's index (variations.csv) grows a line per
// finished unit. Documented in docs/cli.md and docs/labels.md.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/eye_variation.h"
#include "purkinje/models/scene.h"
#include "purkinje/renderer/render.h"

namespace purkinje::studies {

struct RenderSetRequest {
  std::string scene_file;
  std::filesystem::path output_dir;
  std::string camera;               // empty: every camera
  renderer::RenderOptions options;  // a set's variation k renders with seed options.seed + k
  int variations = 0;               // 0: the scene as it is
  std::uint64_t variation_seed = 1;
  EyeVariationRange variation_range;
  bool resume = false;  // continue a killed set in the same folder
};

// A request read and checked before anything is written: its scene, the
// cameras it renders and the variations it draws.
struct RenderPlan {
  RenderSetRequest request;
  Scene scene;
  std::vector<int> cameras;
  std::vector<EyeVariation> variations;  // empty: the scene as it is
};

// Reads the scene and draws the variations. Throws (naming the file, the
// option and the rule) for a bad scene, a camera it lacks, variations of a
// scene without an eye, or a bad Embree configuration.
RenderPlan plan_render_set(const RenderSetRequest& request);

// Every file name the plan writes in its folder: checked before the run,
// since a folder or FIFO in the way would otherwise stop a set after hours.
std::vector<std::string> render_set_outputs(const RenderPlan& plan);

// The folder holds a set this request cannot continue: an index that is not
// a set's, or lines drawn with other options.
class ResumeRefused : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct RenderSetHooks {
  // A single scene's render: progress of each camera (from worker
  // threads, possibly out of order), then its end.
  std::function<void(const std::string& camera, double fraction)> camera_progress;
  std::function<void()> camera_done;
  std::function<void()> unit_done;                        // a set: one more variation in place
  std::function<void(const renderer::RenderFiles&)> wrote;  // a camera's files in place
};

struct RenderSetOutcome {
  std::size_t resumed = 0;             // --resume: variations found complete and kept
  std::filesystem::path index_file;    // a set's index; empty for a single scene
};

// Renders and writes the plan. Throws OutputError when a file cannot be
// written (nothing partial is left), ResumeRefused, or another exception
// for a scene the renderer refuses (naming the scene file).
RenderSetOutcome render_set(const RenderPlan& plan, const RenderSetHooks& hooks = {});

}  // namespace purkinje::studies
