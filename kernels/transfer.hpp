#pragma once
// Particle ↔ grid transfers of direct mapping (particles as integration points), thesis Algorithms 1 and 2.
// Each kernel works on a range of particles; the caller decides the parallel schedule (coloured blocks for the
// scatter, plain ranges for the gather). Compile-time flags select which sums a pass computes, so a scheme's
// passes are the paper's steps and nothing more.
#include <algorithm>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "kernels/cell_moments.hpp"
#include "kernels/isa.hpp"
#include "kernels/stencil.hpp"
#include "kernels/views.hpp"

namespace mpm {

/// Which grid sums one P2G pass accumulates.
struct ScatterFields {
  bool mass;      ///< m_i = Σ_p φ_i(x_p) m_p                         (eq. 2.31 lumped)
  bool momentum;  ///< q_i = Σ_p φ_i(x_p) m_p v_p                      (eqs 2.32, 2.48)
  bool force;     ///< f_i = Σ_p (−∇φ_i·σ_p V_p + φ_i m_p b_p)        (eqs 2.33, 2.45; sign of the weak form 2.16)
  /// The basis moves with the body (thesis Algorithms 3–4): φ_i at the reference position X_p, ∇φ_i = F⁻ᵀ ∇_X φ_i,
  /// so f_i = Σ_p (−∇_X φ_i · V0_p adj(F_p) σ_p + φ_i m_p b_p) (eqs 4.30, 4.83 with V_p F⁻¹ = V0_p adj F).
  bool reference = false;
};

/// Which particle updates one G2P pass performs.
struct GatherFields {
  bool velocity;     ///< v_p += Δt Σ_i φ_i a_i                       (eqs 2.39, 2.47)
  bool position;     ///< x_p += Δt Σ_i φ_i v_i                       (eqs 2.38, 2.51)
  bool deformation;  ///< F_p ← (I + Δt Σ_i v_i ⊗ ∇φ_i) F_p, then σ_p (eqs 2.40–2.41, 2.52–2.53)
  /// As ScatterFields::reference; then F_p ← F_p + Δt Σ_i v_i ⊗ ∇_X φ_i, the same update (eqs 4.35, 4.89).
  bool reference = false;
  /// v_p = Δx_p / Δt, the position increment (OTM, thesis eq. 4.53), with `position`.
  bool velocity_from_position = false;
};

/// The columns a particle's basis functions are evaluated at: current or reference positions.
template <bool reference, int Dim>
MPM_INLINE auto basis_points(const ParticleView<Dim>& p) {
  if constexpr (reference) return p.X;
  else return p.x;
}

/// The scatter asks a body force for this many particles at a time (at_batch).
inline constexpr std::size_t body_force_batch = 64;

/// Body force per unit mass: none.
struct NoBodyForce {
  static constexpr bool active = false;
  template <int Dim>
  std::array<double, Dim> at(std::size_t) const { return {}; }
  /// The force at particles index[0..count) into out (a body force's batch form, used by the scatter, in code
  /// compiled for instruction set I).
  template <int Dim, Isa = Isa::baseline>
  void at_batch(const unsigned*, std::size_t, std::array<double, Dim>*) const {}
};

template <int Dim>
inline double det(const ParticleView<Dim>& p, std::size_t i) {
  if constexpr (Dim == 1) return p.F[0][i];
  else return p.F[0][i] * p.F[3][i] - p.F[1][i] * p.F[2][i];
}

/// A sum with its rounding error carried along (Neumaier): totals of many nearly equal terms, like particle
/// masses, would otherwise drift by O(n ε) and hide the P2G round-off that the conservation check measures.
struct CompensatedSum {
  double sum = 0.0, error = 0.0;
  void add(double x) {
    const double t = sum + x;
    error += std::abs(sum) >= std::abs(x) ? (sum - t) + x : (x - t) + sum;
    sum = t;
  }
  CompensatedSum operator+(const CompensatedSum& o) const {
    CompensatedSum r = *this;
    r.add(o.sum);
    r.error += o.error;
    return r;
  }
  double value() const { return sum + error; }
};

/// Particle momentum of a range, Σ m_p v_p and Σ m_p |v_p|, summed as the scatter goes: the conservation check
/// then needs no pass of its own.
template <int Dim>
struct MomentumTotals {
  std::array<double, Dim> mv{};
  double m_abs_v = 0.0;
  void add(double m, const double* v) {
    double v2 = 0.0;
    for (int d = 0; d < Dim; ++d) {
      mv[d] += m * v[d];
      v2 += v[d] * v[d];
    }
    m_abs_v += m * std::sqrt(v2);
  }
  void add(const MomentumTotals& o) {
    for (int d = 0; d < Dim; ++d) mv[d] += o.mv[d];
    m_abs_v += o.m_abs_v;
  }
};

/// Sum of per-block (or per-cell) totals in index order, compensated: deterministic and free of O(n ε) drift.
template <int Dim>
inline MomentumTotals<Dim> sum_totals(const std::vector<MomentumTotals<Dim>>& parts) {
  std::array<CompensatedSum, Dim> mv{};
  CompensatedSum abs_v;
  for (const auto& b : parts) {
    for (int d = 0; d < Dim; ++d) mv[d].add(b.mv[d]);
    abs_v.add(b.m_abs_v);
  }
  MomentumTotals<Dim> r;
  for (int d = 0; d < Dim; ++d) r.mv[d] = mv[d].value();
  r.m_abs_v = abs_v.value();
  return r;
}

/// One carrier's share of the selected grid sums, a stencil row at a time: m_i += φ_i m, q_i += φ_i mv,
/// f_i += φ_i mb − ∇φ_i·Vσ (eqs 2.31–2.33). A particle passes m_p, m_p v_p, V_p σ_p, m_p b_p; a Gauss point its
/// reconstructed ρ̂ω, ρv̂ω, σ̂ω, ρb̂ω (paper eqs 22–25).
template <ScatterFields Fields, int Dim, int S>
MPM_INLINE void scatter_rows(const Stencil<Dim, S>& st, GridView<Dim> g, double m, const double (&mv)[Dim],
                             const double (&Vsig)[Dim][Dim], const double (&mb)[Dim]) {
  // φ_i = wx_i wy and ∇φ_i = (dwx_i wy, wx_i dwy): every row is wx times a scalar, the force's plus dwx times
  // another (f_id = φ_i mb_d − ∂₀φ_i Vσ_0d − ∂₁φ_i Vσ_1d), so the scalars are formed first, the rows last
  for_each_row(st, g.stride1, [&](int row, double wy, double dwy) MPM_INLINE_LAMBDA {
    if constexpr (Fields.mass) add_to_row(g.m + row, st.wx * (wy * m));
    if constexpr (Fields.momentum)
      for (int d = 0; d < Dim; ++d) add_to_row(g.q[d] + row, st.wx * (wy * mv[d]));
    if constexpr (Fields.force)
      for (int d = 0; d < Dim; ++d) {
        double along_wx = wy * mb[d];
        if constexpr (Dim == 2) along_wx -= dwy * Vsig[1][d];
        add_to_row(g.f[d] + row, st.wx * along_wx - st.dwx * (wy * Vsig[0][d]));
      }
  });
}

/// Bases whose force integration may use sub-points (DualDomainAxis).
template <class Axis>
concept WithSubpoints = requires(const Axis& a) { a.subpoints; };

/// DDMPM with sub-points (Dhakal & Zhang 2016, thesis §2.6.4 and Table 5.8), 1D: the internal force of a particle
/// integrated at n points spread evenly over its current length l_p = V_p, each carrying V_p σ_p / n:
/// f_i −= Σ_s ∇̄φ_i(x_s) V_p σ_p / n, instead of ∇̄φ_i(x_p) V_p σ_p. (The points stay within a cell of x_p:
/// Simulation checks l_p < 2h and widens the coloured blocks by that cell.)
template <int S, class Axis>
MPM_INLINE void scatter_subpoint_stress(const TensorBasis<1, Axis>& basis, GridView<1> g, double xp, double V,
                                        double Vsig) {
  const int n = basis.axis[0].subpoints;
  const double share[1][1] = {{Vsig / n}}, none[1] = {0.0};
  for (int s = 0; s < n; ++s) {
    const double xs[1] = {xp + ((s + 0.5) / n - 0.5) * V};
    scatter_rows<ScatterFields{false, false, true}>(stencil_at<1, S>(basis, xs), g, 0.0, none, share, none);
  }
}

/// P2G over particles order[begin..end): adds the selected sums into the grid; returns the particle momentum of
/// the range when momentum is scattered. I: the instruction set the caller is compiled for (with_active_isa).
template <ScatterFields Fields, int Dim, int S, Isa I = Isa::baseline, class Axis, class Body>
inline MomentumTotals<Dim> scatter_p2g(const TensorBasis<Dim, Axis>& basis, ParticleView<Dim> p,
                                       GridView<Dim> g, const unsigned* order, std::size_t begin,
                                       std::size_t end, const Body& body) {
  MomentumTotals<Dim> totals;
  // The body force in a first loop over a batch of particles: a body force may take a log (the plate's), and around
  // it the scatter loop's live vector registers were spilled and reloaded (as in gather_g2p); in a batch its
  // arithmetic runs in vector lanes
  constexpr bool batched_body = Fields.force && Body::active;
  constexpr std::size_t batch = body_force_batch;
  [[maybe_unused]] std::array<double, Dim> body_at[batch];
  // The quadratic fast path in 2D sums the particles of each cell as moments (cell_moments.hpp), in code with AVX2:
  // in SSE2 code GCC keeps their 32-byte vectors in memory, and a scatter took 2–5× the stencil rows' time
  constexpr bool by_moments = has_avx2<I> && Dim == 2 && std::is_same_v<Axis, UniformAxis<3>> && !Fields.reference;
  struct NoMoments {
    NoMoments(const TensorBasis<Dim, Axis>&, GridView<Dim>) {}
  };
  using Moments = std::conditional_t<by_moments,
                                     CellMomentScatter<Fields.mass, Fields.momentum, Fields.force, batched_body>,
                                     NoMoments>;
  [[maybe_unused]] Moments moments(basis, g);
  for (std::size_t first = begin; first < end; first += batch) {
    const std::size_t last = std::min(end, first + batch);
    if constexpr (batched_body)
      body.template at_batch<Dim, I>(order + first, last - first, body_at);
    for (std::size_t k = first; k < last; ++k) {
      const std::size_t ip = order[k];
      const double mp = p.m[ip];
      double mv[Dim] = {};
      if constexpr (Fields.momentum) {
        double vp[Dim];
        for (int d = 0; d < Dim; ++d) {
          vp[d] = p.v[d][ip];
          mv[d] = mp * vp[d];
        }
        totals.add(mp, vp);
      }
      double Vsig[Dim][Dim] = {};  // V_p σ_p
      double mb[Dim] = {};         // m_p b_p
      if constexpr (Fields.force) {
        const double V = det(p, ip) * p.V0[ip];  // eq. 2.42
        if constexpr (Fields.reference && Dim == 2) {  // V F⁻¹ σ = V0 adj(F) σ
          const double adj[2][2] = {{p.F[3][ip], -p.F[1][ip]}, {-p.F[2][ip], p.F[0][ip]}};
          for (int a = 0; a < 2; ++a)
            for (int b = 0; b < 2; ++b) Vsig[a][b] = p.V0[ip] * (adj[a][0] * p.s[sym_index<2>(0, b)][ip] + adj[a][1] * p.s[sym_index<2>(1, b)][ip]);
        } else if constexpr (Fields.reference) {  // V / F = V0
          Vsig[0][0] = p.V0[ip] * p.s[0][ip];
        } else {
          for (int a = 0; a < Dim; ++a)
            for (int b = 0; b < Dim; ++b) Vsig[a][b] = V * p.s[sym_index<Dim>(a, b)][ip];
        }
        if constexpr (batched_body)
          for (int d = 0; d < Dim; ++d) mb[d] = mp * body_at[k - first][d];
        if constexpr (Dim == 1 && WithSubpoints<Axis>)
          if (basis.axis[0].subpoints > 1) {
            scatter_subpoint_stress<S>(basis, g, p.x[0][ip], V, Vsig[0][0]);
            Vsig[0][0] = 0.0;  // the particle itself carries mass, momentum and body force only
          }
      }
      if constexpr (by_moments) {
        using M = MomentScalars;
        const double s[M::count] = {mp,         mv[0],      mv[1],      Vsig[0][0], Vsig[0][1],
                                    Vsig[1][0], Vsig[1][1], mb[0],      mb[1]};
        moments.add({p.x[0][ip], p.x[1][ip]}, s);
      } else {
        scatter_rows<Fields>(stencil_of<Dim, S>(basis, basis_points<Fields.reference>(p), ip), g, mp, mv, Vsig, mb);
      }
    }
  }
  if constexpr (by_moments) moments.finish();
  return totals;
}

/// The sums a gather forms at a batch of particles, from which it updates them: Σ_i φ_i a_i, Σ_i φ_i v_i and
/// ∇v = Σ_i v_i ⊗ ∇φ_i (row-major), per particle of the batch.
template <int Dim, std::size_t N>
struct GatherSums {
  double a[Dim][N], v[Dim][N], grad_v[Dim * Dim][N];
};

/// The gather's sums at particles [first, first + n) by stencil rows: φ_i = wx_i wy_j, so the grid rows are summed
/// weighted by wy_j (and dwy_j) first, and contracted with wx or dwx once.
template <GatherFields Fields, int Dim, int S, class Axis, std::size_t N>
MPM_INLINE void gather_sums_by_rows(const TensorBasis<Dim, Axis>& basis, ParticleView<Dim> p, GridView<Dim> g,
                                    std::size_t first, std::size_t n, GatherSums<Dim, N>& sums) {
  for (std::size_t k = 0; k < n; ++k) {
    const auto st = stencil_of<Dim, S>(basis, basis_points<Fields.reference>(p), first + k);
    RowVector<S> a_y[Dim] = {}, v_y[Dim] = {}, v_dy[Dim] = {};
    for_each_row(st, g.stride1, [&](int row, double wy, double dwy) MPM_INLINE_LAMBDA {
      for (int d = 0; d < Dim; ++d) {
        if constexpr (Fields.velocity) a_y[d] += wy * load_row<RowVector<S>>(g.a[d] + row);
        if constexpr (Fields.position || Fields.deformation) {
          const auto vi = load_row<RowVector<S>>(g.v[d] + row);
          v_y[d] += wy * vi;
          if constexpr (Fields.deformation && Dim == 2) v_dy[d] += dwy * vi;
        }
      }
    });
    for (int d = 0; d < Dim; ++d) {
      if constexpr (Fields.velocity) sums.a[d][k] = reduce(st.wx * a_y[d]);
      if constexpr (Fields.position) sums.v[d][k] = reduce(st.wx * v_y[d]);
      if constexpr (Fields.deformation) {
        sums.grad_v[d * Dim][k] = reduce(st.dwx * v_y[d]);
        if constexpr (Dim == 2) sums.grad_v[d * Dim + 1][k] = reduce(st.wx * v_dy[d]);
      }
    }
  }
}

namespace detail {
/// UniformAxis<3>'s coefficient table as its interior row plus the changes for the first cell, the last cell and
/// a grid of one cell (the last is zero for quadratics): a particle's row of the table is then arithmetic on two
/// flags, which runs in vector lanes, where a lookup by span class would be a gather per coefficient. Exact: the
/// entries are multiples of 1/2.
inline constexpr auto uniform3_rows = [] {
  constexpr auto& t = UniformAxis<3>::coefficients;
  std::array<std::array<std::array<double, 3>, 3>, 4> r{};
  for (int power = 0; power < 3; ++power)
    for (int k = 0; k < 3; ++k) {
      r[0][power][k] = t[0][power][k];
      r[1][power][k] = t[1][power][k] - t[0][power][k];
      r[2][power][k] = t[2][power][k] - t[0][power][k];
      r[3][power][k] = t[3][power][k] - t[1][power][k] - t[2][power][k] + t[0][power][k];
    }
  return r;
}();
}  // namespace detail

/// The gather's sums at particles [first, first + n) of a 2D grid with the fast path's quadratic B-splines, a
/// particle per vector lane: one loop without calls or branches over the unit-stride particle columns, reading the
/// 9 nodes of each lane by index, which GCC vectorises in code with AVX2 (it needs -fno-trapping-math to evaluate
/// both sides of a selection, kernels/CMakeLists.txt). Per particle, the arithmetic of UniformAxis::operator() and
/// of gather_sums_by_rows, the sums over the nodes in another order. The loops over the stencil are unrolled by
/// pragma: the vectoriser takes only a loop with no loop inside.
template <GatherFields Fields, std::size_t N>
MPM_INLINE void gather_sums_in_lanes(const TensorBasis<2, UniformAxis<3>>& basis, ParticleView<2> p, GridView<2> g,
                                     std::size_t first, std::size_t n, GatherSums<2, N>& sums) {
  constexpr auto& rows = detail::uniform3_rows;
  const auto x = basis_points<Fields.reference>(p);
  const int stride = g.stride1;
  for (std::size_t k = 0; k < n; ++k) {
    double w[2][3], dw[2][3];  // per axis: φ and dφ/dx of the 3 functions
    int node0 = 0;             // the stencil's first node
#pragma GCC unroll 2
    for (int d = 0; d < 2; ++d) {
      const UniformAxis<3>& axis = basis.axis[d];
      const UniformCell at = uniform_cell(x[d][first + k], axis.inv_h, axis.cells);
      const double first_cell = at.cell == 0, last_cell = at.cell == axis.cells - 1;
#pragma GCC unroll 3
      for (int i = 0; i < 3; ++i) {
        double q[3];
#pragma GCC unroll 3
        for (int power = 0; power < 3; ++power)
          q[power] = rows[0][power][i] + first_cell * rows[1][power][i] + last_cell * rows[2][power][i] +
                     (first_cell * last_cell) * rows[3][power][i];
        w[d][i] = q[0] + at.xi * (q[1] + at.xi * q[2]);
        dw[d][i] = (q[1] + (2.0 * at.xi) * q[2]) * axis.inv_h;
      }
      node0 += d == 0 ? at.cell : at.cell * stride;
    }
    // as the rows: sums along axis 1 (wy_j, and dwy_j for ∂₁) per node of axis 0, then contracted with wx or dwx
    double a_y[2][3] = {}, v_y[2][3] = {}, v_dy[2][3] = {};
#pragma GCC unroll 3
    for (int j = 0; j < 3; ++j)
#pragma GCC unroll 3
      for (int i = 0; i < 3; ++i) {
        const int node = node0 + j * stride + i;
#pragma GCC unroll 2
        for (int d = 0; d < 2; ++d) {
          if constexpr (Fields.velocity) a_y[d][i] += w[1][j] * g.a[d][node];
          if constexpr (Fields.position || Fields.deformation) {
            const double vi = g.v[d][node];
            v_y[d][i] += w[1][j] * vi;
            if constexpr (Fields.deformation) v_dy[d][i] += dw[1][j] * vi;
          }
        }
      }
#pragma GCC unroll 2
    for (int d = 0; d < 2; ++d) {
      double a = 0.0, v = 0.0, dv0 = 0.0, dv1 = 0.0;
#pragma GCC unroll 3
      for (int i = 0; i < 3; ++i) {
        a += w[0][i] * a_y[d][i];
        v += w[0][i] * v_y[d][i];
        dv0 += dw[0][i] * v_y[d][i];
        dv1 += w[0][i] * v_dy[d][i];
      }
      if constexpr (Fields.velocity) sums.a[d][k] = a;
      if constexpr (Fields.position) sums.v[d][k] = v;
      if constexpr (Fields.deformation) {
        sums.grad_v[2 * d][k] = dv0;
        sums.grad_v[2 * d + 1][k] = dv1;
      }
    }
  }
}

/// Whether a gather runs its particles in vector lanes (gather_sums_in_lanes) in code for instruction set I: 2D
/// fast-path quadratics, in code with AVX2 (where they were measured, docs/PERFORMANCE.md); elsewhere the rows.
template <Isa I, int Dim, class Axis>
inline constexpr bool gathers_in_lanes = has_avx2<I> && Dim == 2 && std::is_same_v<Axis, UniformAxis<3>>;

/// G2P over particles [begin, end): the selected updates; `stress(F, s)` is the constitutive law (σ from F).
/// I: the instruction set the caller is compiled for (with_active_isa).
template <GatherFields Fields, int Dim, int S, Isa I = Isa::baseline, class Axis, class Stress>
MPM_INLINE void gather_g2p(const TensorBasis<Dim, Axis>& basis, ParticleView<Dim> p, GridView<Dim> g,
                           std::size_t begin, std::size_t end, double dt, const Stress& stress,
                           ParticleGuard& guard) {
  const std::array<double, 3> hi = guard.hi, inv_h = guard.inv_h;  // copies, as the views (views.hpp)
  double max_move = 0.0;  // cells
  // per batch of particles, three loops: the sums over the stencils, the updates, and σ(F). The sums into a local
  // batch: a loop that stores nothing the grid or the particle columns could alias may run in vector lanes. σ in a
  // loop of its own: the constitutive law takes a log, and around a call inside the gather loop every live vector
  // register of the gather was spilled and reloaded (caller-saved in the x86-64 ABI)
  constexpr std::size_t batch = 64;
  GatherSums<Dim, batch> sums;
  for (std::size_t first = begin; first < end; first += batch) {
    const std::size_t last = std::min(end, first + batch);
    if constexpr (gathers_in_lanes<I, Dim, Axis>)
      gather_sums_in_lanes<Fields>(basis, p, g, first, last - first, sums);
    else
      gather_sums_by_rows<Fields, Dim, S>(basis, p, g, first, last - first, sums);
    for (std::size_t ip = first; ip < last; ++ip) {
      const std::size_t k = ip - first;
      if constexpr (Fields.velocity)
        for (int d = 0; d < Dim; ++d) p.v[d][ip] += dt * sums.a[d][k];
      if constexpr (Fields.position)
        for (int d = 0; d < Dim; ++d) {
          const double dx = dt * sums.v[d][k];
          p.x[d][ip] += dx;
          if constexpr (Fields.velocity_from_position) p.v[d][ip] = dx / dt;
          max_move = std::max(max_move, std::abs(dx) * inv_h[d]);
        }
      if constexpr (Fields.deformation) {
        double F[Dim * Dim], Fn[Dim * Dim];
        for (int c = 0; c < Dim * Dim; ++c) F[c] = p.F[c][ip];
        for (int a = 0; a < Dim; ++a)
          for (int b = 0; b < Dim; ++b) {
            double sum = F[a * Dim + b];
            if constexpr (Fields.reference) sum += dt * sums.grad_v[a * Dim + b][k];  // ∇_X v = Σ v_i ⊗ ∇_X φ_i
            else
              for (int c = 0; c < Dim; ++c) sum += dt * sums.grad_v[a * Dim + c][k] * F[c * Dim + b];
            Fn[a * Dim + b] = sum;
          }
        for (int c = 0; c < Dim * Dim; ++c) p.F[c][ip] = Fn[c];
      }
      if constexpr (Fields.position || Fields.velocity)
        for (int d = 0; d < Dim; ++d)
          if (!(p.x[d][ip] >= 0.0 && p.x[d][ip] <= hi[d]) || !std::isfinite(p.v[d][ip])) guard.flag(ip);
    }
    if constexpr (Fields.deformation) {
      // σ into a local batch first, a loop without calls or stores that may alias F, which the compiler runs in
      // vector lanes (in AVX2 code: the neo-Hookean log is then vector_log); then stored, with the guard's checks
      double s_batch[sym_components<Dim>][batch];
      for (std::size_t ip = first; ip < last; ++ip) {
        double F[Dim * Dim], s[sym_components<Dim>];
        for (int c = 0; c < Dim * Dim; ++c) F[c] = p.F[c][ip];
        stress(F, s);
        for (int c = 0; c < sym_components<Dim>; ++c) s_batch[c][ip - first] = s[c];
      }
      for (std::size_t ip = first; ip < last; ++ip) {
        for (int c = 0; c < sym_components<Dim>; ++c) p.s[c][ip] = s_batch[c][ip - first];
        const double J = det(p, ip);
        if (!(J > 0.0) || !std::isfinite(J + s_batch[0][ip - first])) guard.flag(ip);
      }
    }
  }
  if constexpr (Fields.position && !Fields.reference) guard.moved(max_move);  // (reference: binned once, by X)
}

/// MUSL steps 6–7 fused (thesis eqs 2.47–2.48): v_p += Δt Σ_i φ_i a_i, then q_i += φ_i m_p v_p, for particles
/// order[begin..end) of one coloured block. One pass instead of a gather and a scatter: the grid accelerations
/// are only read, the momenta only written by this block's colour. I: the instruction set the caller is compiled
/// for; in code with AVX2 the 2D quadratic rows are GCC vectors (MomentLanes, one 256-bit register), where the
/// stencil rows of a portable build are two 128-bit halves: the pass took 1.3× the native build's time with them.
template <int Dim, int S, Isa I = Isa::baseline, class Axis>
inline MomentumTotals<Dim> advance_velocity_scatter_momentum(const TensorBasis<Dim, Axis>& basis,
                                                             ParticleView<Dim> p, GridView<Dim> g,
                                                             const unsigned* order, std::size_t begin,
                                                             std::size_t end, double dt) {
  MomentumTotals<Dim> totals;
  // v_p += Δt a_p; mv = m_p v_p
  const auto advance = [&](std::size_t ip, const double (&a)[Dim], double (&mv)[Dim]) MPM_INLINE_LAMBDA {
    const double mp = p.m[ip];
    double vp[Dim];
    for (int d = 0; d < Dim; ++d) {
      vp[d] = p.v[d][ip] + dt * a[d];
      p.v[d][ip] = vp[d];
      mv[d] = mp * vp[d];
    }
    totals.add(mp, vp);
  };
  if constexpr (gathers_in_lanes<I, Dim, Axis>) {
    using Lanes = MomentLanes;  // (passed by reference: a 32-byte vector returned by value warns in SSE2 code)
    // w = the row of the 3 functions at x, as uniform_row; `first` its first function
    const auto weights = [&](const UniformAxis<3>& axis, double x, Lanes& w, int& first) MPM_INLINE_LAMBDA {
      const auto at = axis.locate(x);
      Lanes q[3];
      std::memcpy(q, detail::padded_uniform<3>[at.span_class].data(), sizeof q);
      w = q[0] + at.xi * (q[1] + at.xi * q[2]);
      first = at.cell;
    };
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t ip = order[k];
      Lanes wx, wy, a_y[2] = {};  // a_y: Σ_j wy_j a_ij, then contracted with wx (as in gather_g2p)
      int first0, first1;
      weights(basis.axis[0], p.x[0][ip], wx, first0);
      weights(basis.axis[1], p.x[1][ip], wy, first1);
      for (int b = 0; b < 3; ++b)
        for (int d = 0; d < 2; ++d) {
          Lanes row;
          std::memcpy(&row, g.a[d] + (first1 + b) * g.stride1 + first0, sizeof row);
          a_y[d] += wy[b] * row;
        }
      double a[2], mv[2];
      for (int d = 0; d < 2; ++d) {
        const Lanes t = wx * a_y[d];
        a[d] = (t[0] + t[1]) + (t[2] + t[3]);
      }
      advance(ip, a, mv);
      for (int b = 0; b < 3; ++b)
        for (int d = 0; d < 2; ++d) {
          double* at = g.q[d] + (first1 + b) * g.stride1 + first0;
          Lanes row;
          std::memcpy(&row, at, sizeof row);
          row += wx * (wy[b] * mv[d]);
          std::memcpy(at, &row, sizeof row);
        }
    }
  } else {
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t ip = order[k];
      const auto st = stencil_of<Dim, S>(basis, p.x, ip);
      RowVector<S> a_y[Dim] = {};  // Σ_j wy_j a_ij, then contracted with wx (as in gather_g2p)
      for_each_row(st, g.stride1, [&](int row, double wy, double) MPM_INLINE_LAMBDA {
        for (int d = 0; d < Dim; ++d) a_y[d] += wy * load_row<RowVector<S>>(g.a[d] + row);
      });
      double a[Dim], mv[Dim];
      for (int d = 0; d < Dim; ++d) a[d] = reduce(st.wx * a_y[d]);
      advance(ip, a, mv);
      for_each_row(st, g.stride1, [&](int row, double wy, double) MPM_INLINE_LAMBDA {
        for (int d = 0; d < Dim; ++d) add_to_row(g.q[d] + row, st.wx * (wy * mv[d]));
      });
    }
  }
  return totals;
}

