// B-spline bases (thesis §3.1): properties of the generic Cox–de Boor path, and the fast path against it.
#include <limits>
#include <random>

#include <catch2/catch.hpp>

#include "kernels/bspline.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/stencil.hpp"

using namespace mpm;

namespace {

/// Points covering every span densely, including both ends and the knots themselves.
std::vector<double> sample_points(int cells, double length, int random_count, unsigned seed) {
  std::vector<double> xs;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, length);
  for (int i = 0; i < random_count; ++i) xs.push_back(u(rng));
  for (int c = 0; c <= cells; ++c) xs.push_back(length * c / cells);
  for (int c = 0; c < cells; ++c)  // just inside each span's ends
    for (double e : {1e-12, 1 - 1e-12}) xs.push_back(length * (c + e) / cells);
  return xs;
}

/// All function values and derivatives at x from the generic path, as dense vectors.
std::pair<std::vector<double>, std::vector<double>> dense(const KnotVector& kv, double x) {
  std::vector<double> w(kv.num_functions(), 0.0), dw(kv.num_functions(), 0.0);
  double N[9], dN[9];
  const int first = cox_de_boor(kv, x, N, dN);
  for (int k = 0; k <= kv.degree(); ++k) {
    w[first + k] = N[k];
    dw[first + k] = dN[k];
  }
  return {w, dw};
}

}  // namespace

TEST_CASE("Cox-de Boor: partition of unity - non-negativity - boundary interpolation", "[bspline]") {
  for (int p = 1; p <= 4; ++p)
    for (int cells : {1, 2, 3, 7, 16}) {
      const auto kv = KnotVector::open_uniform(p, cells, 2.5);
      REQUIRE(kv.num_functions() == cells + p);
      for (double x : sample_points(cells, 2.5, 200, p * 100 + cells)) {
        const auto [w, dw] = dense(kv, x);
        double sum = 0, dsum = 0;
        for (std::size_t i = 0; i < w.size(); ++i) {
          REQUIRE(w[i] >= -1e-15);
          sum += w[i];
          dsum += dw[i];
        }
        REQUIRE(sum == Approx(1.0).margin(1e-14));
        REQUIRE(dsum == Approx(0.0).margin(1e-12 * cells));
      }
      // open knot vector: only the first (last) function is non-zero at the left (right) end, and it is 1 there
      const auto [w0, dw0] = dense(kv, 0.0);
      const auto [w1, dw1] = dense(kv, 2.5);
      REQUIRE(w0.front() == 1.0);
      REQUIRE(w1.back() == 1.0);
    }
}

TEST_CASE("Cox-de Boor: derivatives match central finite differences", "[bspline]") {
  for (int p = 1; p <= 4; ++p) {
    // a non-uniform knot vector too: derivatives must not assume equal spacing
    for (const KnotVector& kv : {KnotVector::open_uniform(p, 9, 1.0),
                                 KnotVector(p, [&] {
                                   std::vector<double> k(p, 0.0);
                                   for (double x : {0.0, 0.1, 0.15, 0.4, 0.7, 0.72, 1.0}) k.push_back(x);
                                   for (int i = 0; i < p; ++i) k.push_back(1.0);
                                   return k;
                                 }())}) {
      std::mt19937_64 rng(p);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      const auto& knots = kv.knots();
      for (int n = 0; n < 500; ++n) {
        const double x = u(rng), h = 1e-6;
        // skip points whose difference stencil straddles a knot: there the derivative jumps (p = 1) or the
        // difference quotient mixes two polynomials
        bool near_knot = false;
        for (double k : knots) near_knot = near_knot || std::abs(x - k) < 2 * h;
        if (near_knot) continue;
        const auto [w, dw] = dense(kv, x);
        const auto [wp, dwp] = dense(kv, x + h);
        const auto [wm, dwm] = dense(kv, x - h);
        for (std::size_t i = 0; i < w.size(); ++i) REQUIRE(dw[i] == Approx((wp[i] - wm[i]) / (2 * h)).margin(1e-6));
      }
    }
  }
}

TEST_CASE("Cox-de Boor reproduces polynomials of its degree (B-spline coefficients by quasi-interpolation)",
          "[bspline]") {
  // Σ_i ξ*_i φ_i(x) = x with the Greville abscissae ξ*_i = (ξ_{i+1} + ... + ξ_{i+p}) / p
  for (int p = 1; p <= 4; ++p) {
    const auto kv = KnotVector::open_uniform(p, 6, 3.0);
    for (double x : sample_points(6, 3.0, 100, 7)) {
      const auto [w, dw] = dense(kv, x);
      double sum = 0, dsum = 0;
      for (int i = 0; i < kv.num_functions(); ++i) {
        double g = 0;
        for (int k = 1; k <= p; ++k) g += kv.knots()[i + k];
        g /= p;
        sum += g * w[i];
        dsum += g * dw[i];
      }
      REQUIRE(sum == Approx(x).margin(1e-13));
      REQUIRE(dsum == Approx(1.0).margin(1e-12));
    }
  }
}

