#pragma once
// The current extent of a 1D body. Each particle stands for the segment of length V_p = F_p V0_p (thesis eq. 2.42)
// around it, so the body reaches from the first particle's left edge to the last one's right edge (thesis
// Fig. 3.3). The cubic-spline and TLS mappings integrate over it, and the traction bar's load acts at its end.
#include <algorithm>
#include <cstddef>

#include "kernels/views.hpp"

namespace mpm {

struct Extent1d {
  double lo, hi;
};

/// [min_p (x_p − V_p/2), max_p (x_p + V_p/2)] over the n particles of p; with `reference`, of the body at t = 0
/// (X_p ± V0_p/2).
inline Extent1d body_extent_1d(const ParticleView<1>& p, std::size_t n, bool reference = false) {
  Extent1d e{1e300, -1e300};
  for (std::size_t i = 0; i < n; ++i) {
    const double x = reference ? p.X[0][i] : p.x[0][i], half = 0.5 * (reference ? 1.0 : p.F[0][i]) * p.V0[i];
    e.lo = std::min(e.lo, x - half);
    e.hi = std::max(e.hi, x + half);
  }
  return e;
}

}  // namespace mpm
