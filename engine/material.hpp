#pragma once
// Constitutive laws σ(F) (thesis eqs 2.13, 2.14), as small value types chosen once per run (std::variant), so the
// particle loop calls a concrete, inlinable function. 1D keeps the axis component of the 3D law under uniaxial
// strain; 2D is plane strain.
#include <algorithm>
#include <cmath>
#include <variant>

#include "engine/scene.hpp"
#include "kernels/vector_log.hpp"
#include "kernels/views.hpp"

namespace mpm {

struct Lame {
  double lambda, mu;
  static Lame from(const MaterialSpec& m) {
    return {m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu)), m.E / (2 * (1 + m.nu))};
  }
};

/// Small-strain linear elasticity, eq. 2.13: σ = λ tr(ε) I + 2μ ε, ε = ½(F + Fᵀ) − I.
struct LinearElastic {
  Lame k;
  template <int Dim, Isa = Isa::baseline>
  void stress(const double* F, double* s) const {
    if constexpr (Dim == 1) {
      s[0] = (k.lambda + 2 * k.mu) * (F[0] - 1.0);
    } else {
      const double e00 = F[0] - 1.0, e11 = F[3] - 1.0, e01 = 0.5 * (F[1] + F[2]);
      const double tr = e00 + e11;
      s[0] = k.lambda * tr + 2 * k.mu * e00;
      s[1] = 2 * k.mu * e01;
      s[2] = k.lambda * tr + 2 * k.mu * e11;
    }
  }
  /// P-wave speed at volume ratio J (constant for the linear law).
  double wave_speed(double, double rho0) const { return std::sqrt((k.lambda + 2 * k.mu) / rho0); }
  /// Strain energy per reference volume, ½ σ:ε.
  template <int Dim>
  double energy_density(const double* F) const {
    double s[sym_components<Dim>];
    stress<Dim>(F, s);
    if constexpr (Dim == 1) return 0.5 * s[0] * (F[0] - 1.0);
    else return 0.5 * (s[0] * (F[0] - 1.0) + 2 * s[1] * 0.5 * (F[1] + F[2]) + s[2] * (F[3] - 1.0));
  }
};

/// Compressible neo-Hookean, eq. 2.14: σ = (λ ln J / J) I + (μ/J)(F Fᵀ − I). The stress takes its log by
/// log_for<I> (vector_log in AVX2 code), so that the gather's batch of stresses runs in vector lanes.
struct NeoHookean {
  Lame k;
  /// σ(F) in code compiled for instruction set I (the laws' stress<Dim, I>; the default: the build's own).
  template <int Dim, Isa I = Isa::baseline>
  void stress(const double* F, double* s) const {
    if constexpr (Dim == 1) {
      const double J = F[0];
      s[0] = (k.lambda * log_for<I>(J) + k.mu * (J * J - 1.0)) / J;
    } else {
      const double J = F[0] * F[3] - F[1] * F[2];
      const double a = k.lambda * log_for<I>(J), inv_J = 1.0 / J;
      s[0] = (a + k.mu * (F[0] * F[0] + F[1] * F[1] - 1.0)) * inv_J;
      s[1] = k.mu * (F[0] * F[2] + F[1] * F[3]) * inv_J;
      s[2] = (a + k.mu * (F[2] * F[2] + F[3] * F[3] - 1.0)) * inv_J;
    }
  }
  /// Current P-wave speed at volume ratio J, from the uniaxial tangent dP/dF = (λ(1 − ln J) + μ(J² + 1))/J²
  /// of the 1D law (J taken as the stretch), mapped to the current configuration (× J).
  double wave_speed(double J, double rho0) const {
    const double tangent = (k.lambda * (1 - std::log(J)) + k.mu * (J * J + 1)) / (J * J);
    return J * std::sqrt(std::max(tangent, 0.0) / rho0);
  }
  /// ψ = μ/2 (tr FᵀF − d) − μ ln J + λ/2 (ln J)², per reference volume.
  template <int Dim>
  double energy_density(const double* F) const {
    double trC = 0.0;
    for (int c = 0; c < Dim * Dim; ++c) trC += F[c] * F[c];
    const double J = Dim == 1 ? F[0] : F[0] * F[3] - F[1] * F[2];
    const double lnJ = std::log(J);
    return 0.5 * k.mu * (trC - Dim) - k.mu * lnJ + 0.5 * k.lambda * lnJ * lnJ;
  }
};

using Material = std::variant<LinearElastic, NeoHookean>;

inline Material make_material(const MaterialSpec& spec) {
  const Lame k = Lame::from(spec);
  if (spec.model == MaterialModel::neo_hookean) return NeoHookean{k};
  return LinearElastic{k};
}

/// P-wave speed in the reference state, sqrt((λ + 2μ)/ρ0): the speed that limits the explicit time step.
inline double wave_speed(const MaterialSpec& spec) {
  const Lame k = Lame::from(spec);
  return std::sqrt((k.lambda + 2 * k.mu) / spec.density);
}

}  // namespace mpm
