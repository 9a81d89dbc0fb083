#pragma once
// Local maximum-entropy (max-ent) basis on one axis of a uniform grid (thesis §4.3, Arroyo & Ortiz): at x, the
// φ_i ≥ 0 of largest entropy −Σ φ_i ln(φ_i / w_i) relative to the prior w_i with Σ φ_i = 1 and Σ φ_i (x_i − x) = 0
// (eqs 4.36–4.38), i.e. φ_i = w_i exp(μ t_i) / Z with t_i = (x − x_i)/h and μ minimising ln Z (eqs 4.39–4.42),
// found by Newton's method. The prior is the thesis' cubic spline of r = |x − x_i| / (d_max h) (eqs 4.46–4.48;
// ζ_i = h on a uniform grid), so a node reaches d_max ≤ 2 cells and the stencil holds the nodes c − 1 … c + 2 of
// a point in cell c: numbered as DualDomainAxis numbers them (dual_domain.hpp: one ghost function before node 0
// and one after node `cells`, zero everywhere), every cell's stencil starts at its own index, and only those
// nodes are visited (thesis Table 4.1 computed every node for every point).
//
// In 2D the basis is the tensor product of two axes: with the product prior w_i(x1) w_j(x2) on a tensor grid the
// max-ent problem separates, and its solution is exactly the product of the 1D solutions. The thesis uses the
// radial prior w(‖x − x_i‖) instead (eq. 4.46), whose support is a disc rather than a square.
//
// Derivative: with y_i = x − x_i, differentiating the constraint Σ φ_i y_i = 0 gives dμ/dx and
//   dφ_i/dt = φ_i (γ_i − Σ_j φ_j γ_j − (1 + A) t_i / H),  γ_i = (dw_i/dt)/w_i,  H = Σ φ_j t_j²,  A = Σ φ_j t_j γ_j
// (the 1D form of eq. 4.43, sign convention of λ aside), with φ_i γ_i formed as w'_i e^{μ t_i}/Z, finite where
// w_i vanishes. The thesis prints dw/dr on (1/2, 1] as −4 + 8r − 12r²; the derivative of eq. 4.48 is −4 + 8r − 4r².
#include <algorithm>
#include <cmath>

#include "kernels/bspline.hpp"

namespace mpm {

struct MaxEntAxis {
  static constexpr int width = 4;
  double h, inv_h;
  int cells;
  double dmax;  ///< support radius of a node's prior, in cells, 1 < d_max ≤ 2 (at d_max = 1 a node's neighbours lie
                ///< on the edge of its support and the basis degenerates to a Kronecker delta there)

  MaxEntAxis(int cells_, double length, double dmax_)
      : h(length / cells_), inv_h(cells_ / length), cells(cells_), dmax(dmax_), inv_dmax(1.0 / dmax_) {
    for (int cls = 0; cls < classes; ++cls)
      for (int j = 0; j <= samples; ++j) {
        const double xi = std::clamp(double(j) / samples, inset, 1.0 - inset);
        Point pt = point(cls, xi);
        start_mu[cls][j] = solve(pt, 0.0);  // a class without its end's nodes still has ≥ 2 nodes with a prior
      }
  }

  /// The cubic-spline prior w(r) and dw/dr (thesis eq. 4.48; its derivative corrected, see above). Branch-free:
  /// which piece applies depends on where the point lies in its cell, which a branch would mispredict.
  static void prior(double r, double& w, double& dw) {
    const double a = std::max(1.0 - r, 0.0);  // 4/3 − 4r + 4r² − 4r³/3 = 4a³/3: zero, not below, past r = 1
    const bool inner = r <= 0.5;
    w = inner ? 2.0 / 3.0 - 4.0 * r * r + 4.0 * r * r * r : 4.0 / 3.0 * a * a * a;
    dw = inner ? -8.0 * r + 12.0 * r * r : -4.0 * a * a;
  }

