#include "common/dense_decompositions.h"

namespace ident::dense {

Eigen::LLT<Eigen::MatrixXd> Llt(const Eigen::MatrixXd& a) { return Eigen::LLT<Eigen::MatrixXd>(a); }

Eigen::LDLT<Eigen::MatrixXd> Ldlt(const Eigen::MatrixXd& a) { return Eigen::LDLT<Eigen::MatrixXd>(a); }

Eigen::FullPivLU<Eigen::MatrixXd> FullPivLu(const Eigen::MatrixXd& a) { return Eigen::FullPivLU<Eigen::MatrixXd>(a); }

Eigen::ColPivHouseholderQR<Eigen::MatrixXd> ColPivQr(const Eigen::MatrixXd& a) {
  return Eigen::ColPivHouseholderQR<Eigen::MatrixXd>(a);
}

Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> SymmetricEigen(const Eigen::MatrixXd& a, int options) {
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a, options);
}

Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> SymmetricEigen2x2(const Eigen::Matrix2d& a, int options) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(a, options);
}

Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> SymmetricTridiagonalEigen(const Eigen::VectorXd& diagonal,
                                                                         const Eigen::VectorXd& subdiagonal,
                                                                         int options) {
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig;
  eig.computeFromTridiagonal(diagonal, subdiagonal, options);
  return eig;
}

Eigen::MatrixXd Inverse(const Eigen::LLT<Eigen::MatrixXd>& llt) {
  return llt.solve(Eigen::MatrixXd::Identity(llt.rows(), llt.cols()));
}

Eigen::MatrixXd Inverse(const Eigen::FullPivLU<Eigen::MatrixXd>& lu) { return lu.inverse(); }

Eigen::MatrixXd LeadingQColumns(const Eigen::ColPivHouseholderQR<Eigen::MatrixXd>& qr, Eigen::Index cols) {
  return qr.householderQ() * Eigen::MatrixXd::Identity(qr.rows(), cols);
}

Eigen::MatrixXd UpperTriangularInverse(const Eigen::MatrixXd& t) {
  return t.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(t.rows(), t.rows()));
}

Eigen::MatrixXd LowerTriangularInverse(const Eigen::MatrixXd& t) {
  return t.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(t.rows(), t.rows()));
}

}  // namespace ident::dense
