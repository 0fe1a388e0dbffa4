// The regression estimators as Python objects: one class `Estimator` over the registry
// (ident/registry/estimator_registry.h); python/ident/estimators.py names them (RLS, Cauchy, Student,
// Huber, CauchyML). update_many runs its loop in C++ with the GIL released.
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "common/error.h"
#include "ident/registry/estimator_registry.h"
#include "ident/workflow/estimator_spec.h"
#include "python/src/bindings.h"

namespace py = pybind11;

namespace ident::python {
namespace {

using RowMajorArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// One estimator and whether it adapts. The lock makes a second thread's call on the same object an
// error instead of a data race (update_many runs without the GIL).
class Estimator {
 public:
  Estimator(const std::string& name, int num_parameters, const workflow::EstimatorSpec& spec) {
    IDENT_REQUIRE(num_parameters >= 1, "n = {}; need at least one parameter", num_parameters);
    const EstimatorSettings settings = spec.Resolve(num_parameters, name);
    estimator_ = MakeRegressionEstimator(settings, num_parameters);
  }

  StepReport Update(double y, const Eigen::Ref<const Eigen::VectorXd>& z) {
    const Guard guard(*this);
    CheckRegressor(z.size());
    if (!enabled_) return {StepStatus::kSkipped};
    return estimator_->Update(y, z);
  }

  py::array_t<std::int8_t> UpdateMany(const RowMajorArray& y, const RowMajorArray& z) {
    IDENT_REQUIRE(y.ndim() == 1, "Y has {} dimensions; need a 1-D array of outputs", y.ndim());
    IDENT_REQUIRE(z.ndim() == 2, "Z has {} dimensions; need a 2-D array, one regressor per row", z.ndim());
    const py::ssize_t count = y.shape(0);
    const int n = estimator_->num_parameters();
    IDENT_REQUIRE(z.shape(0) == count, "Y has {} samples but Z has {} rows", count, z.shape(0));
    IDENT_REQUIRE(z.shape(1) == n, "Z has {} columns; this estimator has {} parameters", z.shape(1), n);
    py::array_t<std::int8_t> status(count);
    std::int8_t* out = status.mutable_data();
    const double* ys = y.data();
    const double* zs = z.data();
    {
      py::gil_scoped_release release;
      const Guard guard(*this);
      for (py::ssize_t t = 0; t < count; ++t) {
        const StepStatus s = enabled_
                                 ? estimator_->Update(ys[t], Eigen::Map<const Eigen::VectorXd>(zs + t * n, n)).status
                                 : StepStatus::kSkipped;
        out[t] = static_cast<std::int8_t>(s);
      }
    }
    return status;
  }

  py::object Predict(const RowMajorArray& z) const {
    const Guard guard(*this);
    const int n = estimator_->num_parameters();
    if (z.ndim() == 1) {
      CheckRegressor(z.shape(0));
      return py::float_(estimator_->Predict(Eigen::Map<const Eigen::VectorXd>(z.data(), n)));
    }
    IDENT_REQUIRE(z.ndim() == 2 && z.shape(1) == n, "z must be a regressor of {} entries or a 2-D array of them", n);
    py::array_t<double> y_hat(z.shape(0));
    const Eigen::VectorXd theta = estimator_->parameters();
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> rows(z.data(),
                                                                                                        z.shape(0), n);
    Eigen::Map<Eigen::VectorXd>(y_hat.mutable_data(), z.shape(0)) = rows * theta;
    return y_hat;
  }

  Eigen::VectorXd parameters() const {
    const Guard guard(*this);
    return estimator_->parameters();
  }
  Eigen::MatrixXd covariance() const {
    const Guard guard(*this);
    return estimator_->covariance();
  }
  void Reset() {
    const Guard guard(*this);
    estimator_->Reset();
  }
  bool BeginPass() {
    const Guard guard(*this);
    return estimator_->BeginPass();
  }
  bool FinishStartup() {
    const Guard guard(*this);
    return estimator_->FinishStartup();
  }
  bool ReconsiderAtEnd() {
    const Guard guard(*this);
    return estimator_->ReconsiderAtEnd();
  }
  const AnyRegressionEstimator& get() const { return *estimator_; }
  bool enabled() const { return enabled_; }
  void set_enabled(bool enabled) { enabled_ = enabled; }

 private:
  class Guard {
   public:
    explicit Guard(const Estimator& e) : lock_(e.mutex_, std::try_to_lock) {
      if (!lock_.owns_lock()) throw std::runtime_error("the estimator is in use by another thread");
    }

   private:
    std::unique_lock<std::mutex> lock_;
  };
  void CheckRegressor(py::ssize_t size) const {
    IDENT_REQUIRE(size == estimator_->num_parameters(), "z has {} entries; this estimator has {} parameters", size,
                  estimator_->num_parameters());
  }

