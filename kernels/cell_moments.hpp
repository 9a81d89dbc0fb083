#pragma once
// P2G of the 2D quadratic fast path by cell moments. In a cell, the weights are products of the cell's
// polynomials: φ_ab(x) = wx_a(ξ) wy_b(η), wx_a(ξ) = Σ_k qx[k][a] ξ^k, wy_b(η) = Σ_l qy[l][b] η^l (UniformAxis). So
// what the particles of one cell add to a grid field, Σ_p s_p φ_ab(x_p) (eqs 2.31–2.33, s_p = m_p, m_p v_p, m_p b_p),
// is Σ_kl qx[k][a] qy[l][b] M_kl with the moments M_kl = Σ_p s_p ξ_p^k η_p^l, and the force's gradient terms likewise
// with the derivatives' coefficients. A particle then adds its scalars times the 9 monomials ξ^k η^l to the cell's
// moments (a few vector FMAs) instead of forming its 9 weights and gradients and adding 3 rows to every grid field;
// the moments become node values once per run of particles in one cell. The particles of a cell are contiguous in
// the scatter's order (CellBins sorts them by cell within their block), so at 2×2 particles per cell four particles
// share that work.
#include <array>
#include <cstring>

#include "kernels/stencil.hpp"
#include "kernels/views.hpp"

namespace mpm {

/// The scalars a particle carries into the grid sums, V_p σ_p split by the gradient component they multiply.
struct MomentScalars {
  enum : int { mass, momentum0, momentum1, force0_dx, force1_dx, force0_dy, force1_dy, body0, body1, count };
};

/// Four lanes over the powers k = 0, 1, 2 of ξ (the fourth is zero), or over the functions a of a stencil row (the
/// fourth adds to the grid's ghost column, as RowVector does). A GCC vector, not RowVector: GCC lowers it to the
/// registers of the code's instruction set (one 256-bit register in the AVX2 copy), whereas a RowVector keeps the
/// translation unit's (two SSE2 registers in a portable build); plain arrays GCC did not vectorise at all.
using MomentLanes = double __attribute__((vector_size(4 * sizeof(double))));

/// r += (lane k of m) x: lane k broadcast by one vpermpd with AVX2 (__builtin_shufflevector: GCC ≥ 12 and clang).
template <int k>
MPM_INLINE void add_lane_times(MomentLanes& r, const MomentLanes& m, const MomentLanes& x) {
  r += __builtin_shufflevector(m, m, k, k, k, k) * x;
}

/// Accumulates the moments of the particles of one cell at a time and adds them to the grid when the cell
/// changes (and at finish()). `mass`, `momentum`, `force`, `body`: which grid sums, as ScatterFields.
template <bool mass, bool momentum, bool force, bool body>
class CellMomentScatter {
  using Lanes = MomentLanes;
  using S = MomentScalars;

 public:
  CellMomentScatter(const TensorBasis<2, UniformAxis<3>>& basis, GridView<2> g) : basis_(basis), g_(g) {}

  /// Adds one particle at x with scalars s (indexed by MomentScalars).
  MPM_INLINE void add(const double (&x)[2], const double (&s)[S::count]) {
    const auto at0 = basis_.axis[0].locate(x[0]), at1 = basis_.axis[1].locate(x[1]);
    if (at0.cell != cell0_ || at1.cell != cell1_) {
      finish();
      cell0_ = at0.cell;
      cell1_ = at1.cell;
#pragma GCC unroll 9
      for (int scalar = 0; scalar < S::count; ++scalar)
        if (used(scalar))
          for (Lanes& m : moments_[scalar]) m = Lanes{};
    }
    const double xi = at0.xi, eta = at1.xi;
    const Lanes powers_xi = {1.0, xi, xi * xi, 0.0};
    const Lanes monomials[3] = {powers_xi, eta * powers_xi, (eta * eta) * powers_xi};  // ξ^k η^l by power l of η
#pragma GCC unroll 9
    for (int scalar = 0; scalar < S::count; ++scalar)
      if (used(scalar))
        for (int l = 0; l < powers_of_eta(scalar); ++l) moments_[scalar][l] += s[scalar] * monomials[l];
  }

