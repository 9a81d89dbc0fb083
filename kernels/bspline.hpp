#pragma once
// B-spline bases on one axis (thesis §3.1): the generic Cox–de Boor path for any degree and any knot vector,
// and the fixed-stencil fast path for linear and quadratic splines on an open uniform knot vector.
// Both return the degree+1 functions that are non-zero at x: the index of the first, values and x-derivatives.
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace mpm {

/// Values and derivatives of the S = degree+1 basis functions non-zero at one coordinate.
template <int S>
struct AxisWeights {
  int first;     ///< index of the first non-zero function
  double w[S];   ///< φ_{first+k}(x)
  double dw[S];  ///< dφ_{first+k}/dx (x)
};

/// A non-decreasing knot vector of one axis; the parametric and the physical domain coincide (thesis §3.1.1).
class KnotVector {
 public:
  /// Open uniform knot vector on [0, length]: the end knots repeated degree+1 times, `cells` knot spans.
  static KnotVector open_uniform(int degree, int cells, double length) {
    std::vector<double> k;
    k.reserve(cells + 2 * degree + 1);
    for (int i = 0; i < degree; ++i) k.push_back(0.0);
    for (int i = 0; i <= cells; ++i) k.push_back(length * i / cells);
    k.back() = length;
    for (int i = 0; i < degree; ++i) k.push_back(length);
    return KnotVector(degree, std::move(k));
  }

  /// Any non-decreasing knot vector with at least one non-empty span between knots degree and n.
  KnotVector(int degree, std::vector<double> knots) : degree_(degree), knots_(std::move(knots)) {
    if (degree < 0 || static_cast<int>(knots_.size()) < 2 * degree + 2)
      throw std::invalid_argument("KnotVector: need at least 2*degree+2 knots");
    if (!std::is_sorted(knots_.begin(), knots_.end()))
      throw std::invalid_argument("KnotVector: knots must be non-decreasing");
    if (!(lo() < hi())) throw std::invalid_argument("KnotVector: empty domain");
  }

  int degree() const { return degree_; }
  int num_functions() const { return static_cast<int>(knots_.size()) - degree_ - 1; }
  const std::vector<double>& knots() const { return knots_; }
  double lo() const { return knots_[degree_]; }
  double hi() const { return knots_[num_functions()]; }

  /// The span index i with knots[i] <= x < knots[i+1] and degree <= i < num_functions(); x = hi() belongs to
  /// the last non-empty span, and x outside the domain is clamped to the nearest span.
  int span_of(double x) const {
    const int n = num_functions();
    if (x >= hi()) {
      int i = n - 1;
      while (knots_[i] == knots_[i + 1]) --i;
      return i;
    }
    if (x <= lo()) {
      int i = degree_;
      while (knots_[i] == knots_[i + 1]) ++i;
      return i;
    }
    const auto it = std::upper_bound(knots_.begin() + degree_, knots_.begin() + n + 1, x);
    return static_cast<int>(it - knots_.begin()) - 1;
  }

 private:
  int degree_;
  std::vector<double> knots_;
};

/// Cox–de Boor recursion with derivatives (thesis §3.1.1). Writes the degree+1 functions non-zero on the span
/// containing x into N and dN (arrays of degree+1) and returns the index of the first. Any degree ≤ 8.
inline int cox_de_boor(const KnotVector& kv, double x, double* N, double* dN) {
  constexpr int max_degree = 8;
  const int p = kv.degree();
  if (p > max_degree) throw std::invalid_argument("cox_de_boor: degree above 8");
  const auto& U = kv.knots();
  const int i = kv.span_of(x);
  x = std::clamp(x, kv.lo(), kv.hi());
  double left[max_degree + 1], right[max_degree + 1], lower[max_degree + 1];
  N[0] = 1.0;
  lower[0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    if (j == p)  // keep degree p-1 (functions i-p+1 .. i) for the derivative formula
      for (int r = 0; r < p; ++r) lower[r] = N[r];
    left[j] = x - U[i + 1 - j];
    right[j] = U[i + j] - x;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      // φ_r^j from the two φ^{j-1} that overlap it; the denominators are knot differences (> 0 on a non-empty span)
      const double t = N[r] / (right[r + 1] + left[j - r]);
      N[r] = saved + right[r + 1] * t;
      saved = left[j - r] * t;
    }
    N[j] = saved;
  }
  // dφ_k^p/dx = p φ_k^{p-1}/(ξ_{k+p} − ξ_k) − p φ_{k+1}^{p-1}/(ξ_{k+p+1} − ξ_{k+1}), k = i−p+r
  for (int r = 0; r <= p; ++r) {
    const int k = i - p + r;
    double d = 0.0;
    if (p == 0) {
      dN[r] = 0.0;
      continue;
    }
    if (r >= 1) d += p * lower[r - 1] / (U[k + p] - U[k]);
    if (r <= p - 1) d -= p * lower[r] / (U[k + p + 1] - U[k + 1]);
    dN[r] = d;
  }
  return i - p;
}

