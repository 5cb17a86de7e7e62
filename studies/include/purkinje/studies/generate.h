#pragma once
// Labelled data sets from a dataset spec (models/dataset_spec.h): what
// `purkinje generate` and `purkinje merge` do, callable from any front end.
//
// Image k of a set is a pure function of the spec and k (counter-based
// draws and render seed), so a shard (--shard i/N: the images i, i+N, ...)
// writes exactly the files the whole set writes for them, and merging the
// shards' tables and manifests gives the whole set's, byte for byte. Each
// image's files are written all or nothing, its labels last with their
// images' checks; a killed run continues with resume. The table (one CSV
// row per image) and the manifest are written whole at the end.
// Documented in docs/datasets.md.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "purkinje/models/dataset_spec.h"
#include "purkinje/renderer/render.h"

namespace purkinje::studies {

// Shard `index` of `count`: the images index, index + count, ...
struct Shard {
  std::uint64_t index = 0;
  std::uint64_t count = 1;
};

struct GenerateRequest {
  std::filesystem::path spec_file;
  std::filesystem::path output_dir;
  std::optional<std::uint64_t> count;  // overrides the spec's (trials)
  Shard shard;
  bool resume = false;  // keep the complete images a killed run left
  int threads = 0;      // 0: every hardware thread; the bytes do not depend on it
};

// A request read and checked before anything is written: every image of
// the shard is drawn and its scene built.
struct GeneratePlan {
  GenerateRequest request;
  DatasetSpec spec;
  std::uint64_t count = 0;              // images in the whole set
  std::vector<std::uint64_t> images;    // this shard's, in order
  std::vector<int> cameras;
  renderer::RenderOptions options;      // the seed is each image's
  renderer::ImageFileChoice files;
  std::string spec_sha1;                // of the spec, its scene and meshes
  std::string table_file, manifest_file;  // names in the output folder
};

// Throws DatasetSpecError (naming the file, key, value and rule, or the
// image whose draws no eye can have) or std::invalid_argument for a shard
// out of range or a bad Embree configuration.
GeneratePlan plan_generate(const GenerateRequest& request);

// Every file name the plan writes in its folder.
std::vector<std::string> generate_outputs(const GeneratePlan& plan);

struct GenerateHooks {
  std::function<void()> image_done;  // one more image (all its cameras) in place or kept
};

struct GenerateOutcome {
  std::uint64_t rendered = 0, resumed = 0;
  std::filesystem::path table, manifest;
};

// Renders and writes the plan. Throws OutputError when a file cannot be
// written (nothing partial is left: each image's files are all or
// nothing), ResumeRefused (render_set.h) when the folder holds another
// set's images under this set's names, and std::invalid_argument naming
// the spec and the image for a scene the renderer refuses.
GenerateOutcome generate(const GeneratePlan& plan, const GenerateHooks& hooks = {});

// The file names shard `shard` gives its table and manifest; the whole
// set's are table.csv and manifest.json.
std::string table_file_name(const Shard& shard);
std::string manifest_file_name(const Shard& shard);

struct MergeOutcome {
  std::uint64_t shards = 0, rows = 0;
  std::filesystem::path table, manifest;
};

// Joins the shard tables and manifests in `dir` (all N shards of one set,
// written by generate --shard i/N into that folder) into table.csv and
// manifest.json, byte-identical to an unsharded run's. Throws
// std::runtime_error naming the file and the rule for a missing shard,
// shards of different sets, or a table whose checksum is not its
// manifest's; OutputError when writing fails.
MergeOutcome merge_shards(const std::filesystem::path& dir);

}  // namespace purkinje::studies
