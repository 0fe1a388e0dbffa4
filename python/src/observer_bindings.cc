// The state observers as Python objects: one class `Observer` over the registry
// (ident/registry/observer_registry.h) and the measurement models it needs; python/ident/observers.py
// names them (KalmanFilter, LcGaussianFilter, GridObserver). A data item is (y(k), u(k−1)).
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "common/error.h"
#include "ident/registry/observer_registry.h"
#include "models/measurement.h"
#include "python/src/bindings.h"

namespace py = pybind11;

namespace ident::python {
namespace {

using RowMajorArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

class Observer {
 public:
  Observer(EstimatorSettings settings, ObserverProblem problem)
      : settings_(std::move(settings)), problem_(std::move(problem)) {
    problem_.model.Validate();
    observer_ = MakeStateObserver(settings_, problem_);
  }

  StepReport Update(double y, const std::optional<Eigen::VectorXd>& u) {
    const Guard guard(*this);
    StateSpaceItem item{u.value_or(Eigen::VectorXd()), y};
    IDENT_REQUIRE(item.u.size() == problem_.model.num_inputs(), "u has {} entries; the model has {} inputs",
                  item.u.size(), problem_.model.num_inputs());
    if (!enabled_) return {StepStatus::kSkipped};
    return observer_->Update(item);
  }

  py::array_t<std::int8_t> UpdateMany(const RowMajorArray& y, const std::optional<RowMajorArray>& u) {
    IDENT_REQUIRE(y.ndim() == 1, "Y has {} dimensions; need a 1-D array of readings", y.ndim());
    const py::ssize_t count = y.shape(0);
    const int m = problem_.model.num_inputs();
    if (m > 0) {
      IDENT_REQUIRE(u.has_value(), "the model has {} inputs; give U (one row u(k-1) per reading)", m);
      IDENT_REQUIRE(u->ndim() == 2 && u->shape(0) == count && u->shape(1) == m,
                    "U must be a {} x {} array (one row u(k-1) per reading)", count, m);
    } else {
      IDENT_REQUIRE(!u.has_value() || u->size() == 0, "the model has no inputs; U must be empty");
    }
    py::array_t<std::int8_t> status(count);
    std::int8_t* out = status.mutable_data();
    const double* ys = y.data();
    const double* us = m > 0 ? u->data() : nullptr;
    {
      py::gil_scoped_release release;
      const Guard guard(*this);
      StateSpaceItem item{Eigen::VectorXd(m), 0.0};
      for (py::ssize_t t = 0; t < count; ++t) {
        item.y = ys[t];
        if (m > 0) item.u = Eigen::Map<const Eigen::VectorXd>(us + t * m, m);
        out[t] = static_cast<std::int8_t>(enabled_ ? observer_->Update(item).status : StepStatus::kSkipped);
      }
    }
    return status;
  }

  Eigen::VectorXd mean() const {
    const Guard guard(*this);
    return observer_->mean();
  }
  Eigen::MatrixXd covariance() const {
    const Guard guard(*this);
    return observer_->covariance();
  }
  double Predict(const std::optional<Eigen::VectorXd>& u) const {
    const Guard guard(*this);
    const StateSpaceItem item{u.value_or(Eigen::VectorXd()), 0.0};
    IDENT_REQUIRE(item.u.size() == problem_.model.num_inputs(), "u has {} entries; the model has {} inputs",
                  item.u.size(), problem_.model.num_inputs());
    return observer_->Predict(item);
  }
  void Reset() {
    const Guard guard(*this);
    observer_->Reset();
  }
  std::string name() const { return observer_->name(); }
  bool enabled() const { return enabled_; }
  void set_enabled(bool enabled) { enabled_ = enabled; }

 private:
  class Guard {
   public:
    explicit Guard(const Observer& o) : lock_(o.mutex_, std::try_to_lock) {
      if (!lock_.owns_lock()) throw std::runtime_error("the observer is in use by another thread");
    }

   private:
    std::unique_lock<std::mutex> lock_;
  };

