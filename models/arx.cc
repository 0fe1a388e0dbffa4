#include "models/arx.h"

#include <algorithm>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/error.h"

namespace ident::models {

ArxStructure::ArxStructure(int na, std::vector<int> nb, std::vector<int> nk)
    : na_(na), nb_(std::move(nb)), nk_(std::move(nk)) {
  IDENT_REQUIRE(na_ >= 0, "na = {}; need na >= 0", na_);
  IDENT_REQUIRE(nb_.size() == nk_.size(), "nb has {} entries but nk has {}; need one per input", nb_.size(),
                nk_.size());
  // In 64 bits: orders near INT_MAX must be refused, not wrap around.
  long long num_parameters = na_, t0 = na_;
  for (std::size_t i = 0; i < nb_.size(); ++i) {
    IDENT_REQUIRE(nb_[i] >= 0, "nb = {} for input {}; need nb >= 0", nb_[i], i + 1);
    IDENT_REQUIRE(nk_[i] >= 0, "nk = {} for input {}; need nk >= 0", nk_[i], i + 1);
    num_parameters += nb_[i];
    const long long history = static_cast<long long>(nk_[i]) + nb_[i];
    IDENT_REQUIRE(history <= kMaxHistory, "nk + nb = {} for input {}; need at most {}", history, i + 1, kMaxHistory);
    if (nb_[i] > 0) t0 = std::max(t0, history - 1);
  }
  IDENT_REQUIRE(num_parameters >= 1, "the model has no parameters (na = 0 and nb = 0)");
  IDENT_REQUIRE(num_parameters <= kMaxParameters, "the model has {} parameters; need at most {}", num_parameters,
                kMaxParameters);
  num_parameters_ = static_cast<int>(num_parameters);
  t0_ = static_cast<int>(t0);
}

std::string ArxStructure::ToString() const {
  const char* kind = na_ == 0 ? "FIR" : "ARX";
  if (nb_.size() == 1) return fmt::format("{}({},{},{})", kind, na_, nb_[0], nk_[0]);
  return fmt::format("{}({},[{}],[{}])", kind, na_, fmt::join(nb_, ","), fmt::join(nk_, ","));
}

std::vector<std::string> ArxStructure::ParameterNames() const {
  std::vector<std::string> names;
  for (int k = 1; k <= na_; ++k) names.push_back(fmt::format("a{}", k));
  for (std::size_t i = 0; i < nb_.size(); ++i)
    for (int k = 1; k <= nb_[i]; ++k)
      names.push_back(nb_.size() == 1 ? fmt::format("b{}", k) : fmt::format("b{}_{}", k, i + 1));
  return names;
}

namespace {
OutputCleaningOptions WithWarmUp(OutputCleaningOptions cleaning, int num_parameters) {
  if (cleaning.warm_up == 0) cleaning.warm_up = 10 * num_parameters;
  return cleaning;
}
}  // namespace

ArxRegressor::ArxRegressor(const ArxStructure& structure, const OutputCleaningOptions& cleaning)
    : structure_(structure), cleaner_(WithWarmUp(cleaning, structure.num_parameters())) {
  past_y_.setZero(structure_.na());
  past_cleaned_.assign(static_cast<std::size_t>(structure_.na()), 0);
  int window = 0;
  for (int i = 0; i < structure_.num_inputs(); ++i) {
    if (structure_.input_history(i) > 0) u_heads_.emplace_back(i, window);
    for (int k = 0; k < structure_.nb()[i]; ++k) z_from_u_.push_back(window + structure_.nk()[i] + k);
    window += structure_.input_history(i);
  }
  past_u_.assign(static_cast<std::size_t>(window), 0.0);
  Reset();
}

void ArxRegressor::Reset() {
  past_y_.setZero();
  std::fill(past_cleaned_.begin(), past_cleaned_.end(), 0);
  cleaned_in_window_ = 0;
  std::fill(past_u_.begin(), past_u_.end(), 0.0);
  samples_ = 0;
  outputs_ = 0;
  last_cleaned_ = last_screened_ = false;
  cleaner_.Reset();
}

bool ArxRegressor::Next(const Eigen::Ref<const Eigen::VectorXd>& u, Eigen::Ref<Eigen::VectorXd> z) {
  IDENT_REQUIRE(u.size() == structure_.num_inputs(), "input sample has {} entries; the model has {} inputs", u.size(),
                structure_.num_inputs());
  IDENT_REQUIRE(z.size() == structure_.num_parameters(), "regressor has {} entries; the model has {} parameters",
                z.size(), structure_.num_parameters());
  IDENT_REQUIRE(outputs_ == samples_, "ArxRegressor::Next called twice without PushOutput");
  // Every window moves on by one: a window's oldest value moves into the newest place of the next, which
  // that input's sample then takes.
  for (std::size_t k = past_u_.size(); k-- > 1;) past_u_[k] = past_u_[k - 1];
  for (const auto& [i, window] : u_heads_) past_u_[static_cast<std::size_t>(window)] = u(i);
  const long t = samples_++;
  if (t < structure_.first_regression_index()) return false;
  FillRegressor(z);
  return true;
}

void ArxRegressor::FillRegressor(Eigen::Ref<Eigen::VectorXd> z) const {
  const int na = structure_.na();
  for (int k = 0; k < na; ++k) z(k) = -past_y_(k);
  for (std::size_t j = 0; j < z_from_u_.size(); ++j)
    z(na + static_cast<Eigen::Index>(j)) = past_u_[static_cast<std::size_t>(z_from_u_[j])];
}

void ArxRegressor::PushOutput(double y) {
  IDENT_REQUIRE(outputs_ + 1 == samples_, "ArxRegressor::PushOutput called without Next");
  last_cleaned_ = false;
  // Both windows shift by one in plain loops: they hold na entries, too few for a memmove call to pay.
  const Eigen::Index m = past_y_.size();
  if (m > 0) {
    cleaned_in_window_ -= past_cleaned_[static_cast<std::size_t>(m - 1)];
    for (Eigen::Index k = m - 1; k > 0; --k) {
      past_y_(k) = past_y_(k - 1);
      past_cleaned_[static_cast<std::size_t>(k)] = past_cleaned_[static_cast<std::size_t>(k - 1)];
    }
    past_y_(0) = y;
    past_cleaned_.front() = 0;
  }
  ++outputs_;
}

double ArxRegressor::PushCheckedOutput(double y, double y_hat, double scale, bool flagged, bool judged) {
  const long cleaned_before = cleaner_.cleaned();
  const bool screening = cleaner_.in_warm_up();
  const double stored = cleaner_.Clean(y, y_hat, scale, flagged, judged);
  PushOutput(stored);
  last_measured_ = y;
  last_cleaned_ = cleaner_.cleaned() > cleaned_before;
  last_screened_ = last_cleaned_ && screening;
  if (last_cleaned_ && !past_cleaned_.empty()) {
    past_cleaned_.front() = 1;
    ++cleaned_in_window_;
  }
  return stored;
}

std::optional<bool> ArxRegressor::MeasuredIsNearer(double y) const {
  if (!last_cleaned_ || !last_screened_ || structure_.na() == 0) return std::nullopt;
  return std::abs(y - last_measured_) < std::abs(y - past_y_(0));
}

bool ArxRegressor::MeasuredRegressor(Eigen::Ref<Eigen::VectorXd> z_measured) const {
  if (!last_cleaned_ || structure_.na() == 0 || samples_ <= structure_.first_regression_index()) return false;
  IDENT_REQUIRE(z_measured.size() == structure_.num_parameters(),
                "regressor has {} entries; the model has {} parameters", z_measured.size(),
                structure_.num_parameters());
  // z(t) as Next() formed it, with −y(t−1) measured (the first entry, models/arx.h's ordering).
  FillRegressor(z_measured);
  z_measured(0) = -last_measured_;
  return true;
}

void ArxRegressor::RestoreMeasured() {
  if (!last_cleaned_) return;
  past_y_(0) = last_measured_;
  cleaner_.Restore(last_measured_);
  last_cleaned_ = last_screened_ = false;
  cleaned_in_window_ -= past_cleaned_.front();
  past_cleaned_.front() = 0;
}

std::vector<std::string> StaticRegression::ParameterNames() const {
  std::vector<std::string> names;
  if (intercept) names.push_back("intercept");
  for (const auto& r : regressors) names.push_back(r);
  return names;
}

void StaticRegression::Regressor(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> z) const {
  IDENT_REQUIRE(x.size() == static_cast<Eigen::Index>(regressors.size()), "regressor sample has {} entries; need {}",
                x.size(), regressors.size());
  if (intercept) {
    z(0) = 1.0;
    z.tail(x.size()) = x;
  } else {
    z = x;
  }
}

}  // namespace ident::models
