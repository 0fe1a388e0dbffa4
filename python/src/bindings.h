// The parts of the compiled module ident._ident, one function per concept (python/src/*.cc).
#pragma once

#include <pybind11/pybind11.h>

namespace ident::python {

void RegisterStepReport(pybind11::module_& m);  // step_report.cc
void RegisterRegression(pybind11::module_& m);  // regression_bindings.cc
void RegisterObservers(pybind11::module_& m);   // observer_bindings.cc
void RegisterWorkflow(pybind11::module_& m);    // workflow_bindings.cc

}  // namespace ident::python
