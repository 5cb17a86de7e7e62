// Scenes and dataset specs: read from files or text (the same readers and
// messages as the command line), looked at through read-only objects with
// numpy arrays, and written back as plain JSON. A scene is changed by
// changing its JSON (Scene.to_dict, parse_scene): every change then passes
// the file format's checks.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "purkinje/models/check.h"
#include "purkinje/models/dataset_spec.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/scene_file.h"
#include "purkinje/models/truth.h"

namespace purkinje::python {
namespace {

Scene load_scene_or_raise(const std::filesystem::path& file) {
  try {
    return load_scene(file);
  } catch (const SceneError& error) {
    raise_if_missing(file, error.what());
    throw;
  }
}

DatasetSpec load_spec_or_raise(const std::filesystem::path& file) {
  try {
    return load_dataset_spec(file);
  } catch (const DatasetSpecError& error) {
    raise_if_missing(file, error.what());
    throw;
  }
}

// The pixels of points seen by a camera, distortion included, and each
// one's status ("ok", "outside_image", "behind_camera"; behind the camera
// the pixel is 0, 0).
py::tuple project(const Camera& camera, const py::array_t<double, py::array::c_style | py::array::forcecast>& points) {
  if (points.ndim() == 0 || points.ndim() > 2 || points.shape(points.ndim() - 1) != 3) {
    throw std::invalid_argument("Camera.project: points must have shape (3,) or (n, 3), not " +
                                std::string(py::str(points.attr("shape"))));
  }
  const py::ssize_t n = points.size() / 3;
  py::array_t<double> pixels({n, py::ssize_t{2}});
  py::list status;
  auto in = points.data();
  auto out = pixels.mutable_unchecked<2>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Point3 point{in[3 * i], in[3 * i + 1], in[3 * i + 2]};
    if (!point.is_finite()) {
      throw std::invalid_argument("Camera.project: points_mm[" + std::to_string(i) + "] = [" +
                                  check::format_number(point.x) + ", " + check::format_number(point.y) + ", " +
                                  check::format_number(point.z) + "]: must be finite");
    }
    const Projection p = camera.project(point);
    const bool behind = p.status == ProjectionStatus::behind_camera;
    out(i, 0) = behind ? 0.0 : p.pixel.u;
    out(i, 1) = behind ? 0.0 : p.pixel.v;
    status.append(to_string(p.status));
  }
  if (points.ndim() == 1) return py::make_tuple(pixels[py::int_(0)], status[0]);
  return py::make_tuple(pixels, status);
}

py::array_t<double> camera_matrix(const Camera& c) {
  const Intrinsics& k = c.intrinsics();
  py::array_t<double> out({3, 3});
  auto a = out.mutable_unchecked<2>();
  const double values[9] = {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1};
  for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = values[i];
  return out;
}

py::array_t<double> distortion(const Camera& c) {
  const Distortion& d = c.distortion();
  py::array_t<double> out(5);
  auto a = out.mutable_unchecked<1>();
  a(0) = d.k1;
  a(1) = d.k2;
  a(2) = d.p1;
  a(3) = d.p2;
  a(4) = d.k3;
  return out;
}

py::dict draw_dict(const DatasetSpec& spec, std::uint64_t index) {
  if (index >= spec.count) {
    throw py::index_error(spec.source + ": image " + std::to_string(index) + " is beyond the set's " +
                          std::to_string(spec.count) + " images");
  }
  const ImageDraw draw = draw_image(spec, index);
  py::dict out;
  for (std::size_t i = 0; i < spec.parameters.size(); ++i) {
    const VariedParameter& p = spec.parameters[i];
    const double v = draw.values[i];
    if (p.type == ParameterType::boolean) out[py::str(p.name)] = v != 0;
    else if (p.type == ParameterType::integer) out[py::str(p.name)] = static_cast<long long>(v);
    else out[py::str(p.name)] = v;
  }
  return out;
}

}  // namespace

