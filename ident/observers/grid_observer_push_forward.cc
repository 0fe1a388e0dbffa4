// The dynamics step (1) of the grid observer (grid_observer.h): the density before the step carried through
// x ↦ A x + B u onto the moved grid by cubic interpolation of the old grid.
#include <algorithm>
#include <cmath>

#include "ident/observers/grid_observer.h"

namespace ident {
namespace {

// At most 3 × 3 (1 to 3 states): Eigen keeps these on the stack.
using PushMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 3, 3>;
using PushVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 3, 1>;

// Catmull–Rom cubic weights of the nodes base−1 … base+2 at fraction t ∈ [0, 1) past base: exact for
// quadratics, and exactly (0, 1, 0, 0) at t = 0, so a node-onto-node map interpolates nothing.
inline void CubicWeights(double t, double* w) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}

}  // namespace

void GridObserver::PushForward(const Eigen::Ref<const Eigen::MatrixXd>& Ainv,
                               const Eigen::Ref<const Eigen::VectorXd>& shift, const std::array<double, 3>& old_origin,
                               const std::array<double, 3>& old_spacing) {
  // (1): f^d(x) = f_{k−1}(A⁻¹(x − B u)), cubic interpolation in fractional old indices f = f0 + Σ_i j_i G(:, i).
  PushVector new_origin(dim_);
  for (int i = 0; i < dim_; ++i) new_origin(i) = origin_[i] - shift(i);
  PushVector f0(dim_);
  f0.noalias() = Ainv * new_origin;
  PushMatrix G = Ainv;
  OldIndexMap map;
  for (int j = 0; j < dim_; ++j) {
    f0(j) = (f0(j) - old_origin[j]) / old_spacing[j];
    for (int i = 0; i < dim_; ++i) G(j, i) *= spacing_[i] / old_spacing[j];
    map.f0[j] = f0(j);
    for (int i = 0; i < dim_; ++i) map.G[j][i] = G(j, i);
  }
  bool line_path = true;  // lines along axis 0 map into lines along axis 0 of the old grid
  for (int j = 1; j < dim_; ++j) line_path = line_path && G(j, 0) == 0;
  std::fill(q_.begin(), q_.end(), 0.0);
  if (line_path) {
    const int lines = total_ / n_[0];
    for (int line = 0; line < lines; ++line) PushForwardLine(map, line);
  } else {
    for (int idx = 0; idx < total_; ++idx) q_[idx] = InterpolateNode(map, idx);
  }
  for (double& v : q_) v = std::max(0.0, v);  // the cubic's undershoot next to a cut (and a NaN) becomes 0
}

GridObserver::OldLines GridObserver::LinesFeeding(const OldIndexMap& map, const std::array<int, 3>& jl) const {
  // The cubic weights along axes 1 … dim−1, one axis at a time: each old line splits into up to 4.
  OldLines old;
  old.count = 1;
  old.rows[0] = p_.data();
  old.weight[0] = 1;
  int stride = n_[0];
  for (int j = 1; j < dim_ && old.count > 0; ++j) {
    double f = map.f0[j];
    for (int i = 1; i < dim_; ++i) f += jl[i] * map.G[j][i];
    if (!(f > -2 && f < n_[j] + 1)) {
      old.count = 0;
      break;
    }
    const double fb = std::floor(f);
    double w[4];
    CubicWeights(f - fb, w);
    const int base = static_cast<int>(fb) - 1;
    int next = 0;
    std::array<const double*, 16> new_rows{};
    std::array<double, 16> new_w{};
    for (int c = 0; c < old.count; ++c)
      for (int k = 0; k < 4; ++k) {
        const int idx = base + k;
        if (w[k] == 0 || idx < 0 || idx >= n_[j]) continue;
        new_rows[next] = old.rows[c] + static_cast<ptrdiff_t>(idx) * stride;
        new_w[next++] = old.weight[c] * w[k];
      }
    old.count = next;
    old.rows = new_rows;
    old.weight = new_w;
    stride *= n_[j];
  }
  return old;
}

