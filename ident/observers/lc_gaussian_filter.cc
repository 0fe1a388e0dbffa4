#include "ident/observers/lc_gaussian_filter.h"

namespace ident {

// The dynamic filter and the two-state fixed-size filter (MEMS study, benchmarks) are compiled once here.
template class BasicLcGaussianFilter<Eigen::Dynamic>;
template class BasicLcGaussianFilter<2>;

}  // namespace ident
