// Rendering into numpy arrays, with the GIL released while the renderer
// works (Python threads overlap renders). Arrays view the result's memory
// where the types agree (radiance, electrons, AOVs, a sensor image of more
// than 8 bits) and copy where they do not. Files are files.cpp's.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <memory>
#include <mutex>
#include <vector>

#include "bindings.h"
#include "purkinje/models/labels.h"
#include "purkinje/renderer/render.h"

namespace purkinje::python {
namespace {

using renderer::ImagePlane;
using renderer::RenderOptions;
using renderer::RenderResult;

py::array view(const ImagePlane& plane, const py::object& owner) {
  return py::array_t<float>({plane.height, plane.width}, plane.values.data(), owner);
}

py::array sensor_array(const Rendered& r, const py::object& owner) {
  const renderer::SensorImage& s = r.result.sensor;
  if (s.bits > 8) return py::array_t<std::uint16_t>({s.height, s.width}, s.values.data(), owner);
  py::array_t<std::uint8_t> out({s.height, s.width});
  std::uint8_t* data = out.mutable_data();
  for (std::size_t i = 0; i < s.values.size(); ++i) data[i] = static_cast<std::uint8_t>(s.values[i]);
  return out;
}

const ImagePlane& aov(const Rendered& r, const std::string& name) {
  std::string names;
  for (const renderer::NamedPlane& p : r.result.aovs) {
    if (p.name == name) return p.plane;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  throw py::key_error("no AOV \"" + name + "\" (this render has: " + names + ")");
}

// Results Python has let go of, kept for the next renders to reuse their
// images' memory: fresh memory costs a page fault per 4 KB, a tenth of a
// remote render (render.h), and a loop over a data set lets each result
// go before the next. At most two (about 20 MB each for the remote scene).
class ResultPool {
 public:
  std::shared_ptr<Rendered> take() {
    std::unique_ptr<Rendered> kept;
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        kept = std::move(free_.back());
        free_.pop_back();
      }
    }
    if (!kept) kept = std::make_unique<Rendered>();
    return std::shared_ptr<Rendered>(kept.release(), [this](Rendered* r) { give_back(r); });
  }

 private:
  void give_back(Rendered* r) {
    std::unique_ptr<Rendered> owned(r);
    const std::lock_guard<std::mutex> lock(mutex_);
    if (free_.size() < 2) free_.push_back(std::move(owned));
  }
  std::mutex mutex_;
  std::vector<std::unique_ptr<Rendered>> free_;
};

ResultPool& pool() {
  static ResultPool* p = new ResultPool;  // never destroyed: results may outlive static destruction
  return *p;
}

std::shared_ptr<Rendered> render(const Scene& scene, const py::object& camera, const std::string& mode,
                                 int samples_per_pixel, int edge_samples_per_pixel, const std::string& pixel_filter,
                                 double pixel_filter_width, std::uint64_t seed, bool noise,
                                 int iris_cache_resolution, std::int64_t reference_photons_per_light,
                                 bool per_light_glint_masks, const std::optional<std::array<int, 4>>& region,
                                 int threads) {
  std::shared_ptr<Rendered> out = pool().take();
  out->scene = scene;
  RenderOptions& o = out->options;
  o = RenderOptions{};  // a pooled result's options are its last render's (its region too)
  if (mode == "fast") o.mode = renderer::RenderMode::fast;
  else if (mode == "reference") o.mode = renderer::RenderMode::reference;
  else throw std::invalid_argument("render: mode = \"" + mode + "\": must be \"fast\" or \"reference\"");
  o.samples_per_pixel = samples_per_pixel;
  o.edge_samples_per_pixel = edge_samples_per_pixel;
  const std::optional<renderer::PixelFilterKind> filter = renderer::pixel_filter_kind(pixel_filter);
  if (!filter) {
    const std::vector<std::string>& names = renderer::pixel_filter_names();
    std::string valid;
    for (std::size_t i = 0; i < names.size(); ++i) {
      valid += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + ("\"" + names[i] + "\"");
    }
    throw std::invalid_argument("render: pixel_filter = \"" + pixel_filter + "\": must be " + valid);
  }
  o.pixel_filter = {*filter, pixel_filter_width};  // the width is checked by the renderer
  o.seed = seed;
  o.noise = noise;
  o.iris_cache_resolution = iris_cache_resolution;
  o.reference_photons_per_light = reference_photons_per_light;
  o.per_light_glint_masks = per_light_glint_masks;
  if (region) o.region = renderer::PixelRegion{(*region)[0], (*region)[1], (*region)[2], (*region)[3]};
  if (threads < 0 || threads > 1024) {  // the command line's --threads range
    throw std::invalid_argument("render: threads = " + std::to_string(threads) + ": must be from 0 (all) to 1024");
  }
  o.threads = threads;
  const int index = camera_index(scene, camera, "render");  // the renderer checks the range
  py::gil_scoped_release release;
  renderer::render(out->scene, index, o, out->result);
  return out;
}

py::dict glint_dict(const Scene& scene, const renderer::GlintImage& g) {
  py::dict d;
  d["eye"] = g.eye;
  d["illuminator"] = g.illuminator;
  d["illuminator_name"] = scene.illuminators[static_cast<std::size_t>(g.illuminator)].name;
  d["status"] = to_string(g.status);
  d["fresnel"] = g.radiometry.fresnel;
  d["power_w"] = g.radiometry.power_w;
  d["electrons"] = g.electrons;
  return d;
}

}  // namespace