  EstimatorSettings settings_;
  ObserverProblem problem_;
  std::unique_ptr<AnyStateObserver> observer_;
  bool enabled_ = true;
  mutable std::mutex mutex_;
};

// B and Q default to no inputs and no process noise of their own size.
ObserverProblem Problem(const Eigen::MatrixXd& A, const std::optional<Eigen::MatrixXd>& B, const Eigen::MatrixXd& Q,
                        std::shared_ptr<const models::MeasurementFunction> measurement, const Eigen::VectorXd& x0,
                        const Eigen::MatrixXd& P0) {
  IDENT_REQUIRE(measurement != nullptr, "measurement must not be None");
  ObserverProblem p;
  p.model.A = A;
  p.model.B = B.value_or(Eigen::MatrixXd(A.rows(), 0));
  p.model.process_noise = Q;
  p.measurement = std::move(measurement);
  p.x0 = x0;
  p.P0 = P0;
  return p;
}

}  // namespace

void RegisterObservers(py::module_& m) {
  using Measurement = models::MeasurementFunction;
  py::class_<Measurement, std::shared_ptr<Measurement>>(m, "Measurement", "A measurement model y ~ f(y | x)")
      .def_property_readonly("name", &Measurement::name)
      .def_property_readonly("num_states", &Measurement::num_states)
      .def("log_likelihood", &Measurement::LogLikelihood, py::arg("y"), py::arg("x"), "log f(y | x)");
  py::class_<models::ProjectedMeasurement, Measurement, std::shared_ptr<models::ProjectedMeasurement>>(
      m, "ProjectedMeasurement")
      .def_property_readonly("c", &models::ProjectedMeasurement::c);
  py::class_<models::GaussianMeasurement, models::ProjectedMeasurement, std::shared_ptr<models::GaussianMeasurement>>(
      m, "GaussianMeasurement", "y = c'x + e, e ~ N(0, variance)")
      .def(py::init<Eigen::VectorXd, double>(), py::arg("c"), py::arg("variance"));
  py::class_<models::LaplaceMeasurement, models::ProjectedMeasurement, std::shared_ptr<models::LaplaceMeasurement>>(
      m, "LaplaceMeasurement", "y = c'x + e, e Laplace with the given scale")
      .def(py::init<Eigen::VectorXd, double>(), py::arg("c"), py::arg("scale"));
  py::class_<models::ThresholdSensor, models::ProjectedMeasurement, std::shared_ptr<models::ThresholdSensor>>(
      m, "ThresholdSensor", "y = sign(c'x) if abs(c'x) >= threshold, else 0 (y in {-1, 0, 1})")
      .def(py::init<Eigen::VectorXd, double>(), py::arg("c"), py::arg("threshold"));
  py::class_<models::UniformQuantizer, models::ProjectedMeasurement, std::shared_ptr<models::UniformQuantizer>>(
      m, "UniformQuantizer", "y = step * round(c'x / step)")
      .def(py::init<Eigen::VectorXd, double>(), py::arg("c"), py::arg("step"));

  m.def("observer_names", &StateObserverNames, "The registered observers' names");
  py::class_<Observer>(m, "Observer", "A state observer for x(k) = A x(k-1) + B u(k-1) + v, y(k) ~ measurement")
      .def(py::init([](const std::string& name, const Eigen::MatrixXd& A, const std::optional<Eigen::MatrixXd>& B,
                       const Eigen::MatrixXd& Q, std::shared_ptr<const Measurement> measurement,
                       const Eigen::VectorXd& x0, const Eigen::MatrixXd& P0,
                       const std::map<std::string, std::string>& options) {
             EstimatorSettings settings;
             settings.name = name;
             settings.options = options;
             return std::make_unique<Observer>(settings, Problem(A, B, Q, std::move(measurement), x0, P0));
           }),
           py::arg("name"), py::arg("A"), py::arg("B"), py::arg("Q"), py::arg("measurement"), py::arg("x0"),
           py::arg("P0"), py::arg("options") = std::map<std::string, std::string>{})
      .def("update", &Observer::Update, py::arg("y"), py::arg("u") = py::none(),
           "One step: time update with u(k-1), measurement update with y(k). Returns a StepReport")
      .def("update_many", &Observer::UpdateMany, py::arg("Y"), py::arg("U") = py::none(),
           "Readings Y[k] with inputs U[k, :], the loop in C++ without the GIL. Returns the StepStatus codes")
      .def("predict", &Observer::Predict, py::arg("u") = py::none(),
           "c'(A x + B u): the mean of the measured combination c'x(k) after the time update with u(k-1) "
           "(for a linear-Gaussian measurement the predicted reading); NaN for a measurement without c")
      .def("reset", &Observer::Reset, "Back to the prior N(x0, P0)")
      .def_property("enabled", &Observer::enabled, &Observer::set_enabled,
                    "False: update() and update_many() skip every reading (status SKIPPED)")
      .def_property_readonly("mean", &Observer::mean, "The state estimate (posterior mean)")
      .def_property_readonly("covariance", &Observer::covariance, "Its covariance")
      .def_property_readonly("name", &Observer::name);
}

}  // namespace ident::python