template <int S>
void check_fast_equals_generic(int cells, double length, int count) {
  const UniformAxis<S> fast(cells, length);
  const CoxDeBoorAxis<S> generic{KnotVector::open_uniform(S - 1, cells, length)};
  double worst = 0.0;
  for (double x : sample_points(cells, length, count, 42 + cells)) {
    const auto a = fast(x), b = generic(x);
    // On a knot both neighbouring spans are valid: x/h and the knot comparison may round to different sides.
    // Then compare the functions as dense vectors; linear derivatives jump there, so they are not compared.
    if (a.first != b.first) {
      REQUIRE(std::abs(x * cells / length - std::round(x * cells / length)) < 1e-9);
      std::vector<double> wa(cells + S, 0.0), wb(cells + S, 0.0);
      for (int k = 0; k < S; ++k) {
        wa[a.first + k] = a.w[k];
        wb[b.first + k] = b.w[k];
      }
      for (int i = 0; i < cells + S - 1; ++i) worst = std::max(worst, std::abs(wa[i] - wb[i]));
      continue;
    }
    for (int k = 0; k < S; ++k) {
      worst = std::max(worst, std::abs(a.w[k] - b.w[k]));
      // derivatives scale with 1/h; compare relative to it
      worst = std::max(worst, std::abs(a.dw[k] - b.dw[k]) * length / cells);
    }
  }
  INFO("S = " << S << ", cells = " << cells << ", worst = " << worst);
  // 1e-13, plus the rounding of the local coordinate x/h − c itself (≈ ε·x/h, each path rounds it its own way),
  // which only matters on very fine grids
  REQUIRE(worst <= 1e-13 + 4 * std::numeric_limits<double>::epsilon() * cells);
}

TEST_CASE("fast path equals Cox-de Boor to 1e-13 at 1e5 points - every span - 1D", "[bspline][fast]") {
  for (int cells : {1, 2, 3, 5, 64, 1000}) {
    check_fast_equals_generic<2>(cells, 1.7, 100000);
    check_fast_equals_generic<3>(cells, 1.7, 100000);
  }
}

TEST_CASE("fast path equals Cox-de Boor to 1e-13 at 1e5 points - 2D tensor product", "[bspline][fast]") {
  const int c0 = 7, c1 = 3;
  TensorBasis<2, UniformAxis<3>> fast{{UniformAxis<3>(c0, 1.0), UniformAxis<3>(c1, 0.5)}, {c0 + 2, c1 + 2}};
  TensorBasis<2, CoxDeBoorAxis<3>> generic{
      {CoxDeBoorAxis<3>{KnotVector::open_uniform(2, c0, 1.0)}, CoxDeBoorAxis<3>{KnotVector::open_uniform(2, c1, 0.5)}},
      {c0 + 2, c1 + 2}};
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0, worst_sum = 0.0;
  for (int n = 0; n < 100000; ++n) {
    // every fifth point on a cell boundary line, so the boundary spans of both axes are hit exactly
    double x[2] = {u(rng), 0.5 * u(rng)};
    if (n % 5 == 0) x[0] = std::floor(x[0] * c0) / c0;
    if (n % 7 == 0) x[1] = 0.5 * std::floor(2 * x[1] * c1) / c1;
    const auto sf = stencil_at<2, 3>(fast, x);
    const auto sg = stencil_at<2, 3>(generic, x);
    std::vector<std::array<double, 3>> a, b;
    for_each_node(sf, c0 + 2, [&](int i, double w, const std::array<double, 2>& g) { a.push_back({double(i), w, g[0] + g[1]}); });
    for_each_node(sg, c0 + 2, [&](int i, double w, const std::array<double, 2>& g) { b.push_back({double(i), w, g[0] + g[1]}); });
    double sum = 0;
    for (std::size_t k = 0; k < a.size(); ++k) {
      REQUIRE(a[k][0] == b[k][0]);
      worst = std::max({worst, std::abs(a[k][1] - b[k][1]), std::abs(a[k][2] - b[k][2]) / c0});
      sum += a[k][1];
    }
    worst_sum = std::max(worst_sum, std::abs(sum - 1.0));
  }
  REQUIRE(worst <= 1e-13);
  REQUIRE(worst_sum <= 1e-14);
}

TEST_CASE("Gauss-Legendre rules integrate polynomials of degree 2n-1 exactly", "[quadrature]") {
  for (int n = 1; n <= 10; ++n) {
    const GaussRule r = gauss_legendre(n);
    for (int k = 0; k <= 2 * n - 1; ++k) {
      double q = 0;
      for (int i = 0; i < n; ++i) q += r.w[i] * std::pow(r.x[i], k);
      REQUIRE(q == Approx(1.0 / (k + 1)).margin(1e-14));
    }
  }
}