/// Entries per row of the consistent mass in band storage: the (2S − 1)^Dim functions j whose support overlaps
/// that of function i.
template <int Dim, int S>
inline constexpr int mass_band = Dim == 1 ? 2 * S - 1 : (2 * S - 1) * (2 * S - 1);

/// band += the consistent mass M_ij = Σ_p φ_i m_p φ_j (eq. 2.31, thesis eq. 3.9) of carriers order[begin..end): row
/// i holds M_ij at band[i · mass_band + o], o = (j0 − i0 + S − 1) + (2S − 1)(j1 − i1 + S − 1). Assembled once per
/// solve, the CG iterations multiply by the band instead of gathering and scattering at every carrier.
template <int Dim, int S, class Axis>
inline void assemble_consistent_mass(const TensorBasis<Dim, Axis>& basis, MassCarriers<Dim> c, int stride1,
                                     double* band, const unsigned* order, std::size_t begin, std::size_t end) {
  constexpr int W = 2 * S - 1, rows = Dim == 1 ? 1 : S;
  for (std::size_t k = begin; k < end; ++k) {
    const std::size_t ip = order[k];
    const auto st = stencil_of<Dim, S>(basis, c.x, ip);
    double wx[S], wy[rows];
    for (int a = 0; a < S; ++a) wx[a] = st.wx[a];
    for (int a = 0; a < rows; ++a) wy[a] = Dim == 1 ? 1.0 : st.wy[a];
    for (int a1 = 0; a1 < rows; ++a1)
      for (int a0 = 0; a0 < S; ++a0) {
        const double m_phi = c.m[ip] * wx[a0] * wy[a1];  // m_p φ_i
        double* row = band + static_cast<std::size_t>((st.first1 + a1) * stride1 + st.first0 + a0) * mass_band<Dim, S>;
        for (int b1 = 0; b1 < rows; ++b1) {
          double* at = row + W * (b1 - a1 + S - 1) * (Dim - 1) + (S - 1 - a0);
          for (int b0 = 0; b0 < S; ++b0) at[b0] += m_phi * wx[b0] * wy[b1];
        }
      }
  }
}

}  // namespace mpm
