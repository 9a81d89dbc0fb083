#pragma once
// Global interpolating cubic spline in 1D: the function reconstruction of the cubic-spline (CS) mapping,
// thesis §3.2.1. Data (x_p, f_p), p = 1..M, with x_1 < … < x_M (the particles of a 1D body, sorted); the spline
// z is a cubic z_p on every [x_p, x_{p+1}] (thesis eq. 3.2) that interpolates the data (eq. 3.1) and whose value,
// first and second derivative are continuous at the interior data points. Two more conditions fix it:
//   natural      z''(x_1) = z''(x_M) = 0 — the thesis' choice (§3.2.1, last listed property);
//   not-a-knot   z''' continuous at x_2 and x_{M−1} — reproduces cubics exactly (the thesis notes the end
//                condition "is not fundamental" and may be replaced by any that keeps the spline unique).
// The unknowns are the second derivatives M_p = z''(x_p); continuity of z' at the interior points gives the
// tridiagonal system
//   h_{p−1} M_{p−1} + 2 (h_{p−1} + h_p) M_p + h_p M_{p+1} = 6 [(f_{p+1} − f_p)/h_p − (f_p − f_{p−1})/h_{p−1}],
// h_p = x_{p+1} − x_p, solved by the Thomas algorithm (diagonally dominant for both end conditions: no pivoting).
// K fields share the knots, so the matrix is eliminated once for all of them.
//
// Outside [x_1, x_M] the spline is extrapolated by its end cubics (thesis Fig. 3.3: the reconstruction "involves
// extrapolation" where the domain extends past the last data point).
//
// Equal positions: interpolation needs distinct x_p (eq. 3.2). Points closer than `merge_distance` to the
// previous (kept) point are merged into it — position and values averaged over the merged points — so a
// near-duplicate cannot make an h_p of round-off size and blow the second derivatives up.
//
// No allocation after the first fit of a given size: the buffers are reused (clear() keeps their capacity).
#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <vector>

namespace mpm {

enum class SplineEnd { natural, not_a_knot };

template <int K>
class CubicSpline {
 public:
  using Values = Eigen::Matrix<double, K, 1>;

  /// Forgets the data (keeps the buffers).
  void clear() {
    x_.clear();
    f_.clear();
    count_.clear();
    fitted_ = false;
  }

  /// Appends a data point; x must not decrease. A point within `merge_distance` of the last kept point is
  /// averaged into it (see the header comment).
  void push(double x, const Values& f, double merge_distance = 0.0) {
    if (!x_.empty() && x < x_.back() - merge_distance)
      throw std::invalid_argument("CubicSpline::push: positions must not decrease");
    if (!x_.empty() && x - x_.back() <= merge_distance) {
      const double n = ++count_.back();
      x_.back() += (x - x_.back()) / n;  // running means
      f_.back() += (f - f_.back()) / n;
    } else {
      x_.push_back(x);
      f_.push_back(f);
      count_.push_back(1);
    }
    fitted_ = false;
  }

  /// Distinct data points after merging.
  std::size_t size() const { return x_.size(); }
  double front() const { return x_.front(); }
  double back() const { return x_.back(); }

  /// Solves for the second derivatives M_p. One point: the constant through it; two: the line (both end
  /// conditions agree there); three with not-a-knot: the parabola through them.
  void fit(SplineEnd end) {
    const std::size_t n = x_.size();
    if (n == 0) throw std::invalid_argument("CubicSpline::fit: no data");
    second_.assign(n, Values::Zero());
    fitted_ = true;
    if (n <= 2) return;
    if (end == SplineEnd::not_a_knot && n == 3) {
      // the unique parabola: z'' = 2 f[x_1, x_2, x_3] everywhere, which satisfies every continuity condition
      const Values d = 2.0 * (slope(1) - slope(0)) / (x_[2] - x_[0]);
      for (auto& m : second_) m = d;
      return;
    }
    assemble(end);
    thomas();
    if (end == SplineEnd::not_a_knot) {
      // recover the end values eliminated in assemble(): z''' continuous at x_2 and x_{M−1}
      const double h0 = h(0), h1 = h(1), hm = h(n - 2), hl = h(n - 3);
      second_[0] = ((h0 + h1) * second_[1] - h0 * second_[2]) / h1;
      second_[n - 1] = ((hm + hl) * second_[n - 2] - hm * second_[n - 3]) / hl;
    }
  }