  /// Adds the moments of the current cell to the grid (none before the first particle).
  MPM_INLINE void finish() {
    if (cell0_ < 0) return;
    const UniformAxis<3>& ax = basis_.axis[0];
    const UniformAxis<3>& ay = basis_.axis[1];
    // axis 0: coefficient rows over the functions a, by power of ξ, of wx and of −wx' = −(qx[1] + 2ξ qx[2]) / h
    const auto& q = detail::padded_uniform<3>[ax.span_class(cell0_)];
    Lanes wx[3];
    for (int k = 0; k < 3; ++k) std::memcpy(&wx[k], q[k].data(), sizeof(Lanes));
    const Lanes minus_dwx[3] = {wx[1] * -ax.inv_h, wx[2] * (-2.0 * ax.inv_h), Lanes{}};
    // axis 1: scalar coefficients [power][function b], of wy and of −wy'
    const auto& wy = UniformAxis<3>::coefficients[ay.span_class(cell1_)];
    double minus_dwy[2][3];
    for (int b = 0; b < 3; ++b) {
      minus_dwy[0][b] = wy[1][b] * -ay.inv_h;
      minus_dwy[1][b] = wy[2][b] * (-2.0 * ay.inv_h);
    }
    // r += Σ_k M_k x[k]: the moments of one power of η contracted over ξ with coefficient rows x, a row over a
    const auto along_x = [](Lanes& r, const Lanes& moments, const Lanes (&x)[3]) MPM_INLINE_LAMBDA {
      add_lane_times<0>(r, moments, x[0]);
      add_lane_times<1>(r, moments, x[1]);
      add_lane_times<2>(r, moments, x[2]);
    };
    // node row b of the field, Σ_l wy[l][b] r[l] (− Σ_l wy'[l][b] r_dy[l]), added to the grid
    const auto add_row = [&](double* field, int b, const Lanes (&r)[3], const Lanes* r_dy) MPM_INLINE_LAMBDA {
      double* dof = field + (cell1_ + b) * g_.stride1 + cell0_;
      Lanes sum = wy[0][b] * r[0] + wy[1][b] * r[1] + wy[2][b] * r[2];
      if (r_dy) sum += minus_dwy[0][b] * r_dy[0] + minus_dwy[1][b] * r_dy[1];
      Lanes grid;
      std::memcpy(&grid, dof, sizeof grid);
      grid += sum;
      std::memcpy(dof, &grid, sizeof grid);
    };
    const auto add_field = [&](double* field, int scalar) MPM_INLINE_LAMBDA {
      Lanes r[3] = {};
      for (int l = 0; l < 3; ++l) along_x(r[l], moments_[scalar][l], wx);
      for (int b = 0; b < 3; ++b) add_row(field, b, r, nullptr);
    };
    if constexpr (mass) add_field(g_.m, S::mass);
    if constexpr (momentum) {
      add_field(g_.q[0], S::momentum0);
      add_field(g_.q[1], S::momentum1);
    }
    if constexpr (force)
      for (int d = 0; d < 2; ++d) {
        // f_ab = Σ_p (φ_ab m b − wx_a' wy_b Vσ_0d − wx_a wy_b' Vσ_1d)   (eq. 2.33)
        Lanes r[3] = {}, r_dy[2] = {};
        for (int l = 0; l < 3; ++l) {
          along_x(r[l], moments_[S::force0_dx + d][l], minus_dwx);
          if constexpr (body) along_x(r[l], moments_[S::body0 + d][l], wx);
        }
        for (int l = 0; l < 2; ++l) along_x(r_dy[l], moments_[S::force0_dy + d][l], wx);
        for (int b = 0; b < 3; ++b) add_row(g_.f[d], b, r, r_dy);
      }
  }

 private:
  static constexpr bool used(int scalar) {
    switch (scalar) {
      case S::mass: return mass;
      case S::momentum0: case S::momentum1: return momentum;
      case S::body0: case S::body1: return body;
      default: return force;
    }
  }
  /// The powers of η a scalar's weights have: wy_b' is linear.
  static constexpr int powers_of_eta(int scalar) { return scalar == S::force0_dy || scalar == S::force1_dy ? 2 : 3; }

  const TensorBasis<2, UniformAxis<3>>& basis_;
  GridView<2> g_;
  int cell0_ = -1, cell1_ = -1;
  Lanes moments_[S::count][3];  // [scalar][power l of η], lanes over the power k of ξ
};

}  // namespace mpm
