// The extension module purkinje._files: image files and data sets, which
// need OpenImageIO (bindings.h says why it is a module of its own).

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "purkinje/models/dataset_spec.h"
#include "purkinje/models/output_file.h"
#include "purkinje/renderer/image_io.h"
#include "purkinje/studies/generate.h"
#include "purkinje/studies/image_set.h"
#include "purkinje/studies/output_checks.h"
#include "purkinje/studies/track.h"

namespace purkinje::python {
namespace {

py::dict files_dict(const renderer::RenderFiles& f) {
  py::dict d;
  for (const auto& [key, path] : {std::pair{"image", &f.image}, std::pair{"exr", &f.exr},
                                  std::pair{"segmentation", &f.segmentation}, std::pair{"labels", &f.labels}}) {
    if (!path->empty()) d[key] = *path;
  }
  return d;
}

// A refusal as the command line makes it: an output that is an input is
// bad input (ValueError), one that cannot be written an OutputError.
void raise_refusal(const std::optional<studies::Refusal>& refusal) {
  if (!refusal) return;
  if (refusal->kind == studies::Refusal::Kind::input) throw std::invalid_argument(refusal->message);
  throw OutputError(refusal->message);
}

py::dict generate(const std::filesystem::path& spec_file, const std::filesystem::path& output_dir,
                  std::optional<std::uint64_t> count, std::uint64_t shard_index, std::uint64_t shard_count,
                  bool resume, int threads, const py::object& progress) {
  studies::GenerateRequest request;
  request.spec_file = spec_file;
  request.output_dir = output_dir;
  request.count = count;
  request.shard = {shard_index, shard_count};
  request.resume = resume;
  request.threads = threads;
  studies::GeneratePlan plan;
  try {
    plan = studies::plan_generate(request);
  } catch (const DatasetSpecError& error) {
    raise_if_missing(spec_file, error.what());
    throw;
  }
  raise_refusal(studies::check_output_folder(output_dir, {}, studies::generate_outputs(plan),
                                             {spec_file, plan.spec.scene_file}));
  studies::GenerateHooks hooks;
  hooks.image_done = progress_step(progress, plan.images.size());
  studies::GenerateOutcome outcome;
  {
    py::gil_scoped_release release;
    outcome = studies::generate(plan, hooks);
  }
  py::dict out;
  out["rendered"] = outcome.rendered;
  out["resumed"] = outcome.resumed;
  out["table"] = outcome.table;
  out["manifest"] = outcome.manifest;
  return out;
}

}  // namespace
}  // namespace purkinje::python

PYBIND11_MODULE(_files, m) {
  using namespace purkinje;
  using namespace purkinje::python;
  m.doc() = "purkinje's image files and data sets; the purkinje package imports it when needed.";
  m.def("write_render",
        [](const Rendered& r, const std::filesystem::path& folder, std::optional<std::string> stem) {
          const std::string name = stem.value_or(portable_file_name(
              (r.scene.name.empty() ? "scene" : r.scene.name) + "_" +
              r.scene.cameras[static_cast<std::size_t>(r.result.camera)].name()));
          if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
            throw std::invalid_argument("write: stem \"" + name + "\": must be a file name, without a folder");
          }
          raise_refusal(studies::check_output_folder(folder, {}, {name + ".png", name + ".exr", name + ".json"}, {}));
          renderer::RenderFiles files;
          {
            py::gil_scoped_release release;
            create_output_folder(folder);
            files = renderer::write_render(folder, name, r.scene, r.result, r.options);
          }
          return files_dict(files);
        },
        py::arg("result"), py::arg("folder"), py::arg("stem"));
  m.def("write_compare",
        [](const CompareRun& run, const std::filesystem::path& folder) {
          raise_refusal(studies::check_output_folder(folder, {}, studies::compare_outputs(), {}));
          py::gil_scoped_release release;
          studies::write_compare(folder, run.world, run.assumed, run.study, run.settings);
        },
        py::arg("run"), py::arg("folder"));
  m.def("write_sweep",
        [](const SweepRun& run, const std::filesystem::path& folder) {
          raise_refusal(studies::check_output_folder(folder, {}, studies::sweep_outputs(), {}));
          py::gil_scoped_release release;
          studies::write_sweep(folder, run.sweep);
        },
        py::arg("run"), py::arg("folder"));
  m.def("read_exr",
        [](const std::filesystem::path& file) {
          std::vector<renderer::NamedPlane> planes;
          try {
            py::gil_scoped_release release;
            planes = renderer::read_exr(file);
          } catch (const OutputError& error) {  // the image reader's, about its input
            raise_if_missing(file, error.what());
            throw std::invalid_argument(error.what());
          }
          py::dict out;
          for (renderer::NamedPlane& p : planes) {
            py::array_t<float> a({p.plane.height, p.plane.width});
            std::copy(p.plane.values.begin(), p.plane.values.end(), a.mutable_data());
            out[py::str(p.name)] = a;
          }
          return out;
        },
        py::arg("file"));
  m.def("generate", &generate, py::arg("spec_file"), py::arg("output_dir"), py::arg("count"), py::arg("shard_index"),
        py::arg("shard_count"), py::arg("resume"), py::arg("threads"), py::arg("progress"));
  m.def("merge",
        [](const std::filesystem::path& dir) {
          const studies::MergeOutcome outcome = reading({dir}, [&] {
            py::gil_scoped_release release;
            return studies::merge_shards(dir);
          });
          py::dict out;
          out["shards"] = outcome.shards;
          out["rows"] = outcome.rows;
          out["table"] = outcome.table;
          out["manifest"] = outcome.manifest;
          return out;
        },
        py::arg("dir"));
  // purkinje's tracker over a labelled set (as `purkinje track`): the
  // score as (table, csv, json) and the detections by image.
  m.def("track_set",
        [](const std::vector<std::string>& inputs, const std::optional<Scene>& rig, const std::string& rig_name,
           double match_radius_px, double min_pupil_overlap) {
          trackers::ScoringSettings settings;
          settings.match_radius_px = match_radius_px;
          settings.min_pupil_overlap = min_pupil_overlap;
          const std::vector<std::filesystem::path> paths(inputs.begin(), inputs.end());
          const studies::TrackedSet tracked = reading(paths, [&] {
            py::gil_scoped_release release;
            const auto images = studies::read_labelled_images(studies::labels_files(inputs, {}));
            return studies::track_images(images, rig ? &*rig : nullptr, rig_name, settings);
          });
          py::dict detections;
          for (const auto& [image, found] : tracked.detections) detections[py::str(image)] = detections_tuple(found);
          return py::make_tuple(trackers::score_table(tracked.score), trackers::score_csv(tracked.score),
                                trackers::score_json(tracked.score), detections);
        },
        py::arg("inputs"), py::arg("rig"), py::arg("rig_name"), py::arg("match_radius_px"),
        py::arg("min_pupil_overlap"));
}
