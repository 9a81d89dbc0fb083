// The vectorisable logarithm (kernels/vector_log.hpp) against libm's, over the whole range of doubles, and the
// values log gives at its special arguments; and which of the two the kernels take in each instruction set.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "kernels/vector_log.hpp"

using namespace mpm;

namespace {

/// |a − b| in units of the last place of b.
double ulps_apart(double a, double b) {
  if (a == b) return 0.0;
  return std::abs(a - b) / (std::nextafter(std::abs(b), std::numeric_limits<double>::infinity()) - std::abs(b));
}

}  // namespace

TEST_CASE("vector_log agrees with libm's log to an ulp", "[vector-log]") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> exponent(-1074.0, 1024.0), near_one(0.999, 1.001), mantissa(0.5, 2.0);
  double worst = 0.0, worst_at = 0.0;
  const auto check = [&](double x) {
    const double e = ulps_apart(vector_log(x), std::log(x));
    if (!(e <= worst)) {  // a NaN counts as the worst
      worst = e;
      worst_at = x;
    }
  };
  for (int n = 0; n < 300000; ++n) {
    check(std::exp2(exponent(rng)));  // subnormals to the largest doubles
    check(near_one(rng));             // where log x ≈ x − 1 must keep its relative accuracy
    check(mantissa(rng));             // both sides of the reduction's √2 split
  }
  for (const double x : {1.0, 2.0, 0.5, std::sqrt(2.0), std::sqrt(0.5), std::nextafter(1.0, 2.0),
                         std::nextafter(1.0, 0.0), std::numeric_limits<double>::denorm_min(),
                         std::numeric_limits<double>::min(), std::numeric_limits<double>::max()})
    check(x);
  INFO("largest difference " << worst << " ulp, at x = " << worst_at);
  CHECK(worst <= 1.0);
}

TEST_CASE("vector_log returns log's values at zero, infinity, negatives and NaN", "[vector-log]") {
  constexpr double inf = std::numeric_limits<double>::infinity();
  CHECK(vector_log(0.0) == -inf);
  CHECK(vector_log(-0.0) == -inf);
  CHECK(vector_log(inf) == inf);
  CHECK(std::isnan(vector_log(-1.0)));
  CHECK(std::isnan(vector_log(-inf)));
  CHECK(std::isnan(vector_log(std::numeric_limits<double>::quiet_NaN())));
  CHECK(vector_log(1.0) == 0.0);
}

TEST_CASE("log_for takes vector_log in AVX2 code and libm's log in SSE2 code", "[vector-log]") {
  for (const double x : {0.37, 1.0 + 1e-9, 2.5e-310, 7.0e300}) {
    CHECK(log_for<Isa::avx2_fma>(x) == vector_log(x));
#if defined(__AVX2__)
    CHECK(log_for<Isa::baseline>(x) == vector_log(x));  // a build for an AVX2 machine: its own code has AVX2
#else
    CHECK(log_for<Isa::baseline>(x) == std::log(x));
#endif
  }
  // the two differ somewhere in these (by an ulp), so the checks above can tell them apart
  bool differ = false;
  for (int i = 1; i < 2000 && !differ; ++i) differ = vector_log(1.0 + i * 1e-3) != std::log(1.0 + i * 1e-3);
  CHECK(differ);
}
