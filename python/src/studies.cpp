// The calibration study from Python: the rig's eye fixates targets, each
// frame rendered and read by purkinje's tracker, both gaze methods
// calibrated and scored (docs/calibration.md). Frames are rendered in
// memory: no image file library is needed.

#include <pybind11/stl.h>

#include "bindings.h"
#include "purkinje/studies/calibration.h"
#include "purkinje/studies/compare.h"

namespace purkinje::python {
namespace {

// The compare study's settings from the keywords compare and sweep share.
studies::CompareStudySettings study_settings(const Scene& world, int grid, double cap_deg, int camera, int gaze_grid,
                                             int calibration_grid,
                                             const std::optional<std::vector<std::array<double, 3>>>& head_moves,
                                             std::optional<double> glint_noise_px,
                                             std::optional<double> pupil_noise_px, bool calibrate) {
  studies::CompareStudySettings s;
  s.field.grid = grid;
  s.field.cap_deg = cap_deg;
  s.field.camera = camera;
  s.calibration.grid = gaze_grid;
  s.calibration.calibration_grid = calibration_grid;
  s.calibration.head_moves = head_moves ? *head_moves : studies::default_head_moves(world);
  s.calibration.glint_noise_px = glint_noise_px;
  s.calibration.pupil_noise_px = pupil_noise_px;
  s.calibrate = calibrate;
  return s;
}

}  // namespace

void bind_studies(py::module_& m) {
  m.def("_displacement_csv",
        [](const Scene& world, const Scene& assumed, int grid, double cap_deg, int camera, int pupil_border_points) {
          studies::CompareSettings settings;
          settings.grid = grid;
          settings.cap_deg = cap_deg;
          settings.camera = camera;
          settings.pupil_border_points = pupil_border_points;
          py::gil_scoped_release release;
          return studies::displacement_csv(studies::displacement_field(world, assumed, settings));
        },
        py::arg("world"), py::arg("assumed"), py::arg("grid"), py::arg("cap_deg"), py::arg("camera"),
        py::arg("pupil_border_points"));
  m.def("_calibrate",
        [](const Scene& rig, int grid, int calibration_grid, const std::vector<std::array<double, 3>>& head_moves,
           const std::optional<std::array<double, 2>>& tracker_cornea, bool fit_radius, bool fit_pupil_depth,
           std::optional<double> glint_noise_px, std::optional<double> pupil_noise_px, int noise_frames,
           std::uint64_t seed, const std::optional<Scene>& tracker_rig, const py::object& progress) {
          studies::CalibrationSettings settings;
          settings.grid = grid;
          settings.calibration_grid = calibration_grid;
          settings.head_moves = head_moves;
          settings.tracker_cornea = tracker_cornea;
          settings.fit_radius = fit_radius;
          settings.fit_pupil_depth = fit_pupil_depth;
          settings.glint_noise_px = glint_noise_px;
          settings.pupil_noise_px = pupil_noise_px;
          settings.noise_frames = noise_frames;
          settings.seed = seed;
          settings.tracker_rig = tracker_rig;
          reading({}, [&] { studies::check_calibration_rig(rig, rig.name, settings); });
          const std::function<void()> step = progress_step(progress, studies::calibration_frames(settings));
          const studies::CalibrationStudy study = [&] {
            py::gil_scoped_release release;
            return studies::run_calibration(rig, settings, step);
          }();
          py::list panels;
          for (const studies::GazePanel& panel : study.panels) {
            py::list targets, estimates;
            for (const ScreenPoint& t : panel.targets) targets.append(py::make_tuple(t.x_mm, t.y_mm));
            for (const auto& method : panel.estimates) {
              py::list points;
              for (const auto& e : method) {
                points.append(e ? py::object(py::make_tuple(e->x_mm, e->y_mm)) : py::object(py::none()));
              }
              estimates.append(points);
            }
            panels.append(py::make_tuple(panel.title, targets, estimates));
          }
          return py::make_tuple(studies::simulation_json(study.runs), studies::simulation_text(study.runs),
                                study.frames_csv, panels);
        },
        py::arg("rig"), py::arg("grid"), py::arg("calibration_grid"), py::arg("head_moves"), py::arg("tracker_cornea"),
        py::arg("fit_radius"), py::arg("fit_pupil_depth"), py::arg("glint_noise_px"), py::arg("pupil_noise_px"),
        py::arg("noise_frames"), py::arg("seed"), py::arg("tracker_rig"), py::arg("progress"));

  py::class_<CompareRun, std::shared_ptr<CompareRun>>(m, "_CompareRun", "A compare study's results, for writing.");
  m.def("_compare",
        [](const Scene& world_as_given, const Scene& assumed_as_given, const std::optional<std::string>& world_eye,
           const std::optional<std::string>& assumed_eye, const std::optional<std::array<double, 2>>& assumed_cornea,
           int grid, double cap_deg, int camera, int gaze_grid, int calibration_grid,
           const std::optional<std::vector<std::array<double, 3>>>& head_moves, std::optional<double> glint_noise_px,
           std::optional<double> pupil_noise_px, bool calibrate, bool images, int samples, std::uint64_t seed,
           const py::object& progress) {
          auto run = std::make_shared<CompareRun>();
          const auto given = [](const std::optional<std::string>& model) {
            return model ? std::vector<std::filesystem::path>{*model} : std::vector<std::filesystem::path>{};
          };
          const Scene world = reading(given(world_eye), [&] {
            return world_eye ? studies::with_eye_model(world_as_given, *world_eye) : world_as_given;
          });
          const Scene assumed = reading(given(assumed_eye), [&] {
            return assumed_eye ? studies::with_eye_model(assumed_as_given, *assumed_eye) : assumed_as_given;
          });
          run->world = world;
          run->assumed = assumed_cornea
                             ? studies::with_one_surface_cornea(assumed, {(*assumed_cornea)[0], (*assumed_cornea)[1]})
                             : assumed;
          studies::CompareStudySettings& s = run->settings;
          s = study_settings(world, grid, cap_deg, camera, gaze_grid, calibration_grid, head_moves, glint_noise_px,
                             pupil_noise_px, calibrate);
          s.images = images;
          if (samples < 1 || samples > 4096) {
            throw std::invalid_argument("compare: samples = " + std::to_string(samples) + ": must be from 1 to 4096");
          }
          s.render.samples_per_pixel = samples;
          s.render.seed = seed;
          const std::function<void()> step = progress_step(progress, studies::compare_steps(world, s));
          {
            py::gil_scoped_release release;
            run->study = studies::run_compare(run->world, run->assumed, s, step);
          }
          const studies::CompareStudy& study = run->study;
          const auto rendered = [&](const Scene& scene, const std::optional<renderer::RenderResult>& result) {
            if (!result) return py::object(py::none());
            return py::cast(std::make_shared<Rendered>(Rendered{scene, s.render, *result}));
          };
          return py::make_tuple(run, studies::displacement_csv(study.field),
                                study.gaze.empty() ? py::object(py::none())
                                                   : py::object(py::str(studies::gaze_change_csv(study.gaze))),
                                studies::simulation_json(study.summary), studies::simulation_text(study.summary),
                                study.calibration_skipped, rendered(run->world, study.world_image),
                                rendered(run->assumed, study.assumed_image));
        },
        py::arg("world"), py::arg("assumed"), py::arg("world_eye"), py::arg("assumed_eye"), py::arg("assumed_cornea"),
        py::arg("grid"), py::arg("cap_deg"),
        py::arg("camera"), py::arg("gaze_grid"), py::arg("calibration_grid"), py::arg("head_moves"),
        py::arg("glint_noise_px"), py::arg("pupil_noise_px"), py::arg("calibrate"), py::arg("images"),
        py::arg("samples"), py::arg("seed"), py::arg("progress"));

  py::class_<SweepRun, std::shared_ptr<SweepRun>>(m, "_SweepRun", "A sweep's results, for writing.");
  m.def("_sweep_parameters", [] {
    py::list out;
    for (const studies::SweepParameter& p : studies::sweep_parameters()) out.append(py::make_tuple(p.name, p.unit, p.meaning));
    return out;
  });
  m.def("_sweep",
        [](const Scene& world, const std::string& parameter, double start, double stop, int steps, int noise_frames,
           std::uint64_t seed, int grid, double cap_deg, int camera, int gaze_grid, int calibration_grid,
           const std::optional<std::vector<std::array<double, 3>>>& head_moves, std::optional<double> glint_noise_px,
           std::optional<double> pupil_noise_px, bool calibrate, const py::object& progress) {
          const studies::CompareStudySettings s = study_settings(world, grid, cap_deg, camera, gaze_grid,
                                                                 calibration_grid, head_moves, glint_noise_px,
                                                                 pupil_noise_px, calibrate);
          const studies::SweepSettings sweep{parameter, start, stop, steps, noise_frames, seed};
          studies::check_sweep(world, sweep);
          const std::function<void()> step = progress_step(progress, studies::sweep_steps(world, s, sweep));
          auto run = std::make_shared<SweepRun>();
          {
            py::gil_scoped_release release;
            run->sweep = studies::run_sweep(world, s, sweep, step);
          }
          return py::make_tuple(run, studies::sweep_csv(run->sweep), studies::sweep_json(run->sweep));
        },
        py::arg("world"), py::arg("parameter"), py::arg("start"), py::arg("stop"), py::arg("steps"),
        py::arg("noise_frames"), py::arg("seed"), py::arg("grid"), py::arg("cap_deg"), py::arg("camera"),
        py::arg("gaze_grid"), py::arg("calibration_grid"), py::arg("head_moves"), py::arg("glint_noise_px"),
        py::arg("pupil_noise_px"), py::arg("calibrate"), py::arg("progress"));
}

}  // namespace purkinje::python
