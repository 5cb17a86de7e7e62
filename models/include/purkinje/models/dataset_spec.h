#pragma once
// Dataset specs: a base scene and how each image of a labelled set varies
// it (JSON with comments, format version 1, every key in
// docs/dataset-format.md). Each drawn value is a function of the spec's
// seed, the image's index and the parameter's name alone (counter-based),
// so any subset of a set's images (a shard) is drawn, and rendered,
// exactly as the whole set draws it. Errors name the file, the key path,
// the value and the rule, as the scene reader's do:
//   remote.json: parameters.pupil_radius_mm.uniform = [4, 1]: the low end must not exceed the high one

#include <cstdint>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/scene.h"

namespace purkinje {

class DatasetSpecError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr int kDatasetFormatVersion = 1;

// How one parameter is drawn for each image. Booleans are 0 and 1,
// integers exact.
struct Distribution {
  enum class Kind {
    fixed,    // values[0]
    uniform,  // [low, high]; for integers every integer in it equally likely
    normal,   // mean, sd, truncated to [low, high] (by the inverse CDF: no rejection loop)
    choice,   // one of values, with relative weights (empty: equal)
    grid,     // values in turn: the grid parameters of a spec form a product (dataset-format.md)
    cap,      // a gaze turn (deg) uniform over the spherical cap [low, high]: cos uniform
  };
  Kind kind = Kind::fixed;
  std::vector<double> values;
  std::vector<double> weights;
  double low = 0, high = 0;
  double mean = 0, sd = 0;
};

enum class ParameterType { real, integer, boolean };

// A parameter the spec varies. Its name is its column in the set's table
// and its key in each image's labels, with its unit in the name:
// "pupil_radius_mm", "illuminator.led_left.on", "mesh.glasses.on".
struct VariedParameter {
  std::string name;
  ParameterType type = ParameterType::real;
  Distribution distribution;
};

// Which files each image gets besides its labels (always written).
struct DatasetOutputs {
  bool image = true;         // the sensor image, PNG (8-bit for an 8-bit sensor, else 16)
  bool segmentation = true;  // pixel classes, indexed PNG
  bool exr = false;
  std::vector<std::string> exr_planes;  // empty: every plane
  bool exr_half = true;                 // half floats; false: 32-bit
  std::string exr_compression = "rle";  // an OpenEXR codec; rle: lossless, the fastest (docs/benchmarks.md)
};

struct DatasetSpec {
  std::string name;  // file stems: "<name>_<index>_<camera>"
  std::filesystem::path scene_file;
  Scene scene;
  std::uint64_t count = 0;
  std::uint64_t seed = 1;
  std::string camera;  // empty: every camera of the scene
  int samples_per_pixel = 1;
  int edge_samples_per_pixel = 16;
  DatasetOutputs outputs;
  std::vector<VariedParameter> parameters;  // the table's column order
  // As read, for the set's hash (the scene's text is the one parsed: an
  // edit while shards start cannot slip past it), and the spec's name in
  // messages.
  std::string text, scene_text;
  std::string source;
};

// Reads and validates a spec and the scene it names (relative to the
// spec's folder). Throws DatasetSpecError (SceneError's message for a bad
// scene).
DatasetSpec load_dataset_spec(const std::filesystem::path& file);
DatasetSpec parse_dataset_spec(const std::string& text, const std::string& source_name,
                               const std::filesystem::path& folder = {});

// The parameters every spec may vary, with their units: what
// docs/dataset-format.md documents ("illuminator.NAME.on" and the like
// stand for one per illuminator or mesh of the scene).
std::vector<std::string> dataset_parameter_names();

// One image's draws: values parallel to spec.parameters.
struct ImageDraw {
  std::uint64_t index = 0;
  std::uint64_t seed = 0;  // the renderer's (jitter and noise), drawn as the parameters are
  std::vector<double> values;
};

ImageDraw draw_image(const DatasetSpec& spec, std::uint64_t index);

// The spec's scene as image `draw` varies it. Throws DatasetSpecError
// naming the spec, the image and the drawn values for a combination that
// no eye can have (a pupil beyond its iris, a cornea whose cap does not
// reach the limbus, a target too close to fixate).
Scene scene_for_image(const DatasetSpec& spec, const ImageDraw& draw);

// The inverse of the standard normal CDF, to full double precision.
double inverse_normal_cdf(double p);

}  // namespace purkinje
