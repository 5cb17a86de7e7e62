// The detectors on numpy images, purkinje's tracker, and scoring of any
// tracker's detections against labels. Detections cross as plain tuples;
// the package's Python classes (_trackers.py) wrap them. The GIL is
// released while detectors run.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <functional>
#include <type_traits>
#include <map>

#include "bindings.h"
#include "purkinje/models/check.h"
#include "purkinje/models/labels.h"
#include "purkinje/models/spelling.h"
#include "purkinje/studies/tracker.h"
#include "purkinje/trackers/detections_file.h"
#include "purkinje/trackers/glints.h"
#include "purkinje/trackers/pupil.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::python {
namespace {

using trackers::Detections;
using trackers::Glint;
using trackers::GreyView;

constexpr double kDegree = 3.14159265358979323846 / 180.0;

// A grey image: a 2D uint8 or uint16 array whose rows may be strided but
// whose pixels are contiguous (numpy slices of rows are taken as they are).
struct Image {
  py::array array;  // keeps the pixels alive
  GreyView view;
};

Image grey_image(const py::array& a, std::optional<int> bits) {
  const bool is8 = py::isinstance<py::array_t<std::uint8_t>>(a), is16 = py::isinstance<py::array_t<std::uint16_t>>(a);
  if (a.ndim() != 2 || !(is8 || is16)) {
    throw std::invalid_argument("image: must be a 2D uint8 or uint16 array (height, width), not " +
                                std::string(py::str(a.attr("dtype"))) + " of shape " +
                                std::string(py::str(a.attr("shape"))));
  }
  py::array pixels = a;
  if (a.strides(1) != a.itemsize() || a.strides(0) < a.shape(1) * a.itemsize()) {
    pixels = py::module_::import("numpy").attr("ascontiguousarray")(a);
  }
  const int default_bits = is8 ? 8 : 16;
  const int b = bits.value_or(default_bits);
  if (b < 1 || b > default_bits) {
    throw std::invalid_argument("image: bits = " + std::to_string(b) + ": must be from 1 to " +
                                std::to_string(default_bits) + " for a " + (is8 ? "uint8" : "uint16") + " image");
  }
  GreyView view;
  view.data = pixels.data();
  view.width = static_cast<int>(pixels.shape(1));
  view.height = static_cast<int>(pixels.shape(0));
  view.row_bytes = static_cast<std::size_t>(pixels.strides(0));
  view.bytes_per_pixel = static_cast<int>(pixels.itemsize());
  view.bits = b;
  return {pixels, view};
}

// Keyword settings onto a settings struct, each key known or a TypeError
// naming the valid ones (as Python does for an unknown keyword).
template <class Settings>
void apply(Settings& s, const py::dict& keys, const std::string& what,
           const std::map<std::string, std::function<void(Settings&, const py::handle&)>>& setters) {
  for (const auto& [key, value] : keys) {
    const std::string name = py::str(key);
    const auto found = setters.find(name);
    if (found == setters.end()) {
      std::vector<std::string> names;
      std::string valid;
      for (const auto& [k, unused] : setters) {
        names.push_back(k);
        valid += (valid.empty() ? "" : ", ") + k;
      }
      const auto meant = closest_match(name, names);
      throw py::type_error(what + ": unknown setting '" + name + "'" + (meant ? "; did you mean '" + *meant + "'?" : "") +
                           " (valid: " + valid + ")");
    }
    found->second(s, value);
  }
}

template <class S, class T>
std::pair<const std::string, std::function<void(S&, const py::handle&)>> field(const char* name, T S::*member) {
  return {name, [member, name](S& s, const py::handle& v) {
            // bool is an int to Python: a flag given for a number is a slip.
            if (py::isinstance<py::bool_>(v) || !(py::isinstance<py::int_>(v) || (std::is_floating_point_v<T> && py::isinstance<py::float_>(v)))) {
              throw py::type_error(std::string(name) + " = " + std::string(py::repr(v)) + ": must be " +
                                   (std::is_floating_point_v<T> ? "a number" : "an int"));
            }
            s.*member = v.cast<T>();
          }};
}

trackers::BlobGlintSettings glint_settings(const py::dict& keys) {
  using S = trackers::BlobGlintSettings;
  S s;
  apply<S>(s, keys, "detect_glints",
           {field("background_radius_px", &S::background_radius_px), field("threshold", &S::threshold),
            field("relative_threshold", &S::relative_threshold), field("min_area_px", &S::min_area_px),
            field("max_area_px", &S::max_area_px), field("centroid_margin_px", &S::centroid_margin_px),
            field("spot_sigma_px", &S::spot_sigma_px), field("full_scale_e", &S::full_scale_e),
            field("read_noise_e", &S::read_noise_e), field("min_neighbour_share", &S::min_neighbour_share)});
  return s;
}

trackers::StarburstPupilSettings pupil_settings(const py::dict& keys) {
  using S = trackers::StarburstPupilSettings;
  S s;
  apply<S>(s, keys, "detect_pupil",
           {field("min_radius_px", &S::min_radius_px), field("max_radius_px", &S::max_radius_px),
            field("candidates", &S::candidates), field("rays", &S::rays),
            field("ransac_iterations", &S::ransac_iterations), field("inlier_px", &S::inlier_px),
            field("min_axis_ratio", &S::min_axis_ratio), field("min_contrast", &S::min_contrast),
            field("min_confidence", &S::min_confidence), field("glint_margin_px", &S::glint_margin_px)});
  return s;
}

// Glints cross as (u, v, illuminator, energy_dn, peak_dn, area_px,
// saturated, center_sd_u_px, center_sd_v_px).
py::tuple glint_tuple(const Glint& g) {
  return py::make_tuple(g.centre.u, g.centre.v, g.illuminator, g.energy_dn, g.peak_dn, g.area_px, g.saturated,
                        g.centre_sd_u_px, g.centre_sd_v_px);
}
// A field of a detection given from Python, checked as the detections
// file reader checks its column: `where` names it ("image a.png:
// glints[0].u_px").
template <class T>
T detection_field(const py::handle& object, const char* name, const std::string& where) {
  try {
    return object.attr(name).cast<T>();
  } catch (const py::cast_error&) {
    throw py::type_error(where + "." + name + " = " + std::string(py::repr(object.attr(name))) + ": must be a " +
                         (std::is_same_v<T, bool> ? "bool" : std::is_integral_v<T> ? "int" : "number"));
  }
}

double finite_field(const py::handle& object, const char* name, const std::string& where) {
  const double v = detection_field<double>(object, name, where);
  if (!std::isfinite(v)) throw std::invalid_argument(where + "." + name + " = " + check::format_number(v) + ": must be a finite number");
  return v;
}

Glint glint_from(const py::handle& g, const std::string& where) {
  Glint out;
  out.centre = {finite_field(g, "u_px", where), finite_field(g, "v_px", where)};
  out.illuminator = detection_field<int>(g, "illuminator", where);
  if (out.illuminator < -1) {
    throw std::invalid_argument(where + ".illuminator = " + std::to_string(out.illuminator) +
                                ": must be a light's index, an integer from 0 (-1: not told)");
  }
  out.energy_dn = finite_field(g, "energy_dn", where);
  out.peak_dn = finite_field(g, "peak_dn", where);
  out.area_px = detection_field<int>(g, "area_px", where);
  out.saturated = detection_field<bool>(g, "saturated", where);
  out.centre_sd_u_px = finite_field(g, "center_sd_u_px", where);
  out.centre_sd_v_px = finite_field(g, "center_sd_v_px", where);
  return out;
}

// Ellipses cross as (centre u, centre v, semi-axis 1, semi-axis 2, angle in degrees).
py::object ellipse_tuple(const std::optional<Ellipse>& e) {
  if (!e) return py::none();
  return py::make_tuple(e->center.u, e->center.v, e->semi_axis_1_px, e->semi_axis_2_px, e->angle_rad / kDegree);
}
std::optional<Ellipse> ellipse_from(const py::handle& e, const std::string& where) {
  if (e.is_none()) return std::nullopt;
  Ellipse out;
  out.center = {finite_field(e, "center_u_px", where), finite_field(e, "center_v_px", where)};
  for (const auto& [name, axis] : {std::pair{"semi_axis_1_px", &out.semi_axis_1_px}, std::pair{"semi_axis_2_px", &out.semi_axis_2_px}}) {
    *axis = finite_field(e, name, where);
    if (!(*axis > 0)) throw std::invalid_argument(where + "." + name + " = " + check::format_number(*axis) + ": must be > 0");
  }
  const double angle = finite_field(e, "angle_deg", where);
  if (!(std::abs(angle) <= 360)) {
    throw std::invalid_argument(where + ".angle_deg = " + check::format_number(angle) + ": must be in [-360, 360] degrees");
  }
  out.angle_rad = angle * kDegree;
  return out;
}

// Pupils cross as (u, v, ellipse tuple or None, confidence or None).
py::tuple pupil_tuple(const trackers::PupilFound& p) {
  return py::make_tuple(p.centre.u, p.centre.v, ellipse_tuple(p.ellipse),
                        p.confidence ? py::object(py::float_(*p.confidence)) : py::object(py::none()));
}

// Detections given from Python for `image`, each field checked as the
// detections file reader checks it (the same rules, the field named).
Detections detections_from(const py::handle& d, const std::string& image) {
  Detections out;
  const std::string where = "image " + image + ": ";
  int k = 0;
  for (const py::handle g : d.attr("glints")) out.glints.push_back(glint_from(g, where + "glints[" + std::to_string(k++) + "]"));
  k = 0;
  for (const py::handle p : d.attr("pupils")) {
    const std::string at = where + "pupils[" + std::to_string(k++) + "]";
    trackers::PupilFound found;
    found.centre = {finite_field(p, "u_px", at), finite_field(p, "v_px", at)};
    found.ellipse = ellipse_from(p.attr("ellipse"), at + ".ellipse");
    if (!p.attr("confidence").is_none()) {
      const double c = detection_field<double>(p, "confidence", at);
      if (!(c >= 0 && c <= 1)) throw std::invalid_argument(at + ".confidence = " + check::format_number(c) + ": must be in [0, 1], or None");
      found.confidence = c;
    }
    out.pupils.push_back(found);
  }
  return out;
}

}  // namespace

