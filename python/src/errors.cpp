// Library errors as Python exceptions with the command line's messages:
// bad input is a ValueError (SceneError and DatasetSpecError are its
// subclasses), a missing input file a FileNotFoundError, an output that
// cannot be written an OSError (OutputError). std::invalid_argument
// becomes ValueError and std::runtime_error RuntimeError (pybind11's own
// translations).

#include "bindings.h"

#include <memory>

#include "purkinje/models/dataset_spec.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/scene_file.h"

namespace purkinje::python {

void bind_errors(py::module_& m) {
  py::register_exception<SceneError>(m, "SceneError", PyExc_ValueError);
  py::register_exception<DatasetSpecError>(m, "DatasetSpecError", PyExc_ValueError);
  py::register_exception<OutputError>(m, "OutputError", PyExc_OSError);
}

void raise_if_missing(const std::filesystem::path& file, const std::string& message) {
  std::error_code error;
  if (std::filesystem::exists(file, error) || error) return;
  PyErr_SetString(PyExc_FileNotFoundError, message.c_str());
  throw py::error_already_set();
}

int camera_index(const Scene& scene, const py::object& camera, const std::string& who) {
  if (py::isinstance<py::str>(camera)) {
    const std::string name = camera.cast<std::string>();
    std::string names;
    for (std::size_t i = 0; i < scene.cameras.size(); ++i) {
      if (scene.cameras[i].name() == name) return static_cast<int>(i);
      names += (i ? ", " : "") + scene.cameras[i].name();
    }
    throw std::invalid_argument(who + ": camera \"" + name + "\": the scene has no camera of that name (cameras: " +
                                names + ")");
  }
  if (!py::isinstance<py::int_>(camera) || py::isinstance<py::bool_>(camera)) {
    throw py::type_error(who + ": camera must be a camera's index (int) or name (str), not " +
                         std::string(py::str(camera.get_type().attr("__name__"))));
  }
  return camera.cast<int>();
}

std::function<void()> progress_step(const py::object& progress, std::size_t total) {
  auto done = std::make_shared<std::size_t>(0);
  return [progress, total, done] {
    py::gil_scoped_acquire acquire;
    ++*done;
    if (!progress.is_none()) progress(*done, total);
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
  };
}

py::array_t<double> array(const Vector3& v) {
  py::array_t<double> out(3);
  auto a = out.mutable_unchecked<1>();
  a(0) = v.x;
  a(1) = v.y;
  a(2) = v.z;
  return out;
}
py::array_t<double> array(const Point3& p) { return array(p.from_origin()); }
py::array_t<double> array(const UnitVector3& v) { return array(v.vector()); }

py::array_t<double> matrix(const Pose& pose) {
  py::array_t<double> out({4, 4});
  auto a = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) a(r, c) = 0;
  }
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) a(r, c) = pose.rotation()(r, c);
    a(r, 3) = pose.translation()[r];
  }
  a(3, 3) = 1;
  return out;
}

py::object json_loads(const std::string& text) { return py::module_::import("json").attr("loads")(text); }

}  // namespace purkinje::python
