#pragma once
// The particle fields the MLS and cubic-spline reconstructions fit, per particle.
#include <Eigen/Dense>
#include <array>
#include <cstddef>

#include "kernels/transfer.hpp"

namespace mpm {

/// Per-particle fields the fits read: (ρ, ρv) and (σ, ρb), with ρ = m / (J V0).
template <int Dim, class Body>
struct ParticleFields {
  const ParticleView<Dim>* p;
  const Body* body;
  double volume(std::size_t ip) const { return det(*p, ip) * p->V0[ip]; }  // V_p = J_p V0_p (eq. 2.42)
  double rho(std::size_t ip) const { return p->m[ip] / volume(ip); }
  Eigen::Matrix<double, 1 + Dim, 1> mass(std::size_t ip) const {
    Eigen::Matrix<double, 1 + Dim, 1> f;
    f[0] = rho(ip);
    for (int d = 0; d < Dim; ++d) f[1 + d] = f[0] * p->v[d][ip];
    return f;
  }
  Eigen::Matrix<double, sym_components<Dim> + Dim, 1> stress(std::size_t ip) const {
    Eigen::Matrix<double, sym_components<Dim> + Dim, 1> f;
    for (int c = 0; c < sym_components<Dim>; ++c) f[c] = p->s[c][ip];
    std::array<double, Dim> b{};
    if constexpr (Body::active) b = body->template at<Dim>(ip);
    const double r = rho(ip);
    for (int d = 0; d < Dim; ++d) f[sym_components<Dim> + d] = r * b[d];
    return f;
  }
};

}  // namespace mpm
