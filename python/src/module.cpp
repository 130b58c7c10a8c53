// The range_nlm Python module's native part, range_nlm._range_nlm; range_nlm/__init__.py puts
// the Python-side API on it.
#include "bindings.h"

PYBIND11_MODULE(_range_nlm, m)
{
  namespace python = range_nlm::python;
  m.doc() = "range_nlm's native part: the library's filter, stream, parameters and files on numpy arrays.";
  m.attr("__version__") = RANGE_NLM_VERSION;
  python::bindParameters(m);
  python::bindFilter(m);
  python::bindStream(m);
  python::bindFiles(m);
}
