#pragma once
// The extension modules' parts (one source file each, to keep each
// translation unit's pybind11 templates small) and what they share.
//
// Two modules: _purkinje (scenes, truth, rendering and detection in
// memory) and _files (what reads and writes image files and data sets).
// OpenImageIO, which the files need, loads some 260 shared libraries
// (0.26 s); _purkinje does without it, so `import purkinje` is quick and
// _files is imported when a file is first read or written.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "purkinje/models/geometry.h"
#include "purkinje/models/output_file.h"
#include "purkinje/models/rotation.h"
#include "purkinje/models/scene.h"
#include "purkinje/renderer/render.h"
#include "purkinje/studies/compare.h"
#include "purkinje/trackers/scoring.h"

namespace purkinje::python {

namespace py = pybind11;

// A render and what made it (RenderResult in Python): its files need all three.
struct Rendered {
  Scene scene;
  renderer::RenderOptions options;
  renderer::RenderResult result;
};

// A compare study and what made it: its files need the scenes and the
// render options too (write_compare).
struct CompareRun {
  Scene world, assumed;
  studies::CompareStudySettings settings;
  studies::CompareStudy study;
};

// A sweep's results, for writing.
struct SweepRun {
  studies::Sweep sweep;
};

void bind_errors(py::module_& m);
void bind_scene(py::module_& m);
void bind_render(py::module_& m);
void bind_trackers(py::module_& m);
void bind_studies(py::module_& m);

// What a tracker found, as the package's Python classes take it:
// (glints, pupils), each a list of tuples (trackers.cpp).
py::tuple detections_tuple(const trackers::Detections& detections);

// Raises FileNotFoundError with `message` (the library's own, as the
// command line prints it) when `file` does not exist; else returns. Needs
// the GIL.
void raise_if_missing(const std::filesystem::path& file, const std::string& message);

// Runs a reader of `inputs`: what it throws about them (a std::runtime_error
// that is no OutputError, with the command line's message) becomes a
// FileNotFoundError when one of them does not exist, else a ValueError.
// Called holding the GIL (`read` may release it inside).
template <class Read>
auto reading(const std::vector<std::filesystem::path>& inputs, Read read) {
  try {
    return read();
  } catch (const OutputError&) {
    throw;
  } catch (const std::runtime_error& error) {
    for (const std::filesystem::path& input : inputs) raise_if_missing(input, error.what());
    throw std::invalid_argument(error.what());
  }
}

// A camera of `scene` by index (int) or name (str): its index. A name the
// scene lacks is a ValueError naming the cameras, another type a
// TypeError; `who` starts the message ("render"). The range of an index is
// its user's to check.
int camera_index(const Scene& scene, const py::object& camera, const std::string& who);

// The step a long run (generate, calibrate) calls after each unit with
// the GIL released: it takes the GIL, calls progress(done, total) unless
// progress is None, and stops the run on Ctrl-C (Python sees signals only
// when it runs), between units, each of which is all or nothing.
std::function<void()> progress_step(const py::object& progress, std::size_t total);

// Numbers as numpy arrays: a point or vector (3,), a pose (4, 4).
py::array_t<double> array(const Point3& p);
py::array_t<double> array(const Vector3& v);
py::array_t<double> array(const UnitVector3& v);
py::array_t<double> matrix(const Pose& pose);

// The Python json module's loads(text).
py::object json_loads(const std::string& text);

}  // namespace purkinje::python
