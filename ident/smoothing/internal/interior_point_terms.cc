#include "ident/smoothing/internal/interior_point_terms.h"

#include "common/dense_decompositions.h"
#include "common/error.h"

namespace ident::internal::interior_point {

std::unique_ptr<Prepared> PreparePenalty(const Penalty& pen, double sigma) {
  auto prep = std::make_unique<Prepared>();
  prep->scaled = pen.plq();
  PlqForm& f = prep->scaled;
  f.p /= sigma;
  f.b /= sigma;
  f.lo /= sigma;
  f.hi /= sigma;
  f.p0 /= sigma * sigma;
  prep->plq = &f;
  prep->k = f.rows();
  prep->m = pen.dim();
  prep->constant = !(f.lo.array().isFinite().any() || f.hi.array().isFinite().any());
  prep->identity_B = f.B.rows() == f.B.cols() && f.B.isIdentity(0.0) && f.b.isZero(0.0) && f.p.isZero(0.0);
  if (prep->constant) {
    const Eigen::LLT<Eigen::MatrixXd> llt = dense::Llt(f.M);
    IDENT_REQUIRE(llt.info() == Eigen::Success, "{} penalty: M must be positive definite without bounds", pen.Name());
    prep->Kinv = dense::Inverse(llt);
    prep->W = f.B.transpose() * prep->Kinv * f.B;
    prep->c0 = f.p - f.B.transpose() * (prep->Kinv * f.b);
  } else if (!f.diagonal_M) {
    prep->K.resize(prep->k, prep->k);
    prep->KinvB.resize(prep->k, prep->m);
  }
  return prep;
}

}  // namespace ident::internal::interior_point