py::tuple detections_tuple(const Detections& d) {
  py::list glints, pupils;
  for (const Glint& g : d.glints) glints.append(glint_tuple(g));
  for (const trackers::PupilFound& p : d.pupils) pupils.append(pupil_tuple(p));
  return py::make_tuple(glints, pupils);
}

namespace {

// The views of one camera: a render's, or a labels file's.
std::vector<EyeInCameraTruth> camera_views(const Rendered& r) {
  std::vector<EyeInCameraTruth> views;
  for (const EyeInCameraTruth& v : r.result.truth.views) {
    if (v.camera == r.result.camera) views.push_back(v);
  }
  return views;
}

struct ScorerState {
  trackers::Scorer scorer;
};

}  // namespace

void bind_trackers(py::module_& m) {
  m.def("_detect_glints",
        [](const py::array& image, std::optional<int> bits, const py::dict& settings) {
          const Image grey = grey_image(image, bits);
          const trackers::BlobGlintDetector detector(glint_settings(settings));
          std::vector<Glint> glints;
          {
            py::gil_scoped_release release;
            glints = detector.detect(grey.view);
          }
          py::list out;
          for (const Glint& g : glints) out.append(glint_tuple(g));
          return out;
        },
        py::arg("image"), py::arg("bits"), py::arg("settings"));
  m.def("_detect_pupil",
        [](const py::array& image, std::optional<int> bits, const py::iterable& glints, const py::dict& settings) {
          const Image grey = grey_image(image, bits);
          const trackers::StarburstPupilDetector detector(pupil_settings(settings));
          std::vector<Glint> masked;
          int k = 0;
          for (const py::handle g : glints) masked.push_back(glint_from(g, "detect_pupil: glints[" + std::to_string(k++) + "]"));
          std::optional<trackers::PupilDetection> pupil;
          {
            py::gil_scoped_release release;
            pupil = detector.detect(grey.view, masked);
          }
          if (!pupil) return py::object(py::none());
          return py::object(py::make_tuple(ellipse_tuple(pupil->ellipse), pupil->confidence));
        },
        py::arg("image"), py::arg("bits"), py::arg("glints"), py::arg("settings"));

  // A detections file (docs/trackers.md, "Detections files"): by image.
  m.def("_read_detections",
        [](const std::filesystem::path& file, const std::optional<std::string>& text) {
          trackers::DetectionsFile read;
          try {
            read = text ? trackers::parse_detections_file(*text, file) : trackers::read_detections_file(file);
          } catch (const std::runtime_error& error) {  // the reader's: bad input
            if (!text) raise_if_missing(file, error.what());
            throw std::invalid_argument(error.what());
          }
          py::dict out;
          for (const auto& [image, found] : read.images) out[py::str(image)] = detections_tuple(found);
          return out;
        },
        py::arg("file"), py::arg("text"));

  m.def("_camera_index", &camera_index, py::arg("scene"), py::arg("camera"), py::arg("who"));

  py::class_<studies::Tracker>(m, "_Tracker")
      .def(py::init<>())
      .def(py::init([](const Scene& scene, int camera, int eye) {
             if (camera < 0 || static_cast<std::size_t>(camera) >= scene.cameras.size() || eye < 0 ||
                 static_cast<std::size_t>(eye) >= scene.eyes.size()) {
               throw std::invalid_argument("Tracker: camera " + std::to_string(camera) + " or eye " +
                                           std::to_string(eye) + " is not in the scene (" +
                                           std::to_string(scene.cameras.size()) + " cameras, " +
                                           std::to_string(scene.eyes.size()) + " eyes)");
             }
             return studies::Tracker(scene.cameras[static_cast<std::size_t>(camera)], scene.illuminators,
                                     scene.eyes[static_cast<std::size_t>(eye)]);
           }),
           py::arg("scene"), py::arg("camera"), py::arg("eye"))
      .def("track",
           [](const studies::Tracker& t, const py::array& image, std::optional<int> bits) {
             const Image grey = grey_image(image, bits);
             Detections d;
             {
               py::gil_scoped_release release;
               d = t.track(grey.view);
             }
             return detections_tuple(d);
           },
           py::arg("image"), py::arg("bits"))
      .def_property_readonly("identifies_glints", &studies::Tracker::identifies_glints);

  py::class_<ScorerState>(m, "_Scorer")
      .def(py::init([](double match_radius_px, double min_pupil_overlap, bool score_glints, bool score_pupils) {
             trackers::ScoringSettings s;
             s.match_radius_px = match_radius_px;
             s.min_pupil_overlap = min_pupil_overlap;
             s.score_glints = score_glints;
             s.score_pupils = score_pupils;
             return ScorerState{trackers::Scorer(s)};
           }),
           py::arg("match_radius_px"), py::arg("min_pupil_overlap"), py::arg("score_glints"), py::arg("score_pupils"))
      .def("add_render",
           [](ScorerState& s, const std::string& image, const Rendered& r, const py::handle& detections) {
             s.scorer.add(image, camera_views(r), detections_from(detections, image));
           })
      .def("add_labels_file",
           [](ScorerState& s, const std::string& image, const std::filesystem::path& file,
              const py::handle& detections) {
             ImageLabels labels;
             try {
               labels = read_image_labels(file);
             } catch (const std::runtime_error& error) {  // the reader's: bad input
               raise_if_missing(file, error.what());
               throw std::invalid_argument(error.what());
             }
             s.scorer.add(image, labels.views, detections_from(detections, image));
           })
      .def("score", [](const ScorerState& s) {
        const trackers::Score score = s.scorer.score();
        return py::make_tuple(trackers::score_table(score), trackers::score_csv(score), trackers::score_json(score));
      });
}

}  // namespace purkinje::python
