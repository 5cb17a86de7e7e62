// The compare study's files: see compare.h.

#include <algorithm>
#include <string>
#include <vector>

#include "purkinje/models/output_file.h"
#include "purkinje/studies/compare.h"
#include "purkinje/studies/output_checks.h"

namespace purkinje::studies {

std::vector<std::string> compare_outputs() {
  return {"displacements.csv", "gaze.csv",          "summary.txt",     "summary.json", "summary.csv",
          "world.png",         "world.exr",         "world.json",      "assumed.png",  "assumed.exr",
          "assumed.json",      "displacements.png", "gaze_change.png", "gaze_error.png", "images.png", "flip.gif",
          "figures.json",      "index.md"};
}

namespace {

// Removes every one of `outputs` in `dir` that is not `written`: a rerun
// leaves no file of the last run beside its own, figures included (drawn
// anew from these files, or not at all).
void remove_unwritten(const std::filesystem::path& dir, const std::vector<std::string>& outputs,
                      const std::vector<std::string>& written) {
  std::vector<std::string> stale;
  for (const std::string& name : outputs) {
    if (std::find(written.begin(), written.end(), name) == written.end()) stale.push_back(name);
  }
  remove_stale_outputs(dir, stale);
}

}  // namespace

void write_compare(const std::filesystem::path& dir, const Scene& world, const Scene& assumed,
                   const CompareStudy& study, const CompareStudySettings& settings) {
  create_output_folder(dir);
  FileSet files;
  std::vector<std::string> written;
  const auto add_text = [&](const std::string& name, const std::string& content) {
    files.add(dir / name, [content](const std::filesystem::path& temporary) { write_bytes(temporary, content); });
    written.push_back(name);
  };
  add_text("displacements.csv", displacement_csv(study.field));
  if (!study.gaze.empty()) add_text("gaze.csv", gaze_change_csv(study.gaze));
  if (study.world_image && study.assumed_image) {
    for (const renderer::RenderFiles& image :
         {renderer::add_render(files, dir, "world", world, *study.world_image, settings.render),
          renderer::add_render(files, dir, "assumed", assumed, *study.assumed_image, settings.render)}) {
      for (const std::filesystem::path& file : {image.image, image.exr, image.labels, image.segmentation}) {
        if (!file.empty()) written.push_back(file.filename().string());
      }
    }
  }
  add_text("summary.json", simulation_json(study.summary));
  add_text("summary.csv", simulation_csv(study.summary));
  add_text("summary.txt", simulation_text(study.summary));  // last: in place only when all the others are
  files.commit();
  remove_unwritten(dir, compare_outputs(), written);
}

std::vector<std::string> sweep_outputs() { return {"sweep.csv", "sweep.json", "sweep.png", "figures.json", "index.md"}; }

void write_sweep(const std::filesystem::path& dir, const Sweep& sweep) {
  create_output_folder(dir);
  FileSet files;
  const std::string csv = sweep_csv(sweep), json = sweep_json(sweep);
  files.add(dir / "sweep.csv", [csv](const std::filesystem::path& temporary) { write_bytes(temporary, csv); });
  files.add(dir / "sweep.json", [json](const std::filesystem::path& temporary) { write_bytes(temporary, json); });
  files.commit();
  remove_unwritten(dir, sweep_outputs(), {"sweep.csv", "sweep.json"});
}

}  // namespace purkinje::studies
