#pragma once
// sin and cos of one period over [0, L] from a table and a short series: for the exact solutions of manufactured
// problems, which evaluate the same sin(2π X/L) and cos(2π X/L) of the fixed reference positions at every sample.
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>

namespace mpm {

/// sin(k x) and cos(k x), k = 2π/L, for x in [0, L]: the table holds both at 1025 equally spaced nodes (16 KB),
/// and the angle-sum formulas add the remainder b = k (x − x_i) from the nearest node, |b| ≤ π/1024, by its Taylor
/// series (truncation below 1e-21). Agrees with libm's sin and cos to the rounding of the argument k x, ≤ 1.6e-15
/// (tests/test_periodic_sine.cpp), at a fraction of their cost; the table is built once per problem.
class PeriodicSine {
 public:
  static constexpr int intervals = 1024;

  explicit PeriodicSine(double length)
      : k_(2 * std::numbers::pi / length), step_(length / intervals), inv_step_(intervals / length) {
    for (int i = 0; i <= intervals; ++i) {
      const double phase = 2 * std::numbers::pi * i / intervals;
      sin_[i] = std::sin(phase);
      cos_[i] = std::cos(phase);
    }
  }

  /// sin and cos at the table node nearest x, and the remainder b = k (x − x_i): the table reads of operator(),
  /// apart from its arithmetic (rotate), so that a batch can read first and compute in vector lanes after.
  struct Node {
    double sin_i, cos_i, b;
  };
  /// x outside [0, L] is referred to the nearest end node (correct, less accurate far out).
  Node node(double x) const {
    const int i = std::clamp(static_cast<int>(x * inv_step_ + 0.5), 0, intervals);
    return {sin_[i], cos_[i], k_ * (x - i * step_)};
  }
  /// (sin k x, cos k x) from the node's values and the remainder's series (reciprocals of the factorials as
  /// constants: a division costs a multiplication's latency several times over).
  static std::pair<double, double> rotate(double sin_i, double cos_i, double b) {
    const double b2 = b * b;
    const double sin_b = b * (1 - b2 * (1.0 / 6) * (1 - b2 * (1.0 / 20)));                 // b − b³/3! + b⁵/5!
    const double cos_b = 1 - b2 * 0.5 * (1 - b2 * (1.0 / 12) * (1 - b2 * (1.0 / 30)));  // 1 − b²/2! + b⁴/4! − b⁶/6!
    return {sin_i * cos_b + cos_i * sin_b, cos_i * cos_b - sin_i * sin_b};
  }
  /// (sin k x, cos k x).
  std::pair<double, double> operator()(double x) const {
    const Node n = node(x);
    return rotate(n.sin_i, n.cos_i, n.b);
  }

 private:
  double k_, step_, inv_step_;
  std::array<double, intervals + 1> sin_, cos_;
};

}  // namespace mpm
