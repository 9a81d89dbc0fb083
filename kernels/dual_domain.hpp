#pragma once
// Dual domain MPM (DDMPM) on one axis (thesis §2.6.4): piecewise-linear values, but gradients blended with the
// smoothed "dual domain" gradient,
//   ∇̄φ_i(x) = α(x) ∇φ_i(x) + (1 − α(x)) ∇̃φ_i(x),   ∇̃φ_i(x) = Σ_j φ_j(x)/V_j ∫_Ω φ_j ∇φ_i dΩ,
// with V_j = ∫_Ω φ_j dΩ and the weight α(x) = 2 Σ_i φ_i(x) φ_{i+1}(x) of thesis ch. 5 (zero on the cell
// boundaries, 1/2 at a cell's centre). Ω is the grid's domain, so the integrals are those of the uniform P1 basis:
// V_j = h (h/2 at the two end nodes), ∫ φ_j φ'_{j±1} = ±1/2, ∫ φ_j φ'_j = ∓1/2 at the ends and 0 inside.
// In 2D the basis is the tensor product: ∂(φ_i(x) φ_j(y))/∂x ≈ ∇̄φ_i(x) φ_j(y) (TensorBasis).
//
// At x in cell c (nodes c, c+1), ∇̃ reaches the nodes c−1 … c+2: the stencil is 4 functions wide. The axis numbers
// its functions with one ghost function before node 0 and one after node `cells` (function k is node k − 1), so
// that every cell's stencil starts at function c, as a B-spline stencil does (cell_bins.hpp relies on that); the
// ghosts have zero value and gradient everywhere and so never receive mass.
#include <algorithm>

#include "kernels/bspline.hpp"

namespace mpm {

struct DualDomainAxis {
  static constexpr int width = 4;
  double inv_h;  ///< 1 / cell size
  int cells;
  /// Internal-force integration points per particle (DDMPM with sub-points, thesis Table 5.8; 1D): the force
  /// scatter integrates ∇̄φ_i σ_p over the particle's length at this many points (transfer.hpp); 1: at x_p.
  int subpoints = 1;

  DualDomainAxis(int cells_, double length, int subpoints_ = 1)
      : inv_h(cells_ / length), cells(cells_), subpoints(subpoints_) {}

  AxisWeights<4> operator()(double x) const {
    const auto [c, xi] = uniform_cell(x, inv_h, cells);
    AxisWeights<4> a;
    a.first = c;
    a.w[0] = 0.0;
    a.w[1] = 1.0 - xi;
    a.w[2] = xi;
    a.w[3] = 0.0;
    // (1/V_j) ∫ φ_j ∇φ_i for i = j − 1, j, j + 1, in units of 1/h: {−1/2, 0, 1/2} inside; at an end node V_j = h/2
    // and the integral of φ_j φ'_j is ∓1/2, which gives the one-sided {0, −1, 1} and {−1, 1, 0}
    auto dual_row = [&](int node, double row[3]) {
      row[0] = node == 0 ? 0.0 : node == cells ? -1.0 : -0.5;
      row[1] = node == 0 ? -1.0 : node == cells ? 1.0 : 0.0;
      row[2] = node == cells ? 0.0 : node == 0 ? 1.0 : 0.5;
    };
    double left[3], right[3];
    dual_row(c, left);
    dual_row(c + 1, right);
    const double smooth[4] = {(1.0 - xi) * left[0], (1.0 - xi) * left[1] + xi * right[0],
                              (1.0 - xi) * left[2] + xi * right[1], xi * right[2]};
    const double linear[4] = {0.0, -1.0, 1.0, 0.0};
    const double alpha = 2.0 * (1.0 - xi) * xi;
    for (int k = 0; k < 4; ++k) a.dw[k] = (alpha * linear[k] + (1.0 - alpha) * smooth[k]) * inv_h;
    return a;
  }
};

}  // namespace mpm