void bind_render(py::module_& m) {
  py::class_<Rendered, std::shared_ptr<Rendered>>(m, "RenderResult",
                                                  "One camera's image of a scene, its AOVs and its labels.")
      .def_property_readonly("camera", [](const Rendered& r) { return r.result.camera; }, "the camera's index")
      .def_property_readonly("camera_name",
                             [](const Rendered& r) { return r.scene.cameras[static_cast<std::size_t>(r.result.camera)].name(); },
                             "the camera's name")
      .def_property_readonly("scene", [](const Rendered& r) { return r.scene; }, "the scene rendered")
      .def_property_readonly("bits", [](const Rendered& r) { return r.result.sensor.bits; }, "the sensor's ADC depth")
      .def_property_readonly("image", [](py::object self) { return sensor_array(self.cast<const Rendered&>(), self); },
                             "The sensor image in digital numbers, (height, width): uint8 for an 8-bit sensor, "
                             "else uint16 holding 0 .. 2^bits - 1 (the PNG keeps them in the high bits).")
      .def_property_readonly("radiance", [](py::object self) { return view(self.cast<const Rendered&>().result.radiance, self); },
                             "Scene radiance per pixel, W m^-2 sr^-1, float32, before the optics and without glints.")
      .def_property_readonly("electrons", [](py::object self) { return view(self.cast<const Rendered&>().result.electrons, self); },
                             "The noise-free linear image in electrons, float32: radiance through the optics, glints added.")
      .def_property_readonly("aov_names",
                             [](const Rendered& r) {
                               py::list names;
                               for (const renderer::NamedPlane& p : r.result.aovs) names.append(p.name);
                               return names;
                             },
                             "the AOVs' names (aov() takes them)")
      .def("aov", [](py::object self, const std::string& name) { return view(aov(self.cast<const Rendered&>(), name), self); },
           py::arg("name"), "An AOV by name (aov_names), float32 (height, width); KeyError naming the others.")
      .def_property_readonly("segmentation",
                             [](const Rendered& r) {
                               const ImagePlane& id = aov(r, "id");
                               py::array_t<std::uint8_t> out({id.height, id.width});
                               std::uint8_t* data = out.mutable_data();
                               for (std::size_t i = 0; i < id.values.size(); ++i) data[i] = static_cast<std::uint8_t>(id.values[i]);
                               return out;
                             },
                             "Pixel classes, uint8: 0 background, 1 skin, 2 sclera, 3 iris, 4 pupil, 5 lash, 6 brow.")
      .def("_truth_json", [](const Rendered& r) { return truth_to_json(r.scene, r.result.truth); })
      .def_property_readonly("glints",
                             [](const Rendered& r) {
                               py::list out;
                               for (const renderer::GlintImage& g : r.result.glints) out.append(glint_dict(r.scene, g));
                               return out;
                             },
                             "Each glint's light path and signal: eye, illuminator, status, fresnel, power_w, electrons.")
      .def_property_readonly("distractors",
                             [](const Rendered& r) {
                               py::list out;
                               for (const renderer::GlintImage& g : r.result.distractors) {
                                 py::dict d = glint_dict(r.scene, g);
                                 const double* c = g.radiometry.roughness_cov_px2;
                                 d["spread_cov_px2"] = py::make_tuple(c[0], c[1], c[2]);
                                 out.append(d);
                               }
                               return out;
                             },
                             "A wet eye's scleral highlights as the image holds them, in the labels' order: eye, "
                             "illuminator, status, fresnel, power_w, electrons (what the camera sees of it), "
                             "spread_cov_px2 (the roughness's spread: u-u, u-v, v-v).")
      ;

  m.def("_render", &render, py::arg("scene"), py::arg("camera"), py::arg("mode"), py::arg("samples_per_pixel"),
        py::arg("edge_samples_per_pixel"), py::arg("pixel_filter"), py::arg("pixel_filter_width"), py::arg("seed"), py::arg("noise"), py::arg("iris_cache_resolution"),
        py::arg("reference_photons_per_light"), py::arg("per_light_glint_masks"), py::arg("region"),
        py::arg("threads"));

}

}  // namespace purkinje::python
