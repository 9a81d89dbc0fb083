#pragma once
// The limiter of the TLS reconstruction at the Gauss points (thesis §6.3.1: what keeps 2D MPM–TLS from diverging).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#include "kernels/stencil.hpp"
#include "kernels/taylor_ls.hpp"

namespace mpm::detail {

/// Bounds the reconstruction at the Gauss points by the data it came from (a Barth–Jespersen-type limiter):
/// per field, the deviations from the cell mean are scaled by the largest α ∈ [0, 1] that keeps every Gauss-point
/// value inside [min, max] of the cell's samples and its mean (`lo`, `hi`: the samples' bounds). The higher
/// Taylor functions integrate to zero over the cell, so scaling them leaves the integral — mass, momentum —
/// exactly as the constraint set it. Without it, a fit through a few clustered particles of a strongly compressed
/// cell extrapolates to wild (even negative) densities at the Gauss points, which is how 2D MPM–TLS diverges
/// (thesis §6.3.1).
/// `psi`: the Taylor basis at the Gauss points, the same in every cell's frame. Inlined: as a call, it reloaded
/// the fit its caller had just stored (the 2×2 TLS step 1–2 % faster inlined, two A/B runs of 5).
template <int Dim, int Degree, int K>
MPM_INLINE void limited_values(const TaylorFit<Dim, Degree, K>& fit, const Eigen::Matrix<double, K, 1>& lo,
                               const Eigen::Matrix<double, K, 1>& hi, std::span<const TaylorVector<Dim, Degree>> psi,
                               Eigen::Matrix<double, K, 1>* values) {
  constexpr int N = TaylorFit<Dim, Degree, K>::size;
  const std::size_t points = psi.size();
  for (int k = 0; k < K; ++k) {
    // The deviations from the mean c_0 are the higher terms alone, Σ_{n≥1} c_n ψ_n: summed directly, not as the
    // value less the mean. (The Eigen form, on 1–3 fields at a time, took 12 % of a 2×2 TLS step's time; these
    // plain loops made the step 3 % faster.)
    const double mean = fit.c(0, k);
    double dev_max = 0.0, dev_min = 0.0;
    for (std::size_t g = 0; g < points; ++g) {
      double dev = 0.0;
      for (int n = 1; n < N; ++n) dev += fit.c(n, k) * psi[g][n];
      values[g][k] = dev;
      dev_max = std::max(dev_max, dev);
      dev_min = std::min(dev_min, dev);
    }
    // α = min(1, (hi − mean) / max dev, (mean − lo) / |min dev|) over the bounds widened to the mean: each ratio
    // falls as |dev| grows (and correctly rounded division keeps that order), so the extreme deviations alone
    // decide — two divisions per field and no branch. A side without deviations divides by +0 and gives +inf or
    // NaN, both of which std::min(α, ·) passes over.
    const double up = std::max(hi[k], mean) - mean, down = mean - std::min(lo[k], mean);
    const double alpha = std::min(std::min(1.0, up / std::abs(dev_max)), down / std::abs(dev_min));
    for (std::size_t g = 0; g < points; ++g) values[g][k] = mean + alpha * values[g][k];
  }
}

}  // namespace mpm::detail