  std::unique_ptr<AnyRegressionEstimator> estimator_;
  bool enabled_ = true;
  mutable std::mutex mutex_;
};

py::object LockInDict(const std::optional<LockInStatus>& status) {
  if (!status) return py::none();
  py::list events;
  for (const RestartEvent& e : status->events) {
    py::dict d;
    d["update"] = e.update;
    d["replayed"] = e.replayed;
    d["dropped"] = e.dropped;
    d["left_out"] = e.left_out;
    d["low_weight_before"] = e.low_weight_before;
    d["low_weight_after"] = e.low_weight_after;
    d["resolved"] = e.resolved;
    d["end_of_data"] = e.end_of_data;
    d["pass"] = e.pass;
    events.append(d);
  }
  py::dict d;
  d["window"] = status->window;
  d["threshold"] = status->threshold;
  d["restart"] = status->restart;
  d["flagged"] = status->flagged;
  d["restarts"] = status->restarts;
  d["low_weight_fraction"] = status->low_weight_fraction;
  d["events"] = events;
  d["start_update"] = status->start_update;
  d["start_window"] = status->start_window;
  d["start_at_end"] = status->start_at_end;
  return d;
}

workflow::EstimatorSpec SpecFrom(std::optional<double> dof, std::optional<int> delta, double forgetting,
                                 bool stabilised, std::optional<double> nu0, std::optional<Eigen::MatrixXd> V0,
                                 bool exact, std::optional<int> lock_in_window, std::optional<double> lock_in_threshold,
                                 bool lock_in_restart, std::optional<long> history_limit) {
  workflow::EstimatorSpec spec;
  spec.dof = dof;
  spec.delta = delta;
  spec.forgetting = forgetting;
  spec.stabilised = stabilised;
  IDENT_REQUIRE(nu0.has_value() == V0.has_value(), "give the prior as both nu0 and V0, or neither");
  if (V0) {
    RegressionPrior prior;
    prior.nu0 = *nu0;
    prior.V0 = *V0;
    prior.Validate();
    spec.prior = prior;
  }
  spec.exact = exact;
  spec.lock_in_window = lock_in_window;
  spec.lock_in_threshold = lock_in_threshold;
  spec.no_lock_in_restart = !lock_in_restart;
  spec.history_limit = history_limit;
  return spec;
}

}  // namespace

void RegisterRegression(py::module_& m) {
  m.def("estimator_names", &RegressionEstimatorNames, "The registered regression estimators' names");
  py::class_<Estimator>(m, "Estimator",
                        "A recursive (or batch reference) regression estimator y = theta'z + e, chosen by name")
      .def(py::init([](const std::string& name, int n, std::optional<double> dof, std::optional<int> delta,
                       double forgetting, bool stabilised, std::optional<double> nu0, std::optional<Eigen::MatrixXd> V0,
                       bool exact, std::optional<int> lock_in_window, std::optional<double> lock_in_threshold,
                       bool lock_in_restart, std::optional<long> history_limit) {
             return std::make_unique<Estimator>(
                 name, n,
                 SpecFrom(dof, delta, forgetting, stabilised, nu0, std::move(V0), exact, lock_in_window,
                          lock_in_threshold, lock_in_restart, history_limit));
           }),
           py::arg("name"), py::arg("n"), py::kw_only(), py::arg("dof") = py::none(), py::arg("delta") = py::none(),
           py::arg("forgetting") = 1.0, py::arg("stabilised") = false, py::arg("nu0") = py::none(),
           py::arg("V0") = py::none(), py::arg("exact") = false, py::arg("lock_in_window") = py::none(),
           py::arg("lock_in_threshold") = py::none(), py::arg("lock_in_restart") = true,
           py::arg("history_limit") = py::none())
      .def("update", &Estimator::Update, py::arg("y"), py::arg("z"),
           "One sample: output y, regressor z (n entries). Returns a StepReport; a NaN sample is rejected, not "
           "raised")
      .def("update_many", &Estimator::UpdateMany, py::arg("Y"), py::arg("Z"),
           "Samples Y[t], Z[t, :] in order, the loop in C++ without the GIL. Returns the StepStatus codes (int8)")
      .def("predict", &Estimator::Predict, py::arg("z"),
           "theta'z for one regressor (a float) or for each row of a 2-D array")
      .def("reset", &Estimator::Reset, "Back to the prior")
      .def("begin_pass", &Estimator::BeginPass,
           "Prepare another pass over the same samples from the current estimate (False: no change possible)")
      .def("finish_startup", &Estimator::FinishStartup,
           "The data have ended during the robust start-up: start from every sample seen")
      .def("reconsider_at_end", &Estimator::ReconsiderAtEnd,
           "The data have ended: keep a restart from the robust fit of every kept sample if its likelihood is "
           "higher (cauchy, student; regressors that do not depend on the estimate)")
      .def_property("enabled", &Estimator::enabled, &Estimator::set_enabled,
                    "False: update() and update_many() skip every sample (status SKIPPED)")
      .def_property_readonly("parameters", &Estimator::parameters, "theta-hat (numpy array, n)")
      .def_property_readonly("covariance", &Estimator::covariance, "Covariance of theta-hat (n x n)")
      .def_property_readonly("name", [](const Estimator& e) { return e.get().name(); })
      .def_property_readonly(
          "kind", [](const Estimator& e) { return e.get().kind(); }, "'recursive' or 'batch'")
      .def_property_readonly("n", [](const Estimator& e) { return e.get().num_parameters(); })
      .def_property_readonly("nu", [](const Estimator& e) { return e.get().nu(); })
      .def_property_readonly("Dy", [](const Estimator& e) { return e.get().Dy(); })
      .def_property_readonly("noise_std", [](const Estimator& e) { return e.get().noise_std(); })
      .def_property_readonly("in_startup", [](const Estimator& e) { return e.get().in_startup(); })
      .def_property_readonly(
          "lock_in", [](const Estimator& e) { return LockInDict(e.get().lock_in()); },
          "The lock-in safeguard's state (a dict), or None");
}

}  // namespace ident::python