void GridObserver::PushForwardLine(const OldIndexMap& map, int line) {
  // Per line: up to 4^(dim−1) old lines with weights, then a 1-D cubic along axis 0.
  std::array<int, 3> jl{0, 0, 0};
  int r = line;
  for (int i = 1; i < dim_; ++i) {
    jl[i] = r % n_[i];
    r /= n_[i];
  }
  const OldLines old = LinesFeeding(map, jl);
  if (old.count == 0) return;
  const int n0 = n_[0];
  double* out = q_.data() + static_cast<size_t>(line) * n0;
  double a = map.f0[0];
  for (int i = 1; i < dim_; ++i) a += jl[i] * map.G[0][i];
  const double b = map.G[0][0];
  if (std::abs(b - 1) * n0 <= 1e-9 && std::isfinite(a) && std::abs(a) < 4.0 * n0)
    ShiftLine(old, a, out);
  else
    InterpolateLine(old, a, b, out);
}

void GridObserver::ShiftLine(const OldLines& old, double a, double* out) {
  // Constant fraction along the line: the combined old line, then 4 shifted copies.
  const int n0 = n_[0];
  double* tmp = r_.data();
  std::fill(tmp, tmp + n0, 0.0);
  for (int c = 0; c < old.count; ++c) {
    const double wc = old.weight[c];
    const double* src = old.rows[c];
    for (int j = 0; j < n0; ++j) tmp[j] += wc * src[j];
  }
  const double fb = std::floor(a);
  double w[4];
  CubicWeights(a - fb, w);
  for (int k = 0; k < 4; ++k) {
    if (w[k] == 0) continue;
    const int off = static_cast<int>(fb) - 1 + k;  // old index = j + off
    const int lo = std::max(0, -off), hi = std::min(n0, n0 - off);
    const double wk = w[k];
    for (int j = lo; j < hi; ++j) out[j] += wk * tmp[j + off];
  }
}

void GridObserver::InterpolateLine(const OldLines& old, double a, double b, double* out) const {
  // Old index a + b j0 of node j0: the cubic over the combined old lines at each.
  const int n0 = n_[0];
  for (int j0 = 0; j0 < n0; ++j0) {
    const double f = a + b * j0;
    if (!(f > -2 && f < n0 + 1)) continue;
    const double fb = std::floor(f);
    double w[4];
    CubicWeights(f - fb, w);
    const int base = static_cast<int>(fb) - 1;
    double v = 0;
    for (int k = 0; k < 4; ++k) {
      const int idx = base + k;
      if (idx < 0 || idx >= n0 || w[k] == 0) continue;
      double s = 0;
      for (int c = 0; c < old.count; ++c) s += old.weight[c] * old.rows[c][idx];
      v += w[k] * s;
    }
    out[j0] = v;
  }
}

double GridObserver::InterpolateNode(const OldIndexMap& map, int idx) const {
  // Any map: per node, 4^dim old nodes.
  std::array<double, 3> f{};
  int r = idx;
  for (int j = 0; j < dim_; ++j) f[j] = map.f0[j];
  for (int i = 0; i < dim_; ++i) {
    const int ji = r % n_[i];
    r /= n_[i];
    for (int j = 0; j < dim_; ++j) f[j] += ji * map.G[j][i];
  }
  std::array<std::array<double, 4>, 3> w{};
  std::array<int, 3> base{};
  for (int j = 0; j < dim_; ++j) {
    if (!(f[j] > -2 && f[j] < n_[j] + 1)) return 0;  // also NaN
    const double fb = std::floor(f[j]);
    CubicWeights(f[j] - fb, w[j].data());
    base[j] = static_cast<int>(fb) - 1;
  }
  double v = 0;
  const int corners = 1 << (2 * dim_);
  for (int corner = 0; corner < corners; ++corner) {
    double weight = 1;
    int flat = 0, stride = 1;
    for (int j = 0; j < dim_; ++j) {
      const int k = (corner >> (2 * j)) & 3;
      const int id = base[j] + k;
      if (id < 0 || id >= n_[j]) {
        weight = 0;
        break;
      }
      weight *= w[j][k];
      flat += id * stride;
      stride *= n_[j];
    }
    if (weight != 0) v += weight * p_[flat];
  }
  return v;
}

}  // namespace ident