void bind_scene(py::module_& m) {
  py::class_<Sensor>(m, "Sensor", "A camera's sensor and aperture (docs/scene-format.md, \"Camera sensor\").")
      .def_readonly("pixel_pitch_mm", &Sensor::pixel_pitch_mm, "square pixel size, mm")
      .def_readonly("f_number", &Sensor::f_number, "aperture diameter = focal length / f_number")
      .def_readonly("exposure_s", &Sensor::exposure_s, "integration time, s")
      .def_readonly("quantum_efficiency", &Sensor::quantum_efficiency, "electrons per photon at the lights' wavelength")
      .def_readonly("full_well_e", &Sensor::full_well_e, "electrons at which a pixel saturates")
      .def_readonly("read_noise_e", &Sensor::read_noise_e, "Gaussian read noise, electrons RMS")
      .def_readonly("gain", &Sensor::gain, "analog gain: 1 maps the full well onto the ADC's range")
      .def_readonly("bits", &Sensor::bits, "ADC depth: 8, 10, 12 or 16")
      .def_readonly("psf_sigma_px", &Sensor::psf_sigma_px, "the optics' Gaussian point spread, px")
      .def_readonly("focus_distance_mm", &Sensor::focus_distance_mm, "None: everything in focus")
      .def_readonly("noise", &Sensor::noise, "whether shot and read noise are on")
      .def_readonly("corner_illumination", &Sensor::corner_illumination,
                    "the lens's vignetting beyond cos^4: relative illumination at the farthest corner (1: none)")
      .def_readonly("hot_pixel_fraction", &Sensor::hot_pixel_fraction, "fraction of hot pixels (0: none)")
      .def_readonly("hot_pixel_e_per_s", &Sensor::hot_pixel_e_per_s, "a hot pixel's mean dark current, electrons/s")
      .def_readonly("hot_pixel_seed", &Sensor::hot_pixel_seed, "picks the hot pixels (the same in every image)")
      .def_readonly("jpeg_quality", &Sensor::jpeg_quality, "None: raw; else the image went through a JPEG of this quality");

  py::class_<Camera>(m, "Camera", "A pinhole camera in OpenCV's conventions, with its sensor.")
      .def_property_readonly("name", &Camera::name, "the camera's name, unique in its scene")
      .def_property_readonly("resolution_px",
                             [](const Camera& c) { return py::make_tuple(c.intrinsics().width, c.intrinsics().height); },
                             "(width, height)")
      .def_property_readonly("camera_matrix", &camera_matrix, "OpenCV's K, [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] in px")
      .def_property_readonly("distortion", &distortion, "OpenCV's distCoeffs (k1, k2, p1, p2, k3)")
      .def_property_readonly("world_from_camera", [](const Camera& c) { return matrix(c.world_from_camera()); },
                             "4 x 4 pose: camera-frame points to world points, mm")
      .def_property_readonly("center_mm", [](const Camera& c) { return array(c.center()); }, "the optical centre in the world, mm")
      .def_property_readonly("focal_length_mm", &Camera::focal_length_mm, "fx times the sensor's pixel pitch, mm")
      .def_property_readonly("sensor", &Camera::sensor, "the sensor and aperture (Sensor)")
      .def("project", &project, py::arg("points_mm"),
           "World points (3,) or (n, 3), mm, to pixels (distortion included) and their statuses: "
           "\"ok\", \"outside_image\" (pixel still given) or \"behind_camera\" (pixel 0, 0).")
      .def("__repr__", [](const Camera& c) {
        return "<purkinje.Camera '" + c.name() + "' " + std::to_string(c.intrinsics().width) + "x" +
               std::to_string(c.intrinsics().height) + ">";
      });

  py::class_<Illuminator>(m, "Illuminator", "A near-infrared point light (LED).")
      .def_readonly("name", &Illuminator::name, "the light's name, unique in its scene")
      .def_property_readonly("position_mm", [](const Illuminator& l) { return array(l.position); }, "world position, mm")
      .def_readonly("radiant_intensity_w_sr", &Illuminator::radiant_intensity_w_sr, "toward the eye, W/sr")
      .def_readonly("wavelength_nm", &Illuminator::wavelength_nm, "nm")
      .def_readonly("emitter_diameter_mm", &Illuminator::emitter_diameter_mm, "the emitting disc's diameter, mm (0: a point)")
      .def("__repr__", [](const Illuminator& l) { return "<purkinje.Illuminator '" + l.name + "'>"; });

  py::class_<EyeModel>(m, "EyeModel", "An eye's anatomy (docs/eye-models.md); lengths in mm.")
      .def_readonly("name", &EyeModel::name, "the preset it started from")
      .def_property_readonly("cornea_radius_mm", [](const EyeModel& e) { return e.anterior_cornea.radius_mm; }, "the anterior cornea's apical radius, mm")
      .def_property_readonly("cornea_asphericity", [](const EyeModel& e) { return e.anterior_cornea.asphericity; }, "the anterior cornea's conic constant Q (0: a sphere)")
      .def_readonly("limbus_radius_mm", &EyeModel::limbus_radius_mm, "radius of the corneal cap's border, mm")
      .def_property_readonly("posterior_cornea",
                             [](const EyeModel& e) -> py::object {
                               if (!e.posterior_cornea) return py::none();
                               const PosteriorCornea& p = *e.posterior_cornea;
                               py::dict d;
                               d["radius_mm"] = p.surface.radius_mm;
                               d["asphericity"] = p.surface.asphericity;
                               d["thickness_mm"] = p.thickness_mm;
                               d["index"] = p.cornea_index;
                               return d;
                             },
                             "None for a one-surface eye, else its radius_mm, asphericity, thickness_mm, index")
      .def_readonly("aqueous_index", &EyeModel::aqueous_index, "refractive index behind the cornea")
      .def_readonly("iris_depth_mm", &EyeModel::iris_depth_mm, "anterior apex to the iris plane, mm")
      .def_readonly("iris_radius_mm", &EyeModel::iris_radius_mm, "outer border of the iris, mm")
      .def_readonly("pupil_radius_mm", &EyeModel::pupil_radius_mm, "mm")
      .def_property_readonly("pupil_decentration_mm",
                             [](const EyeModel& e) {
                               return py::make_tuple(e.pupil_decentration_x_mm, e.pupil_decentration_y_mm);
                             },
                             "the pupil centre in the iris plane, eye-frame (x, y), mm")
      .def_readonly("rotation_center_depth_mm", &EyeModel::rotation_center_depth_mm, "anterior apex to the centre of rotation, mm")
      .def_readonly("sclera_radius_mm", &EyeModel::sclera_radius_mm, "the sclera sphere's radius, mm")
      .def_property_readonly("iris_outer_radius_mm", &EyeModel::iris_outer_radius_mm,
                             "how far from the axis the iris reaches in the rendered eye: the chamber angle in a "
                             "two-surface eye, the sclera in a one-surface eye, mm")
      .def_property_readonly("kappa_deg",
                             [](const EyeModel& e) {
                               constexpr double k = 180.0 / 3.14159265358979323846;
                               return py::make_tuple(e.kappa_horizontal_rad * k, e.kappa_vertical_rad * k);
                             },
                             "(horizontal, vertical)")
      .def("__repr__", [](const EyeModel& e) { return "<purkinje.EyeModel '" + e.name + "'>"; });

  py::class_<Eye>(m, "Eye", "An eye placed and turned in the world: its anatomy and where its parts are.")
      .def_property_readonly("model", &Eye::model, "the anatomy (EyeModel)")
      .def_property_readonly("cornea_center_mm", [](const Eye& e) { return array(e.cornea_center()); }, "the anterior cornea's centre of curvature, world, mm")
      .def_property_readonly("rotation_center_mm", [](const Eye& e) { return array(e.rotation_center()); }, "the centre of rotation, world, mm")
      .def_property_readonly("corneal_apex_mm", [](const Eye& e) { return array(e.corneal_apex()); }, "the anterior corneal apex, world, mm")
      .def_property_readonly("pupil_center_mm", [](const Eye& e) { return array(e.pupil_center()); }, "the real (unrefracted) pupil centre, world, mm")
      .def_property_readonly("optical_axis", [](const Eye& e) { return array(e.optical_axis()); }, "unit vector out of the eye through the apex")
      .def_property_readonly("visual_axis", [](const Eye& e) { return array(e.visual_axis()); }, "unit vector from the cornea centre toward the fixation (kappa applied)")
      .def_property_readonly("world_from_eye", [](const Eye& e) { return matrix(e.world_from_eye()); },
                             "4 x 4 pose: eye-frame points to world points, mm")
      .def_property_readonly("motion",
                             [](const Eye& e) { return py::make_tuple(e.motion().yaw_deg_s, e.motion().pitch_deg_s); },
                             "(yaw_deg_s, pitch_deg_s): how it turns during the exposure; (0, 0): still")
      .def("__repr__", [](const Eye& e) { return "<purkinje.Eye '" + e.model().name + "'>"; });

  py::class_<Mesh>(m, "Mesh", "A triangle mesh beside the eyes, in world coordinates.")
      .def_readonly("name", &Mesh::name, "the mesh's name")
      .def_readonly("albedo", &Mesh::albedo, "Lambertian reflectance, 0 to 1")
      .def_property_readonly("vertices_mm",
                             [](const Mesh& mesh) {
                               py::array_t<double> out({static_cast<py::ssize_t>(mesh.vertices.size()), py::ssize_t{3}});
                               auto a = out.mutable_unchecked<2>();
                               for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
                                 for (int k = 0; k < 3; ++k) a(i, k) = mesh.vertices[i][k];
                               }
                               return out;
                             },
                             "(n, 3) world points, mm")
      .def_property_readonly("triangles", [](const Mesh& mesh) {
        py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(mesh.triangles.size()), py::ssize_t{3}});
        auto a = out.mutable_unchecked<2>();
        for (std::size_t i = 0; i < mesh.triangles.size(); ++i) {
          for (int k = 0; k < 3; ++k) a(i, k) = mesh.triangles[i][k];
        }
        return out;
      }, "(m, 3) vertex indices, counter-clockwise seen from the front");

  py::class_<Screen>(m, "Screen", "What the eye looks at: a rectangle, points on it in mm from its top-left corner.")
      .def_property_readonly("top_left_mm", [](const Screen& s) { return array(s.top_left); }, "the top-left corner, world, mm")
      .def_property_readonly("center_mm", [](const Screen& s) { return array(s.center()); }, "the centre, world, mm")
      .def_property_readonly("right", [](const Screen& s) { return array(s.right); }, "unit vector along the rows")
      .def_property_readonly("down", [](const Screen& s) { return array(s.down); }, "unit vector down the columns")
      .def_readonly("width_mm", &Screen::width_mm, "along right, mm")
      .def_readonly("height_mm", &Screen::height_mm, "along down, mm")
      .def("at", [](const Screen& s, double x_mm, double y_mm) { return array(s.at({x_mm, y_mm})); },
           py::arg("x_mm"), py::arg("y_mm"), "The world point (mm) x_mm along the rows and y_mm down the columns.");

  py::class_<Scene>(m, "Scene", "Cameras, near-infrared lights, eyes, meshes and a screen in one world frame.")
      .def_readonly("name", &Scene::name, "the scene's name (labels and file stems carry it)")
      .def_readonly("cameras", &Scene::cameras, "list of Camera")
      .def_readonly("illuminators", &Scene::illuminators, "list of Illuminator")
      .def_readonly("eyes", &Scene::eyes, "list of Eye")
      .def_readonly("meshes", &Scene::meshes, "list of Mesh")
      .def_readonly("screen", &Scene::screen, "None when the scene has none")
      .def("to_json", &scene_to_json,
           "The scene as a scene file in plain JSON (no comments); parse_scene reads it back to the same "
           "scene, bit for bit.")
      .def("to_dict", [](const Scene& s) { return json_loads(scene_to_json(s)); },
           "to_json() as Python dicts and lists: change a value and give it to parse_scene.")
      .def("__repr__", [](const Scene& s) {
        return "<purkinje.Scene '" + s.name + "': " + std::to_string(s.cameras.size()) + " cameras, " +
               std::to_string(s.illuminators.size()) + " illuminators, " + std::to_string(s.eyes.size()) +
               " eyes, " + std::to_string(s.meshes.size()) + " meshes>";
      });

  m.def("load_scene", &load_scene_or_raise, py::arg("file"),
        "Reads a scene file (docs/scene-format.md) and the mesh files it names. Raises FileNotFoundError or "
        "SceneError (a ValueError) with the command line's message.");
  m.def("_parse_scene_text", &parse_scene, py::arg("text"), py::arg("source"), py::arg("folder"));
  m.def("eye_model_presets", &eye_model_preset_names, "The eye model presets' names.");
  m.def("eye_model",
        [](const std::string& name) {
          if (auto model = eye_model_preset(name)) return *model;
          throw std::invalid_argument("eye_model: \"" + name + "\": unknown eye model (valid: keratometric, le_grand, navarro)");
        },
        py::arg("name"), "A preset's anatomy (docs/eye-models.md): \"keratometric\", \"le_grand\" or \"navarro\".");
  m.def("_truth_text",
        [](const Scene& scene, int pupil_border_points, const std::string& format) {
          // The command line's --pupil-points range.
          if (pupil_border_points < 0 || pupil_border_points > 100000) {
            throw std::invalid_argument("truth: pupil_border_points = " + std::to_string(pupil_border_points) +
                                        ": must be between 0 and 100000");
          }
          TruthOptions options;
          options.pupil_border_points = pupil_border_points;
          py::gil_scoped_release release;
          const SceneTruth truth = compute_truth(scene, options);
          return format == "csv" ? truth_to_csv(scene, truth) : truth_to_json(scene, truth);
        },
        py::arg("scene"), py::arg("pupil_border_points"), py::arg("format"));

  py::class_<DatasetSpec>(m, "DatasetSpec", "A labelled data set's recipe: a base scene and how each image varies it "
                                            "(docs/dataset-format.md).")
      .def_readonly("name", &DatasetSpec::name, "the set's name: file stems are <name>_<index>_<camera>")
      .def_readonly("count", &DatasetSpec::count, "images in the set")
      .def_readonly("seed", &DatasetSpec::seed, "the seed of every draw")
      .def_readonly("scene", &DatasetSpec::scene, "the base scene")
      .def_property_readonly("parameters",
                             [](const DatasetSpec& s) {
                               py::list names;
                               for (const VariedParameter& p : s.parameters) names.append(p.name);
                               return names;
                             },
                             "the varied parameters' names, in the table's column order")
      .def("draw", &draw_dict, py::arg("index"), "Image `index`'s drawn values, by parameter name.")
      .def("scene_for_image",
           [](const DatasetSpec& s, std::uint64_t index) {
             if (index >= s.count) draw_dict(s, index);  // the index error
             return scene_for_image(s, draw_image(s, index));
           },
           py::arg("index"), "The scene of image `index`, as generate renders it.")
      .def("__repr__", [](const DatasetSpec& s) {
        return "<purkinje.DatasetSpec '" + s.name + "': " + std::to_string(s.count) + " images, " +
               std::to_string(s.parameters.size()) + " parameters>";
      });
  m.def("load_dataset_spec", &load_spec_or_raise, py::arg("file"),
        "Reads a dataset spec and the scene it names. Raises FileNotFoundError or DatasetSpecError (a "
        "ValueError) with the command line's message.");
  m.def("_parse_dataset_spec_text", &parse_dataset_spec, py::arg("text"), py::arg("source"), py::arg("folder"));
}

}  // namespace purkinje::python
