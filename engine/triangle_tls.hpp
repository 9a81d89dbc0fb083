#pragma once
// The TLS reconstruction on one triangle (thesis §6.1.2): the Taylor basis of the reference triangle, fitted by
// least squares to the particles' values, evaluated at the triangle's Gauss points. The density and the momentum
// density keep the first coefficient fixed by the particle sums (thesis eq. 5.9), so the grid receives exactly
// Σ m_p and Σ m_p v_p; the stress is fitted without the constraint: its mean over the triangle is then the fit's,
// not the particle-volume sum that carries MPM's integration error.
#include <Eigen/Dense>
#include <array>
#include <cstddef>
#include <span>

#include "engine/triangle_mesh.hpp"
#include "kernels/reconstruction.hpp"

namespace mpm {

/// Dunavant's 6-point rule on the reference triangle, degree 4: exact for P1 × the quadratic Taylor basis.
/// Barycentric points (ξ1, ξ2) and weights summing to 1 (to be multiplied by the area).
struct TriangleGauss {
  static constexpr int points = 6;
  static constexpr double a = 0.445948490915965, wa = 0.223381589678011;
  static constexpr double b = 0.091576213509771, wb = 0.109951743655322;
  static constexpr std::array<std::array<double, 2>, points> xi{
      {{a, a}, {1 - 2 * a, a}, {a, 1 - 2 * a}, {b, b}, {1 - 2 * b, b}, {b, 1 - 2 * b}}};
  static constexpr std::array<double, points> w{wa, wa, wa, wb, wb, wb};
};

/// Taylor basis functions on the reference triangle at (ξ1, ξ2) (thesis eqs 6.1–6.3 with Δx = 1/2, centroid
/// (1/3, 1/3); eqs 6.16–6.17). Every function but the first has zero mean over the triangle. The mixed term is
/// 4(ξ1 − 1/3)(ξ2 − 1/3) + 1/9: the mean of (ξ1 − 1/3)(ξ2 − 1/3) over the triangle is −1/36, so eq. 6.18's
/// + 1/18 leaves a mean of −1/18 and would break the conservation of eq. 5.9.
inline std::array<double, 6> triangle_taylor(double s, double t) {
  const double ds = s - 1.0 / 3.0, dt = t - 1.0 / 3.0;
  return {1.0, 2 * ds, 2 * dt, 2 * ds * ds - 1.0 / 9.0, 2 * dt * dt - 1.0 / 9.0, 4 * ds * dt + 1.0 / 9.0};
}

/// Number of Taylor functions of a degree in 2D.
constexpr int triangle_taylor_size(int degree) { return (degree + 1) * (degree + 2) / 2; }

/// The fields of one triangle at its Gauss points: ρ, ρv (2), σ (xx, xy, yy).
struct TriangleFields {
  static constexpr int count = 6;  // ρ | ρv0, ρv1 | σ00, σ01, σ11
  std::array<std::array<double, TriangleGauss::points>, count> at{};
};

/// A particle's data for a fit: its reference coordinates in the triangle being fitted and its values.
struct TriangleSample {
  double s, t;
  std::array<double, TriangleFields::count> f;  // ρ_p, ρ_p v_p, σ_p
};

/// Fits the triangle's fields to `own` (its particles) or, where they do not determine a fit of `degree`, to
/// `own` + `near` (the particles of its edge neighbours), then lower degrees down to a constant; the first
/// three fields keep their first coefficient at `totals` / area (ρ: Σ m_p, ρv: Σ m_p v_p). The fallback taken
/// is counted in `counts`. Returns the fields at the Gauss points.
inline TriangleFields fit_triangle(std::span<const TriangleSample> own, std::span<const TriangleSample> near,
                                   const std::array<double, 3>& totals, double area, int degree,
                                   FallbackCounts& counts) {
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
  constexpr int C = TriangleFields::count;
  const auto attempt = [&](int deg, bool with_near, TriangleFields& out) {
    const int K = triangle_taylor_size(deg);
    Matrix D = Matrix::Zero(K, K);
    std::array<Vector, C> rhs;
    for (auto& r : rhs) r = Vector::Zero(K);
    std::size_t n = 0;
    const auto add = [&](std::span<const TriangleSample> samples) {
      for (const auto& p : samples) {
        const auto psi6 = triangle_taylor(p.s, p.t);
        const Eigen::Map<const Vector> psi(psi6.data(), K);
        D.noalias() += psi * psi.transpose();
        for (int c = 0; c < C; ++c) rhs[c].noalias() += p.f[c] * psi;
        ++n;
      }
    };
    add(own);
    if (with_near) add(near);
    if (n < static_cast<std::size_t>(K)) return false;
    std::array<Vector, C> coef;
    if (K > 1) {
      // constrained fields: c₁ fixed, the rest from the normal equations of the mean-free functions
      const Matrix Dr = D.bottomRightCorner(K - 1, K - 1);
      Eigen::ColPivHouseholderQR<Matrix> qr_r(Dr);
      qr_r.setThreshold(1e-8);
      Eigen::ColPivHouseholderQR<Matrix> qr(D);
      qr.setThreshold(1e-8);
      if (qr_r.rank() < K - 1 || qr.rank() < K) return false;
      for (int c = 0; c < C; ++c) {
        coef[c] = Vector::Zero(K);
        if (c < 3) {
          coef[c][0] = totals[c] / area;
          const Vector r = rhs[c].tail(K - 1) - coef[c][0] * D.bottomLeftCorner(K - 1, 1);
          coef[c].tail(K - 1) = qr_r.solve(r);
        } else {
          coef[c] = qr.solve(rhs[c]);
        }
      }
    } else {
      for (int c = 0; c < C; ++c) coef[c] = Vector::Constant(1, c < 3 ? totals[c] / area : rhs[c][0] / D(0, 0));
    }
    for (int g = 0; g < TriangleGauss::points; ++g) {
      const auto psi6 = triangle_taylor(TriangleGauss::xi[g][0], TriangleGauss::xi[g][1]);
      const Eigen::Map<const Vector> psi(psi6.data(), K);
      for (int c = 0; c < C; ++c) out.at[c][g] = coef[c].dot(psi);
    }
    return true;
  };
  TriangleFields out;
  if (attempt(degree, false, out)) return out;
  if (attempt(degree, true, out)) {
    ++counts.neighbour;
    return out;
  }
  for (int deg = degree - 1; deg >= 1; --deg)
    if (attempt(deg, true, out)) {
      ++counts.degree;
      return out;
    }
  attempt(0, false, out);  // a triangle with particles always has a constant fit
  ++counts.constant;
  return out;
}

}  // namespace mpm
