#pragma once
// The cubic-spline (CS) reconstruction (1D, thesis §3.2): one cubic spline per field through all particles of the
// body, evaluated at `gauss_per_cell` Gauss points in each half of every knot span (thesis §3.2.3, Fig. 3.4: two
// per half), restricted to the body's current extent. It is the thesis' non-conservative comparison method: ∫ρ̂
// and ∫ρv̂ differ from Σ m_p and Σ m_p v_p by the interpolation error.
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "engine/body_extent.hpp"
#include "engine/cell_bins.hpp"
#include "engine/gauss_point_store.hpp"
#include "engine/particle_fields.hpp"
#include "engine/scene.hpp"
#include "kernels/cubic_spline.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

template <int Dim>
class CubicSplineReconstruction {
 public:
  static constexpr const char* name = "cubic-spline";
  explicit CubicSplineReconstruction(const Scene& scene)
      : half_rule_(gauss_legendre(scene.algorithm.gauss_per_cell[0])) {}

  /// ρ̂ω and ρv̂ω at the Gauss points (thesis eqs 3.8–3.9), and σ̂ω, ρb̂ω (eq. 3.7) when `stress` is set; returns
  /// the particle momentum Σ m_p v_p, Σ m_p |v_p|.
  template <class Body>
  MomentumTotals<Dim> rebuild(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                              const CellBins<Dim>&, const Body& body, bool stress, bool, FallbackCounts& fallbacks) {
    if constexpr (Dim != 1) {
      throw std::logic_error("GaussPoints: the cubic-spline mapping is 1D only (the scene refuses it in 2D)");
    } else {
      const MomentumTotals<Dim> totals = sort_by_position(p, cells, gp.grid.count());
      fit_splines(p, body, stress, gp.grid.h[0], fallbacks);
      // The body's current extent: the end particles' domains, x_p ∓ V_p/2, reach the body's ends, and the
      // spline is extrapolated there (thesis Fig. 3.3); outside it no Gauss point carries anything.
      const Extent1d extent = body_extent_1d(p, sorted_.size());
      const double lo = extent.lo, hi = extent.hi;  // (clang 14 cannot capture structured bindings)
      const int n = static_cast<int>(half_rule_.x.size());
      gp.grid.for_each_cell([&](std::size_t c) {
        for (int half = 0; half < 2; ++half) {
          double w[16];  // ≤ 10 points per half (scene range of gauss_per_cell)
          place_half_span(gp, c, half, lo, hi, w);
          for (int j = 0; j < n; ++j) {
            const std::size_t g = gp.first_point(c) + half * n + j;
            gp.clear_point(g);
            if (w[j] == 0.0) continue;
            // ρ̂ω and ρv̂ω (thesis eqs 3.8–3.9), σ̂ω and ρb̂ω (eq. 3.7)
            const auto mv = mass_spline_(gp.x[0][g]);
            gp.m[g] = w[j] * mv[0];
            gp.q[0][g] = w[j] * mv[1];
            if (!stress) continue;
            const auto sv = stress_spline_(gp.x[0][g]);
            gp.s[0][g] = w[j] * sv[0];
            gp.fb[0][g] = w[j] * sv[1];
          }
        }
      });
      return totals;
    }
  }

 private:
  /// The particles of the `ncells` cells in order of position (1D), into sorted_; their totals Σ m_p v_p, Σ m_p |v_p|.
  MomentumTotals<Dim> sort_by_position(const ParticleView<Dim>& p, const CellBins<Dim>& cells, std::size_t ncells) {
    // cell by cell (the bins are colour-major, so their order is not the cells'), then an insertion sort by x
    // within: particles of a 1D body keep their order almost always, so this is O(n) in practice and stable
    const unsigned* order = cells.order().data();
    sorted_.clear();
    cell_totals_.assign(ncells, MomentumTotals<Dim>{});
    for (std::size_t c = 0; c < ncells; ++c) {
      const auto [b, e] = cells.block_range(c);
      for (std::size_t k = b; k < e; ++k) {
        const unsigned ip = order[k];
        double v[Dim];
        for (int d = 0; d < Dim; ++d) v[d] = p.v[d][ip];
        cell_totals_[c].add(p.m[ip], v);
        std::size_t i = sorted_.size();
        sorted_.push_back(ip);
        for (; i > 0 && p.x[0][sorted_[i - 1]] > p.x[0][ip]; --i) sorted_[i] = sorted_[i - 1];
        sorted_[i] = ip;
      }
    }
    return sum_totals(cell_totals_);
  }

  /// The splines of (ρ, ρv) and, when `stress` is set, (σ, ρb) through the particles in order of position (`h`:
  /// the cell size).
  template <class Body>
  void fit_splines(const ParticleView<Dim>& p, const Body& body, bool stress, double h, FallbackCounts& fallbacks) {
    const ParticleFields<Dim, Body> fields{&p, &body};
    // Particles closer than this are one data point (kernels/cubic_spline.hpp): far below any spacing a run
    // survives, far above the round-off of positions.
    const double merge = 1e-10 * h;
    mass_spline_.clear();
    stress_spline_.clear();
    for (const unsigned ip : sorted_) {  // the particles are the data points (thesis §3.2.1)
      mass_spline_.push(p.x[0][ip], fields.mass(ip), merge);
      if (stress) stress_spline_.push(p.x[0][ip], fields.stress(ip), merge);
    }
    // natural end conditions, as in the thesis (§3.2.1: z''(x_1) = z''(x_M) = 0)
    mass_spline_.fit(SplineEnd::natural);
    if (stress) stress_spline_.fit(SplineEnd::natural);
    // A single data point makes the spline the constant through it: still a reconstruction, but a degenerate one
    // the summary should show.
    if (mass_spline_.size() < 2) ++fallbacks.constant;
  }

  /// Places the Gauss points of half `half` of cell c on its part inside [lo, hi] (thesis Fig. 3.4); returns
  /// their weights into `w` (all zero when the half lies outside).
  void place_half_span(GaussPointStore<Dim>& gp, std::size_t c, int half, double lo, double hi, double* w) const {
    const double h = gp.grid.h[0];
    const double a = gp.grid.box(c).lo[0] + 0.5 * half * h;
    const std::size_t n = half_rule_.x.size();
    gp.place_clipped(gp.first_point(c) + half * n, half_rule_, a, a + 0.5 * h, lo, hi, w);
  }

  GaussRule half_rule_;                                   ///< Gauss rule of a half knot span, on [0, 1]
  std::vector<unsigned> sorted_;                          ///< particle indices by position
  std::vector<MomentumTotals<Dim>> cell_totals_;
  CubicSpline<1 + Dim> mass_spline_;                      ///< ρ, ρv
  CubicSpline<sym_components<Dim> + Dim> stress_spline_;  ///< σ, ρb
};

}  // namespace mpm
