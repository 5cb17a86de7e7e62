// The extension module purkinje._purkinje; the package (python/purkinje)
// wraps it. Every part lives in a file of its own (bindings.h).

#include "bindings.h"
#include "purkinje/models/version.h"

PYBIND11_MODULE(_purkinje, m) {
  namespace python = purkinje::python;
  m.doc() = "purkinje's C++ core; use the purkinje package, which wraps it.";
  m.attr("__version__") = purkinje::version();
  python::bind_errors(m);
  python::bind_scene(m);
  python::bind_render(m);
  python::bind_trackers(m);
  python::bind_studies(m);
}
