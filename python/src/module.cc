// ident._ident: the compiled part of the Python package `ident` (python/ident/ is the public face).
// Library errors become ValueError with the library's one-line message.
#include <pybind11/pybind11.h>

#include "common/error.h"
#include "python/src/bindings.h"

PYBIND11_MODULE(_ident, m) {
  m.doc() = "ident's compiled core: recursive robust estimators, observers and the fit/compare workflow";
  pybind11::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ident::InvalidArgument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const ident::DataError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  ident::python::RegisterStepReport(m);
  ident::python::RegisterRegression(m);
  ident::python::RegisterObservers(m);
  ident::python::RegisterWorkflow(m);
#ifdef IDENT_DATASETS_DIR
  m.attr("source_datasets_dir") = IDENT_DATASETS_DIR;
#else
  m.attr("source_datasets_dir") = "";
#endif
}
