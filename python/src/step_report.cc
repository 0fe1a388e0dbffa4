// StepStatus and StepReport (common/step_report.h) as Python types.
#include <pybind11/pybind11.h>

#include <string>

#include "common/step_report.h"
#include "python/src/bindings.h"

namespace py = pybind11;

namespace ident::python {

void RegisterStepReport(py::module_& m) {
  py::enum_<StepStatus>(m, "StepStatus", "What one update did (the codes update_many returns)")
      .value("UPDATED", StepStatus::kUpdated)
      .value("SKIPPED", StepStatus::kSkipped)
      .value("REJECTED_INVALID", StepStatus::kRejectedInvalid)
      .value("NUMERICAL_FAILURE", StepStatus::kNumericalFailure);
  py::class_<StepReport>(m, "StepReport",
                         "One update: status, the weight beta(t) given to the sample, nu(t) and the prediction "
                         "error before the update")
      .def_readonly("status", &StepReport::status)
      .def_readonly("weight", &StepReport::weight)
      .def_readonly("nu", &StepReport::nu)
      .def_readonly("prediction_error", &StepReport::prediction_error)
      .def_property_readonly("updated", &StepReport::updated)
      .def("__bool__", &StepReport::updated)
      .def("__repr__", [](const StepReport& r) {
        return "StepReport(status=" + std::string(ToString(r.status)) + ", weight=" + std::to_string(r.weight) +
               ", nu=" + std::to_string(r.nu) + ", prediction_error=" + std::to_string(r.prediction_error) + ")";
      });
}

}  // namespace ident::python
