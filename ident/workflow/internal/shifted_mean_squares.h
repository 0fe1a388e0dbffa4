// The mean squares of internal::MeanSquares (y and the regressor z over the estimation part, the rows
// detrended by their means) gathered in the same pass as those means, for a source whose regressor is
// affine in the rows (DataSource::affine_in_rows()). Internal to ident/workflow/.
//
// The rows are taken about a provisional centre a, the mean of the first kCentreRows rows (fewer for a file
// of more than 64 columns: at most 65 536 values are held). Once the means m
// are known, the regressor of the rows less m is the regressor of the rows less a plus the constant
// d = z(a − m) − z(0) (z of constant rows), and y moves by d_y = a_y − m_y, so per entry
//   Σ (z_a + d)² = Σ z_a² + 2 d Σ z_a + n d².
// With a near m (both means of the same data) the sums lose no more digits than the rows' own spread.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "ident/workflow/data_source.h"

namespace ident::workflow::internal {

class ShiftedMeanSquares {
 public:
  static constexpr int kCentreRows = 1024;
  static constexpr long kCentreValues = 1 << 16;

  // Resets `source`, which must be affine in the rows; `columns`: the rows' size.
  ShiftedMeanSquares(DataSource& source, int columns);
  // The next row of the estimation part, as read (not detrended).
  void Add(const Eigen::Ref<const Eigen::VectorXd>& row);
  // The mean squares of the rows less `offset` (their detrending offsets): (mean y², mean z_1², …), as
  // MeanSquares::Get gives them; resets the source.
  Eigen::VectorXd Get(const Eigen::VectorXd& offset);

 private:
  void Centre();                                                          // a from the rows held, then adds them
  void AddShifted(const Eigen::Ref<const Eigen::VectorXd>& shifted);      // a row less a
  Eigen::VectorXd ConstantRegressor(const Eigen::VectorXd& value) const;  // z of rows all equal to `value`

  DataSource& source_;
  int columns_;
  long centre_rows_;          // rows held for the centre
  std::vector<double> held_;  // the first rows, until the centre is known
  Eigen::VectorXd centre_, shifted_, z_, sum_, sum_squares_;
  bool centred_ = false;
  long count_ = 0;
};

}  // namespace ident::workflow::internal
