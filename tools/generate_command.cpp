// `purkinje generate`: a labelled data set from a dataset spec, whole or
// one shard of it; `purkinje merge`: the shards' tables and manifests
// joined (studies/generate.h). Documented in docs/cli.md and
// docs/datasets.md.

#include <charconv>
#include <iostream>
#include <memory>
#include <string>

#include "cli.h"
#include "progress.h"
#include "purkinje/studies/generate.h"

namespace purkinje::tools {
namespace {

struct GenerateOptions {
  studies::GenerateRequest request;
  std::string shard;  // "i/N"
  std::uint64_t count = 0;  // 0: the spec's
  bool quiet = false;
};

// "i/N" with 0 <= i < N.
studies::Shard parse_shard(const std::string& text) {
  const auto slash = text.find('/');
  studies::Shard shard;
  const auto number = [&](std::string_view s, std::uint64_t& out) {
    const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), out);
    return error == std::errc() && end == s.data() + s.size() && !s.empty();
  };
  const std::string_view view(text);
  if (slash == std::string::npos || !number(view.substr(0, slash), shard.index) ||
      !number(view.substr(slash + 1), shard.count) || shard.count < 1 || shard.index >= shard.count) {
    throw CommandError(kUsageError, "--shard " + text + ": must be I/N with 0 <= I < N (as Slurm's "
                                    "$SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT for an array 0-(N-1))");
  }
  return shard;
}

int run_generate(GenerateOptions& o) {
  studies::GenerateRequest& request = o.request;
  if (!o.shard.empty()) request.shard = parse_shard(o.shard);
  if (o.count > 0) request.count = o.count;
  const studies::GeneratePlan plan = studies::plan_generate(request);
  refuse(check_output_folder(request.output_dir, {}, studies::generate_outputs(plan),
                             {request.spec_file, plan.spec.scene_file}));
  Progress progress("generate", plan.images.size(), o.quiet);
  studies::GenerateHooks hooks;
  hooks.image_done = [&] { progress.step(); };
  const studies::GenerateOutcome outcome = studies::generate(plan, hooks);
  std::cout << "generated " << outcome.rendered << " images";
  if (request.resume) std::cout << " (" << outcome.resumed << " complete ones kept)";
  std::cout << " of " << plan.images.size() << (request.shard.count > 1 ? " in this shard" : "") << "\n";
  std::cout << "wrote " << outcome.table.string() << ", " << outcome.manifest.filename().string() << "\n";
  return kOk;
}

}  // namespace

Command add_generate_command(CLI::App& app) {
  auto o = std::make_shared<GenerateOptions>();
  CLI::App* generate = app.add_subcommand("generate", "Render a labelled data set from a dataset spec");
  generate->footer(std::string("Writes each image's files (DIR/<name>_<index>_<camera>.png, _classes.png,\n"
                               ".exr and .json, as the spec's outputs say), then table.csv (one row per\n"
                               "image) and manifest.json; a shard writes table.shard-I-of-N.csv and\n"
                               "manifest.shard-I-of-N.json, which `purkinje merge DIR` joins\n"
                               "(docs/datasets.md).\n\n") +
                   kExitCodes);
  generate->add_option("SPEC", o->request.spec_file, "Dataset spec (JSON, see docs/dataset-format.md)")->required();
  generate->add_option("-o,--output", o->request.output_dir, "Output folder (created if missing)")->required();
  generate->add_option("--count", o->count, "Images in the set, instead of the spec's count (for trials)")
      ->check(CLI::Range(std::uint64_t{1}, std::uint64_t{1} << 40));
  generate->add_option("--shard", o->shard,
                       "Render only shard I of N: the images I, I+N, I+2N, ... (Slurm: one array task each)");
  generate->add_flag("--resume", o->request.resume,
                     "Continue a killed run in the same folder: complete images are kept, the rest\n"
                     "rendered again (the same bytes as one run)");
  generate->add_option("--threads", o->request.threads, "Worker threads (0: all); output does not depend on it")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  generate->add_flag("--quiet", o->quiet, "No progress on standard error");
  return {generate, [o] { return run_command("generate", [&] { return run_generate(*o); }); }};
}

Command add_merge_command(CLI::App& app) {
  auto dir = std::make_shared<std::filesystem::path>();
  CLI::App* merge = app.add_subcommand("merge", "Join a data set's shard tables and manifests");
  merge->footer(std::string("Reads DIR/manifest.shard-I-of-N.json and table.shard-I-of-N.csv of every\n"
                            "shard, checks they are the N shards of one set, and writes table.csv and\n"
                            "manifest.json: the bytes an unsharded run writes (docs/datasets.md).\n\n") +
                kExitCodes);
  merge->add_option("DIR", *dir, "The data set's folder, where its shards wrote")->required();
  return {merge, [dir] {
            return run_command("merge", [&] {
              const studies::MergeOutcome outcome = studies::merge_shards(*dir);
              std::cout << "merged " << outcome.shards << " shards, " << outcome.rows << " rows: wrote "
                        << outcome.table.string() << ", " << outcome.manifest.filename().string() << "\n";
              return kOk;
            });
          }};
}

}  // namespace purkinje::tools
