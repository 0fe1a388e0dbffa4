// Triangularise a pre-array in place: A = Q R by Householder reflections, R left in the upper triangle
// of A, Q discarded — the step of every array-form (square-root) filter update.
//
// This is Eigen's own unblocked Householder QR (Eigen::internal::householder_qr_inplace_unblocked; Golub &
// Van Loan, Matrix Computations, alg. 5.2.1) written through Eigen's public Householder primitives
// makeHouseholderInPlace and applyHouseholderOnTheLeft, so R is bit-identical to
// Eigen::HouseholderQR::matrixQR()'s upper triangle for matrices of fewer than 48 columns (HouseholderQR runs
// exactly this loop there). Why not HouseholderQR itself: its compute() also instantiates the blocked
// algorithm and its matrix-product kernels for every fixed size, which never run below 48 columns but
// dominate the compile time of every translation unit that instantiates a fixed size. This loop
// instantiates only the unblocked algorithm.
//
// Preconditions: workspace has at least a.cols() entries. Allocation-free, noexcept.
#pragma once

#include <algorithm>

#include <Eigen/Core>
#include <Eigen/Householder>

namespace ident {

template <typename Derived, typename Workspace>
void TriangularizeInPlace(Eigen::MatrixBase<Derived>& a, Workspace& workspace) noexcept {
  const Eigen::Index rows = a.rows(), cols = a.cols();
  for (Eigen::Index k = 0; k < std::min(rows, cols); ++k) {
    const Eigen::Index remaining_rows = rows - k;
    double tau = 0, beta = 0;
    a.col(k).tail(remaining_rows).makeHouseholderInPlace(tau, beta);  // H_k = I − τ v v', v = [1; essential]
    a(k, k) = beta;
    a.bottomRightCorner(remaining_rows, cols - k - 1)
        .applyHouseholderOnTheLeft(a.col(k).tail(remaining_rows - 1), tau, workspace.data() + k + 1);
  }
}

}  // namespace ident
