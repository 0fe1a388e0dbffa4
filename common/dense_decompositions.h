// Eigen's dense decompositions of dynamic-size (and 2 x 2) matrices, constructed in one translation unit
// (common/dense_decompositions.cc).
//
// A decomposition's compute() is a deep template (blocked Cholesky, pivoted LU, Householder QR, the
// tridiagonal QR iteration) that every translation unit constructing one instantiates and compiles again.
// These functions construct it once for the whole library; the caller keeps the returned object and uses
// its read-outs (info(), solve(), matrixL(), eigenvalues(), rank(), ...), which are light. The numbers are
// Eigen's own: the same algorithm on the same matrix (an expression argument is evaluated into a matrix
// first, exactly as the decomposition's constructor evaluates it).
//
// Example:
//   const Eigen::LLT<Eigen::MatrixXd> llt = ident::dense::Llt(Z.transpose() * Z);
//   if (llt.info() != Eigen::Success) ...;
//   const Eigen::VectorXd x = llt.solve(b);
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>

namespace ident::dense {

// A = LL' (Eigen::LLT; info() says whether A is positive definite).
Eigen::LLT<Eigen::MatrixXd> Llt(const Eigen::MatrixXd& a);
// A = P'LDL'P (Eigen::LDLT, robust pivoting).
Eigen::LDLT<Eigen::MatrixXd> Ldlt(const Eigen::MatrixXd& a);
// PAQ = LU with complete pivoting (Eigen::FullPivLU: rank(), isInvertible(), solve(), inverse()).
Eigen::FullPivLU<Eigen::MatrixXd> FullPivLu(const Eigen::MatrixXd& a);
// AP = QR with column pivoting (Eigen::ColPivHouseholderQR).
Eigen::ColPivHouseholderQR<Eigen::MatrixXd> ColPivQr(const Eigen::MatrixXd& a);
// The eigen-decomposition of a symmetric A (lower triangle read; Eigen::SelfAdjointEigenSolver, eigenvalues in
// increasing order). options: Eigen::ComputeEigenvectors or Eigen::EigenvaluesOnly.
Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> SymmetricEigen(const Eigen::MatrixXd& a,
                                                              int options = Eigen::ComputeEigenvectors);
Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> SymmetricEigen2x2(const Eigen::Matrix2d& a,
                                                                 int options = Eigen::ComputeEigenvectors);

// The same from a symmetric tridiagonal matrix: its diagonal and subdiagonal (Eigen's computeFromTridiagonal).
Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> SymmetricTridiagonalEigen(const Eigen::VectorXd& diagonal,
                                                                         const Eigen::VectorXd& subdiagonal,
                                                                         int options = Eigen::ComputeEigenvectors);

// Read-outs that solve for a whole matrix (the blocked triangular solves and Householder products).
// A⁻¹ from A's Cholesky factor: llt.solve(I).
Eigen::MatrixXd Inverse(const Eigen::LLT<Eigen::MatrixXd>& llt);
// A⁻¹ from A's LU factors: lu.inverse() (A must be invertible).
Eigen::MatrixXd Inverse(const Eigen::FullPivLU<Eigen::MatrixXd>& lu);
// The first `cols` columns of the QR factorisation's Q: qr.householderQ() · I(n × cols).
Eigen::MatrixXd LeadingQColumns(const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr, Eigen::Index cols);
// T⁻¹ for the triangular matrix in the upper (lower) triangle of `t`; the other triangle is not read.
Eigen::MatrixXd UpperTriangularInverse(const Eigen::MatrixXd& t);
Eigen::MatrixXd LowerTriangularInverse(const Eigen::MatrixXd& t);

}  // namespace ident::dense
