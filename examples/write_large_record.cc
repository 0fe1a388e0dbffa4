// Writes a long synthetic input-output record as CSV, for testing `ident fit` on large files.
//
//   write_large_record PATH [ROWS=10000000] [SEED=1]
//
// System (ARX(2,2,1), stable poles 0.75 ± 0.37i):
//   y(t) = 1.5 y(t−1) − 0.7 y(t−2) + 1.0 u(t−1) + 0.5 u(t−2) + e(t),
//   u(t) ~ N(0, 1) white (persistently exciting), e(t) ~ N(0, 0.1²). Columns: t,u,y (10^7 rows ≈ 330 MB).
// `ident fit PATH --output y --input u --na 2 --nb 2 --nk 1` recovers θ = (−1.5, 0.7, 1.0, 0.5)
// (ident's ARX sign convention: A(q) = 1 + a1 q⁻¹ + a2 q⁻²).
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include <fmt/format.h>

int main(int argc, char** argv) {
  if (argc < 2 || argc > 4) {
    std::fprintf(stderr, "usage: write_large_record PATH [ROWS=10000000] [SEED=1]\n");
    return 2;
  }
  const long rows = argc > 2 ? std::atol(argv[2]) : 10'000'000L;
  const unsigned seed = argc > 3 ? static_cast<unsigned>(std::atol(argv[3])) : 1u;
  if (rows < 1) {
    std::fprintf(stderr, "write_large_record: ROWS = %s; need at least 1\n", argv[2]);
    return 1;
  }
  std::FILE* out = std::fopen(argv[1], "w");
  if (!out) {
    std::perror(argv[1]);
    return 1;
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  double y1 = 0, y2 = 0, u1 = 0, u2 = 0;
  fmt::print(out, "t,u,y\n");
  for (long t = 0; t < rows; ++t) {
    const double u = n01(rng);
    const double y = 1.5 * y1 - 0.7 * y2 + 1.0 * u1 + 0.5 * u2 + 0.1 * n01(rng);
    fmt::print(out, "{},{:.9g},{:.9g}\n", t, u, y);
    y2 = y1;
    y1 = y;
    u2 = u1;
    u1 = u;
  }
  if (std::fclose(out) != 0) {
    std::perror(argv[1]);
    return 1;
  }
  return 0;
}