/// Generic path of one axis: Cox–de Boor on any knot vector, degree S-1.
template <int S>
struct CoxDeBoorAxis {
  static constexpr int width = S;
  KnotVector knots;
  AxisWeights<S> operator()(double x) const {
    AxisWeights<S> a;
    a.first = cox_de_boor(knots, x, a.w, a.dw);
    return a;
  }
};

/// The cell of x on a uniform grid of `cells` cells (clamped to the grid) and the local coordinate ξ of x in it.
struct UniformCell {
  int cell;
  double xi;
};
[[gnu::always_inline]] inline UniformCell uniform_cell(double x, double inv_h, int cells) {
  // floor(s) without the libm call, s clamped to [0, cells − ½] first, so the truncation gives a cell in
  // [0, cells − 1] (NaN gives 0). No branch, so that a loop over particles runs in vector lanes
  // (gather_sums_in_lanes); with cells − 1 as the bound GCC branched to skip the truncation of a known integer
  const double s = x * inv_h;
  const int c = static_cast<int>(std::min(cells - 0.5, std::max(0.0, s)));
  return {c, s - c};
}

namespace detail {

/// Coefficient table of UniformAxis<S>, [span class][power a, b, c][function] (see there).
template <int S>
using UniformTable = std::array<std::array<std::array<double, S>, 3>, S == 3 ? 4 : 1>;

template <int S>
constexpr UniformTable<S> uniform_coefficients() {
  if constexpr (S == 3)
    return {{
        {{{0.5, 0.5, 0.0}, {-1.0, 1.0, 0.0}, {0.5, -1.0, 0.5}}},  // interior: uniform B-spline pieces
        {{{1.0, 0.0, 0.0}, {-2.0, 2.0, 0.0}, {1.0, -1.5, 0.5}}},  // first cell: knots 0,0,0,1,2
        {{{0.5, 0.5, 0.0}, {-1.0, 1.0, 0.0}, {0.5, -1.5, 1.0}}},  // last cell: the mirror image
        {{{1.0, 0.0, 0.0}, {-2.0, 2.0, 0.0}, {1.0, -2.0, 1.0}}},  // one cell: Bernstein polynomials
    }};
  else
    return {{{{{1.0, 0.0}, {-1.0, 1.0}, {0.0, 0.0}}}}};  // linear: 1 − ξ, ξ
}

}  // namespace detail

/// Fast path of one axis: degree S-1 ∈ {1, 2} on an open uniform knot vector, from closed-form polynomials.
/// Each function is a + b ξ + c ξ² in the local coordinate ξ ∈ [0, 1] of its cell; interior cells share one row
/// of coefficients, the first and last cell (and a grid of one cell) have their own.
template <int S>
struct UniformAxis {
  static_assert(S == 2 || S == 3, "fast path exists for linear and quadratic splines only");
  static constexpr int width = S;
  /// [span class][power][function], span class = (first cell) + 2 (last cell) for quadratics: a power's
  /// coefficients over the functions are contiguous, so the S functions evaluate as one SIMD vector (stencil.hpp)
  static constexpr detail::UniformTable<S> coefficients = detail::uniform_coefficients<S>();
  double inv_h;  ///< 1 / cell size
  int cells;

  UniformAxis(int cells_, double length) : inv_h(cells_ / length), cells(cells_) {}

  /// The cell of x, clamped to the grid, its local coordinate ξ and its span class.
  struct Location {
    int cell;
    double xi;
    int span_class;
  };
  [[gnu::always_inline]] Location locate(double x) const {
    const UniformCell at = uniform_cell(x, inv_h, cells);
    return {at.cell, at.xi, span_class(at.cell)};
  }
  /// Which row of `coefficients` cell c uses: the open knot vector's end cells differ from the interior ones.
  [[gnu::always_inline]] int span_class(int c) const { return S == 3 ? (c == 0) + 2 * (c == cells - 1) : 0; }

  [[gnu::always_inline]] AxisWeights<S> operator()(double x) const {
    const Location at = locate(x);
    const auto& q = coefficients[at.span_class];
    AxisWeights<S> a;
    a.first = at.cell;
    for (int k = 0; k < S; ++k) {
      a.w[k] = q[0][k] + at.xi * (q[1][k] + at.xi * q[2][k]);
      a.dw[k] = (q[1][k] + 2.0 * at.xi * q[2][k]) * inv_h;
    }
    return a;
  }
};

}  // namespace mpm