  /// z(x) (thesis eq. 3.2); the end cubics extrapolate outside [x_1, x_M].
  Values operator()(double x) const {
    if (!fitted_) throw std::logic_error("CubicSpline: evaluated before fit()");
    const std::size_t n = x_.size();
    if (n == 1) return f_[0];
    // interval p with x_p ≤ x < x_{p+1}, clamped to the end intervals
    const auto it = std::upper_bound(x_.begin() + 1, x_.end() - 1, x);
    const std::size_t p = static_cast<std::size_t>(it - x_.begin()) - 1;
    const double hp = h(p), t = x - x_[p];
    // z_p(x) = f_p + t [Δf/h − h (2 M_p + M_{p+1})/6] + t² M_p/2 + t³ (M_{p+1} − M_p)/(6h)
    const Values b = slope(p) - hp * (2.0 * second_[p] + second_[p + 1]) / 6.0;
    return f_[p] + t * (b + t * (0.5 * second_[p] + t * (second_[p + 1] - second_[p]) / (6.0 * hp)));
  }

 private:
  double h(std::size_t p) const { return x_[p + 1] - x_[p]; }
  Values slope(std::size_t p) const { return (f_[p + 1] - f_[p]) / h(p); }

  /// The rows p = 1..M−2 of the system for M_1..M_{M−2} (sub-, main and super-diagonal, right-hand sides).
  /// Natural: M_1 = M_M = 0 drop out. Not-a-knot: M_1 = ((h_1 + h_2) M_2 − h_1 M_3)/h_2 is substituted into the
  /// first row (and likewise at the other end), which keeps the system tridiagonal; rows scaled by h_2 (h_{M−2}).
  void assemble(SplineEnd end) {
    const std::size_t n = x_.size(), rows = n - 2;
    lower_.assign(rows, 0.0);
    diag_.assign(rows, 0.0);
    upper_.assign(rows, 0.0);
    rhs_.assign(rows, Values::Zero());
    for (std::size_t r = 0; r < rows; ++r) {
      const std::size_t p = r + 1;
      lower_[r] = h(p - 1);
      diag_[r] = 2.0 * (h(p - 1) + h(p));
      upper_[r] = h(p);
      rhs_[r] = 6.0 * (slope(p) - slope(p - 1));
    }
    if (end != SplineEnd::not_a_knot) return;
    const double h0 = h(0), h1 = h(1);
    diag_[0] = (h0 + h1) * (h0 + 2.0 * h1);
    upper_[0] = (h1 - h0) * (h1 + h0);
    rhs_[0] *= h1;
    // the last row (the first one too when M = 4; M = 3 is the parabola of fit())
    const double hm = h(n - 2), hl = h(n - 3);  // last interval and the one before it
    lower_[rows - 1] = (hl - hm) * (hl + hm);
    diag_[rows - 1] = (hl + hm) * (2.0 * hl + hm);
    rhs_[rows - 1] *= hl;
  }

  /// Thomas algorithm on the assembled rows; the solution goes to second_[1..M−2].
  void thomas() {
    const std::size_t rows = diag_.size();
    for (std::size_t r = 1; r < rows; ++r) {  // forward elimination
      const double w = lower_[r] / diag_[r - 1];
      diag_[r] -= w * upper_[r - 1];
      rhs_[r] -= w * rhs_[r - 1];
    }
    second_[rows] = rhs_[rows - 1] / diag_[rows - 1];  // back substitution
    for (std::size_t r = rows - 1; r-- > 0;) second_[r + 1] = (rhs_[r] - upper_[r] * second_[r + 2]) / diag_[r];
  }

  std::vector<double> x_;
  std::vector<Values> f_;
  std::vector<int> count_;
  std::vector<Values> second_;  ///< M_p = z''(x_p)
  std::vector<double> lower_, diag_, upper_;
  std::vector<Values> rhs_;
  bool fitted_ = false;
};

}  // namespace mpm
