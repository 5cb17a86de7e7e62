// Library errors as Python exceptions with the command line's messages:
// bad input is a ValueError (SceneError and DatasetSpecError are its
// subclasses), a missing input file a FileNotFoundError, an output that
// cannot be written an OSError (OutputError). std::invalid_argument
// becomes ValueError and std::runtime_error RuntimeError (pybind11's own
// translations).

#include "bindings.h"

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
