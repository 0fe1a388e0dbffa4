#include "ident/observers/kalman_filter.h"

namespace ident {

// The dynamic filter and the two-state fixed-size filter (MEMS study, benchmarks) are compiled once here.
template class BasicKalmanFilter<Eigen::Dynamic>;
template class BasicKalmanFilter<2>;

}  // namespace ident
