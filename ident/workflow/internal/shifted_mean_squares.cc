#include "ident/workflow/internal/shifted_mean_squares.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "common/error.h"

namespace ident::workflow::internal {

ShiftedMeanSquares::ShiftedMeanSquares(DataSource& source, int columns)
    : source_(source),
      columns_(columns),
      centre_rows_(std::clamp(kCentreValues / std::max(columns, 1), 1L, static_cast<long>(kCentreRows))),
      centre_(Eigen::VectorXd::Zero(columns)),
      shifted_(columns),
      z_(source.num_parameters()),
      sum_(Eigen::VectorXd::Zero(source.num_parameters() + 1)),
      sum_squares_(Eigen::VectorXd::Zero(source.num_parameters() + 1)) {
  IDENT_REQUIRE(source.affine_in_rows(), "{}: the regressor is not affine in the rows", source.structure());
  held_.reserve(static_cast<std::size_t>(centre_rows_ * columns));
  source_.Reset();
}

void ShiftedMeanSquares::Add(const Eigen::Ref<const Eigen::VectorXd>& row) {
  if (centred_) {
    shifted_ = row - centre_;
    AddShifted(shifted_);
    return;
  }
  held_.insert(held_.end(), row.data(), row.data() + columns_);
  if (std::ssize(held_) == centre_rows_ * columns_) Centre();
}

void ShiftedMeanSquares::Centre() {
  const long rows = std::ssize(held_) / columns_;
  const Eigen::Map<const Eigen::MatrixXd> held(held_.data(), columns_, rows);  // a row per column
  for (int c = 0; c < columns_; ++c) {  // the mean of the finite values, m ← m + (v − m)/k; 0 if none
    double mean = 0;
    long finite = 0;
    for (long r = 0; r < rows; ++r)
      if (std::isfinite(held(c, r))) mean += (held(c, r) - mean) / static_cast<double>(++finite);
    centre_(c) = std::isfinite(mean) ? mean : 0;
  }
  centred_ = true;
  for (long r = 0; r < rows; ++r) {
    shifted_ = held.col(r) - centre_;
    AddShifted(shifted_);
  }
  held_.clear();
  held_.shrink_to_fit();
}

void ShiftedMeanSquares::AddShifted(const Eigen::Ref<const Eigen::VectorXd>& shifted) {
  // As MeanSquares::Add: the samples with a finite output and regressor.
  const double y = shifted(source_.output_column());
  if (source_.Regressor(shifted, z_) && std::isfinite(y) && AllFinite(z_)) {
    sum_(0) += y;
    sum_squares_(0) += y * y;
    sum_.tail(z_.size()) += z_;
    sum_squares_.tail(z_.size()) += z_.cwiseAbs2();
    ++count_;
  }
  source_.PushOutput(y);
}

Eigen::VectorXd ShiftedMeanSquares::ConstantRegressor(const Eigen::VectorXd& value) const {
  std::unique_ptr<DataSource> walker = source_.Clone();
  walker->Reset();
  Eigen::VectorXd z(source_.num_parameters());
  for (int t = 0; t <= source_.first_regression_index(); ++t) {
    const bool formed = walker->Regressor(value, z);
    walker->PushOutput(value(source_.output_column()));
    if (formed) return z;
  }
  throw InvalidArgument(fmt::format("{}: no regressor after {} constant rows", source_.structure(),
                                    source_.first_regression_index() + 1));
}

Eigen::VectorXd ShiftedMeanSquares::Get(const Eigen::VectorXd& offset) {
  if (!centred_) Centre();
  source_.Reset();
  if (count_ == 0) return sum_squares_;            // zeros, as MeanSquares gives them
  const Eigen::VectorXd shift = centre_ - offset;  // the rows less the offset are the rows less a, plus this
  Eigen::VectorXd d(sum_.size());
  d(0) = shift(source_.output_column());
  d.tail(z_.size()) = ConstantRegressor(shift) - ConstantRegressor(Eigen::VectorXd::Zero(columns_));
  const double n = static_cast<double>(count_);
  const Eigen::ArrayXd squares = sum_squares_.array() / n + 2 * d.array() * (sum_.array() / n) + d.array().square();
  source_.Reset();
  return squares.max(0).matrix();
}

}  // namespace ident::workflow::internal