  AxisWeights<4> operator()(double x) const {
    // On the ends of the node set (its convex hull) the basis is interpolatory; a hair inside them the Newton
    // iteration converges, so points at or beyond an end are evaluated there.
    x = std::clamp(x, inset * h, cells * h - inset * h);
    const auto [c, xi] = uniform_cell(x, inv_h, cells);
    const int cls = (c == 0) + 2 * (c == cells - 1);
    Point pt = point(cls, xi);
    // μ(ξ) of the cell's class, tabulated, is a start one or two Newton steps from the solution
    const double s = xi * samples;
    const int j = std::min(static_cast<int>(s), samples - 1);
    solve(pt, start_mu[cls][j] + (s - j) * (start_mu[cls][j + 1] - start_mu[cls][j]));
    AxisWeights<4> a;
    a.first = c;
    const double inv_Z = pt.inv_Z;
    double A = 0.0, gbar = 0.0, pg[4];
    for (int k = 0; k < 4; ++k) {
      a.w[k] = pt.e[k] * inv_Z;
      pg[k] = pt.dw[k] * pt.scale[k] * inv_Z;  // φ_k γ_k = w'_k e^{μ t_k} / Z
      gbar += pg[k];
      A += pg[k] * pt.t[k];
    }
    const double c_t = (1.0 + A) / pt.H;
    for (int k = 0; k < 4; ++k) a.dw[k] = (pg[k] - a.w[k] * (gbar + c_t * pt.t[k])) * inv_h;
    return a;
  }

 private:
  double inv_dmax;
  static constexpr double inset = 1e-9;  ///< in cells
  static constexpr int samples = 32;     ///< of μ(ξ) per cell class
  /// Cell classes: interior, first cell (no node c − 1), last cell (no node c + 2), the only cell (neither).
  static constexpr int classes = 4;
  double start_mu[classes][samples + 1];

  /// One point's Newton state: per stencil node c − 1 + k, t_k = (x − x_k)/h, the prior and its t-derivative;
  /// e_k = w_k e^{μ t_k} up to a common factor (scale_k: that factor without w_k), 1/Σ e_k, F = Σ e_k t_k / Z,
  /// and H = Σ e_k t_k² / Z.
  struct Point {
    double t[4], w[4], dw[4], e[4], scale[4], inv_Z, F, H;
  };

  Point point(int cls, double xi) const {
    Point pt;
    for (int k = 0; k < 4; ++k) {
      pt.t[k] = xi + 1.0 - k;
      pt.w[k] = pt.dw[k] = 0.0;
      if ((k == 0 && cls & 1) || (k == 3 && cls & 2)) continue;  // beyond an end of the node set
      double dwdr;
      prior(std::abs(pt.t[k]) * inv_dmax, pt.w[k], dwdr);
      pt.dw[k] = dwdr * inv_dmax * std::copysign(1.0, pt.t[k]);
    }
    return pt;
  }

  /// e^{μ t_k} = e^{μ(ξ + 1)} q^k with q = e^{−μ}: one exponential per evaluation; the common factor cancels.
  static void evaluate(Point& pt, double mu) {
    const double q = std::exp(-std::clamp(mu, -200.0, 200.0));
    double qk = 1.0, Z = 0.0, F = 0.0, H = 0.0;
    for (int k = 0; k < 4; ++k, qk *= q) {
      pt.scale[k] = qk;
      pt.e[k] = pt.w[k] * qk;
      Z += pt.e[k];
      F += pt.e[k] * pt.t[k];
      H += pt.e[k] * pt.t[k] * pt.t[k];
    }
    pt.inv_Z = 1.0 / Z;
    pt.F = F * pt.inv_Z;
    pt.H = H * pt.inv_Z;
  }

  /// Newton on F(μ) = Σ φ_i t_i = d ln Z / dμ, F' = Σ φ_i t_i² − F² > 0: ln Z is convex, so a step that does not
  /// reduce |F| is halved. The residual is measured against F' (near an end of the node set F' → 0, and the
  /// derivative divides by it); a step that cannot reduce it has met round-off. Returns μ; pt holds its state.
  static double solve(Point& pt, double mu) {
    evaluate(pt, mu);
    for (int it = 0; it < 100; ++it) {
      const double slope = pt.H - pt.F * pt.F, before = std::abs(pt.F);
      if (before <= 1e-15 * slope) break;
      double step = -pt.F / slope;
      evaluate(pt, mu + step);
      // a full step that does not reduce |F| close to the solution has met round-off; far from it, halve
      for (int half = 0; !(std::abs(pt.F) < before); ++half, step *= 0.5) {
        if (half == 60 || before <= 1e-10 * slope) {
          evaluate(pt, mu);  // keep μ
          return mu;
        }
        evaluate(pt, mu + 0.5 * step);
      }
      mu += step;
    }
    return mu;
  }
};

}  // namespace mpm
