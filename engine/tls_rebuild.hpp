#pragma once
// The TLS reconstruction at the Gauss points (thesis §5.3 / §6.1.1): per active cell, ρ is fitted in a Taylor basis
// with its first coefficient fixed by the cell's particle sums, so the grid receives exactly Σ m_p and Σ m_p v_p
// (Gauss rules with ≥ 2 points per axis integrate the quadratic Taylor basis exactly); v, σ and ρb are fitted
// without a constraint, from the cell's own particles or, where they do not determine the fit well, from its 3×3
// neighbourhood; the limiter (kernels/tls_limiter.hpp) bounds the values at the Gauss points.
// In 1D the TLS cell is the occupied part of the cell: the cell clipped to the body's current extent
// (body_extent.hpp). Spreading a partly filled end cell's mass over the whole cell puts mass where there is no
// body and, measured on the column (4 particles per cell, 50 cells), made its displacement error 8e-2 against
// 4.7e-5 for direct mapping; on the clipped cell the Taylor basis is mean-free again, so eq. 5.9 still conserves.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "engine/body_extent.hpp"
#include "engine/cell_bins.hpp"
#include "engine/gauss_point_store.hpp"
#include "engine/scratch_store.hpp"
#include "engine/scene.hpp"
#include "engine/tls_records.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/taylor_ls.hpp"
#include "kernels/tls_limiter.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

/// One TLS rebuild of the fields `Fit` names at Taylor degree `Degree`, as its passes: pass 1 sums each cell's
/// particles and fits what they determine; pass 1b keeps the sums a neighbourhood fit needs that pass 1 did not;
/// pass 2 sums rows of three cells along axis 0; pass 3 fits the remaining cells to their 3×3 neighbourhood.
template <int Dim, int Degree, TlsFields Fit, class Body>
class TlsPasses {
 public:
  static constexpr int KR = Fit.reuse ? 0 : 1;                     // ρ, the constrained fit (a reuse keeps it)
  static constexpr int KV = Fit.velocity ? Dim : 0;                // v
  static constexpr int KS = Fit.stress ? sym_components<Dim> : 0;  // σ
  static constexpr int KB = Fit.stress && Body::active ? Dim : 0;  // ρb
  static constexpr int KF = KV + KS + KB;                          // the unconstrained fits
  static constexpr int K = KR + KF;
  static_assert(KF > 0, "a TLS rebuild fits the velocity or the stress");
  static_assert(!Fit.reuse || (Fit.velocity && !Fit.stress), "a reuse refits the velocity alone");
  static constexpr std::size_t enough_points = static_cast<std::size_t>(taylor_size<Dim>(Degree)) + 1;
  using Sums = detail::TlsCellSums<Dim, Degree, K, KF>;
  using Values = Eigen::Matrix<double, K, 1>;  // what a particle gives: ρ | v | σ | ρb
  using FitValues = Eigen::Matrix<double, KF, 1>;
  using FitSystem = detail::TaylorNormalSystem<Dim, Degree, KF>;
  using Bounds = detail::TlsFitBounds<Dim, KF>;
  // The unconstrained fields of a cell and its two neighbours along axis 0, in the cell's frame: the first half of
  // a separable 3×3 (1D: 3) neighbourhood sum, summed only where a neighbourhood fit needs it. (A type of its own:
  // the scratch is one store per type.)
  struct RowSums : FitSystem {};
  // Which cells are sparse is taken from the bins' counts once, into a byte per cell in row-major order: looked up
  // through the bins (rank, then block start) for the nine cells around every cell, in pass 1's block order,
  // those dependent loads were a quarter of pass 1 with 2×2 particles per cell.
  struct Sparse {
    bool value;
  };

  TlsPasses(GaussPointStore<Dim>& gp, ScratchStore& scratch, const GaussRule& cell_rule, const ParticleView<Dim>& p,
            const CellBins<Dim>& cells, const CellBins<Dim>& layout, const Body& body)
      : gp_(gp),
        p_(p),
        cells_(cells),
        layout_(layout),
        body_(body),
        cell_rule_(cell_rule),
        order_(cells.order().data()),
        ncells_(gp.grid.count()),
        totals_(scratch.get<MomentumTotals<Dim>>(layout.blocks())),
        near_(scratch.get<FitSystem>(ncells_)),
        bounds_(scratch.get<Bounds>(ncells_)),
        rows_(scratch.get<RowSums>(ncells_)),
        kept_(scratch.get<detail::TlsKeptFit<Dim, Degree>>(ncells_)),
        kept_matrices_(scratch.get<detail::TlsKeptMatrices<Dim, Degree>>(ncells_)),
        needs_neighbours_(scratch.get<std::uint8_t>(ncells_)),
        sparse_(scratch.get<Sparse>(ncells_)) {
    if constexpr (Fit.velocity) std::fill(totals_.begin(), totals_.end(), MomentumTotals<Dim>{});
    if constexpr (Dim == 1) extent_ = body_extent_1d(p, cells.order().size());
    // The Gauss points sit at the same place of every TLS cell (1D: of its occupied part): ξ = 2 local − 1.
    for (int g = 0; g < gp.per_cell; ++g) {
      Vec<Dim> xi;
      for (int d = 0; d < Dim; ++d) xi[d] = 2.0 * gp.local[g][d] - 1.0;
      psi_buffer_[g] = taylor_basis_ref<Dim, Degree>(xi);
    }
    psi_ = std::span<const TaylorVector<Dim, Degree>>(psi_buffer_.data(), gp.per_cell);
    opt_.rank_threshold = own_fit_pivot;
  }

  /// Runs the passes; adds the fallbacks to `fallbacks`. Returns Σ m v, Σ m |v| when the velocity is fitted.
  MomentumTotals<Dim> run(FallbackCounts& fallbacks) {
    mark_sparse();
    fit_own_cells();
    if (conditioning_failed_.load()) keep_neighbour_sums();
    sum_rows();
    fit_neighbourhoods();
    for (const auto& c : counts_) fallbacks += c;
    if constexpr (!Fit.velocity) return MomentumTotals<Dim>{};
    return sum_totals(totals_);
  }

 private:
  // The unconstrained fits (velocity, stress) have no integral to anchor them. From its own particles alone a cell
  // fits them only with one sample more than it has Taylor functions (a residual to spare: 2D linear, 4 particles)
  // and a well-conditioned normal matrix (relative pivot ≥ 1e-3 after equilibration, not just full rank);
  // otherwise it fits the same degree to its own and its 8 neighbours' particles (thesis §5.2.3, Fig. 5.7; a
  // `neighbour` fallback). Measured on the plate (docs/RECONSTRUCTION.md): a constant stress per cell
  // under-integrates the force (64², 2×2 particles: u error 24 % of A at A = 0.05); a linear fit through 4
  // particles without the conditioning test blows up (exit 3), and so does one through 6 (3×2) whose layout
  // compression has flattened. With the test, requiring 2 samples per function (every fit of a 2×2 layout a
  // neighbourhood fit) made the 2×2 step 1.3x slower and was less accurate at A = 0.1 (64², 2×2: σ 1.14e6 against
  // 5.8e5), though more at A = 0.05 (64², 2×2: v 2.5 against 3.6).
  static constexpr double own_fit_pivot = 1e-3;

  /// Fallbacks are counted per thread (integers: the same sum for any partition), and a fit without one costs a
  /// comparison: a count per cell was written by every cell and summed serially.
  void count(const FitStatus& status) {
    if (status.stage != FitStage::full) counts_.local().add(status);
  }

  /// The TLS cell: in 1D the occupied part of the cell (see the top of this file).
  CellBox<Dim> tls_box(std::size_t c) const {
    CellBox<Dim> box = gp_.grid.box(c);
    if constexpr (Dim == 1)
      if (std::max(box.lo[0], extent_.lo) < std::min(box.hi[0], extent_.hi)) {
        box.lo[0] = std::max(box.lo[0], extent_.lo);
        box.hi[0] = std::min(box.hi[0], extent_.hi);
      }
    return box;
  }

  /// Keeps what the neighbourhood fits read of cell slot s (the per-cell scratch is indexed by slot).
  void keep_sums(std::size_t s, const Sums& cs) {
    near_[s] = cs.template fields<KR, KF>();
    bounds_[s] = cs.bounds();
    if constexpr (Fit.reuse) near_[s].D = kept_matrices_[s].own_D;  // a reuse sums no D (add_samples<false>)
    else kept_matrices_[s].own_D = cs.sys.D;
  }

  /// The limiter and the Gauss-point values of a cell's unconstrained fit.
  void write_fit(std::size_t c, const CellBox<Dim>& box, const Bounds& cb, const TaylorFit<Dim, Degree, KF>& fit) {
    const std::size_t first = gp_.first_point(c);
    const int per_cell = gp_.per_cell;
    const double volume = box.volume();
    std::array<FitValues, GaussPointStore<Dim>::max_per_cell> values;
    detail::limited_values(fit, cb.lo, cb.hi, psi_, values.data());
    // Momentum as ρ̂ v̂, not a fit of ρv (beyond the thesis, which fits ρv, eq. 5.9): v̂ is bounded by the cell's
    // particle velocities, so a nodal velocity Σφρ̂v̂ω / Σφρ̂ω is a weighted mean of bounded values even where the
    // nodal mass is tiny. Fitting ρ and ρv apart let their ratio run away at such nodes (v ≈ 2e4 m/s on the
    // 64² plate with 2×2 particles per cell). The mean of v̂ is shifted so that Σ_g ρ̂v̂ω = Σ m_p v_p exactly.
    if constexpr (Fit.velocity) {
      double m_g = 0.0;
      Eigen::Matrix<double, Dim, 1> q_g = Eigen::Matrix<double, Dim, 1>::Zero();
      for (int g = 0; g < per_cell; ++g) {
        m_g += gp_.m[first + g];
        q_g += gp_.m[first + g] * values[g].template head<Dim>();
      }
      const Eigen::Matrix<double, Dim, 1> shift = (cb.momentum - q_g) / m_g;
      for (int g = 0; g < per_cell; ++g)
        for (int d = 0; d < Dim; ++d) gp_.q[d][first + g] = gp_.m[first + g] * (values[g][d] + shift[d]);
    }
    if constexpr (Fit.stress)
      for (int g = 0; g < per_cell; ++g) {
        const double w = gp_.local_w[g] * volume;
        for (int k = 0; k < KS; ++k) gp_.s[k][first + g] = w * values[g][KV + k];
        for (int d = 0; d < KB; ++d) gp_.fb[d][first + g] = w * values[g][KV + KS + d];
      }
  }

  /// The sums of a cell's own particles (positions, ρ, v, σ, ρb as `Fit` names them) and its bounds, mass and
  /// momentum, in its Taylor frame; `total`: Σ m v (the momentum constraint) and Σ m |v|. The view is copied: read
  /// through a reference, GCC reloaded every column pointer after each store to the sums.
  Sums sum_cell(std::size_t c, MomentumTotals<Dim>& total) const {
    const ParticleView<Dim> p = p_;
    const Body& body = body_;
    const unsigned* order = order_;
    const auto range = cells_.block_range(c);  // (clang 14 cannot capture structured bindings)
    const std::size_t begin = range.first, end = range.second;
    Sums cs;
    cs.box = tls_box(c);
    cs.frame = TaylorFrame<Dim>(cs.box);
    if (begin == end) return cs;
    const TaylorFrame<Dim> frame = cs.frame;
    // locals while the particles stream in (see add_samples)
    Values lo = Values::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    double mass = 0.0;
    // a reuse sums the velocity right-hand sides only: D depends on the positions, unchanged since it was kept
    cs.sys.template add_samples<!Fit.reuse>([&](auto&& add_one) {
      for (std::size_t k = begin; k < end; ++k) {
        const std::size_t ip = order[k];
        Values f;
        Vec<Dim> x;
        for (int d = 0; d < Dim; ++d) x[d] = p.x[d][ip];
        double rho = 0.0;
        if constexpr (!Fit.reuse) {
          rho = p.m[ip] / (det(p, ip) * p.V0[ip]);  // V_p = J_p V0_p (eq. 2.42)
          f[0] = rho;
          mass += p.m[ip];
        }
        if constexpr (Fit.velocity) {
          double v[Dim];
          for (int d = 0; d < Dim; ++d) f[KR + d] = v[d] = p.v[d][ip];
          total.add(p.m[ip], v);
        }
        if constexpr (Fit.stress)
          for (int i = 0; i < KS; ++i) f[KR + KV + i] = p.s[i][ip];
        if constexpr (KB > 0) {
          const std::array<double, Dim> b = body.template at<Dim>(ip);
          for (int d = 0; d < Dim; ++d) f[KR + KV + KS + d] = rho * b[d];
        }
        add_one(frame.xi(x), f, 1.0);
        lo = lo.cwiseMin(f);
        hi = hi.cwiseMax(f);
      }
    });
    cs.sys.points = end - begin;
    cs.lo = lo;
    cs.hi = hi;
    cs.mass = mass;
    for (int d = 0; d < Dim; ++d) cs.momentum[d] = total.mv[d];
    return cs;
  }

  // Whose sums passes 2 and 3 read: the cells within one cell of a cell with particles too few for its own fit,
  // which the bins' counts tell before any particle is read. Every other cell keeps its sums in pass 1's locals:
  // written to the scratch and read back, that record of ≈ 70 doubles was the pass's largest memory traffic. A
  // cell with enough particles whose own fit fails on its conditioning alone (rare) has its neighbours' sums
  // taken in pass 1b.
  void mark_sparse() {
    if constexpr (Fit.reuse) return;  // a reuse reads what the rebuild before it found (TlsKeptFit::near_sparse)
    gp_.grid.for_each_cell([&](std::size_t c) {
      const auto range = cells_.block_range(c);
      const std::size_t n = range.second - range.first;
      sparse_[c].value = n > 0 && n < enough_points;
    });
  }
  bool near_sparse(std::size_t c) const {
    if constexpr (Fit.reuse) return kept_[gp_.slot(c)].near_sparse;
    bool any = false;
    gp_.grid.for_each_cell_near(c, 1, [&](std::size_t n) { any |= sparse_[n].value; });
    return any;
  }

  /// Pass 1: each particle is read once, into the sums of its cell, and the cell fits what its own particles
  /// determine; the cells in the order of `layout`'s blocks, which the particle columns follow (a row-major sweep
  /// jumped between the colour classes of the blocks).
  void fit_own_cells() {
    layout_.for_each_cell_by_block([&](std::size_t block, std::size_t c) { fit_own_cell(block, c); });
  }
  void fit_own_cell(std::size_t block, std::size_t c) {
    const std::size_t s = gp_.slot(c);
    MomentumTotals<Dim> total;
    const Sums cs = sum_cell(c, total);
    if constexpr (Fit.velocity) totals_[block].add(total);
    needs_neighbours_[s] = 0;
    const bool keep = near_sparse(c);
    if constexpr (!Fit.reuse) kept_[s].near_sparse = keep;
    if (keep) keep_sums(s, cs);
    if (cs.sys.points == 0) {  // an empty cell carries nothing: nothing to conserve there
      const std::size_t first = gp_.first_point(c);
      for (int g = 0; g < gp_.per_cell; ++g) gp_.clear_point(first + g);
      return;
    }
    if constexpr (!Fit.reuse) fit_density(c, cs);  // a reuse keeps the density at the Gauss points
    count(kept_[s].rho);

    // the own fit as detail::own_fit would make it, through factors a reuse keeps
    detail::TlsKeptFit<Dim, Degree>& k = kept_[s];
    if constexpr (!Fit.reuse)
      k.own_fitted = cs.sys.points >= enough_points && k.own_factors.factor(cs.sys.D, own_fit_pivot);
    if (k.own_fitted) {
      TaylorFit<Dim, Degree, KF> fit;
      detail::fit_with(cs.box, k.own_factors, cs.sys.b.template middleCols<KF>(KR),
                       cs.sys.shift.template segment<KF>(KR), cs.sys.points, fit);
      write_fit(c, cs.box, cs.bounds(), fit);
      return;
    }
    needs_neighbours_[s] = 1;
    if (keep) return;
    keep_sums(s, cs);
    conditioning_failed_.store(true, std::memory_order_relaxed);
  }

  /// The density fit uses the cell's own particles only: completing it from the neighbouring cells (thesis
  /// §5.2.3) was measured to bias the slopes of compressed cells (plate, A = 0.1: 64-cell error 2.4x larger);
  /// a cell its own particles do not determine drops to a lower degree instead, conservative all the same.
  /// The cell's mass Σ m_p fixes the first Taylor coefficient of ρ (thesis eq. 5.9).
  void fit_density(std::size_t c, const Sums& cs) {
    const std::size_t first = gp_.first_point(c);
    const CellBox<Dim>& box = cs.box;
    const double volume = box.volume();
    if constexpr (Dim == 1) {  // the occupied part of the cell: its Gauss points move there
      const CellBox<Dim> whole = gp_.grid.box(c);
      double w[16];            // ≤ 10 points per cell (scene range of gauss_per_cell)
      gp_.place_clipped(first, cell_rule_, whole.lo[0], whole.hi[0], extent_.lo, extent_.hi, w);
    }
    auto rho_sys = cs.template fields<0, 1>();
    rho_sys.reshift(Eigen::Matrix<double, 1, 1>(cs.mass / volume));
    const auto rho_fit = detail::complete_fit<Degree>(box, rho_sys, true, [](auto&) { return false; }, TlsOptions{});
    kept_[gp_.slot(c)].rho = rho_fit.status;
    std::array<Eigen::Matrix<double, 1, 1>, GaussPointStore<Dim>::max_per_cell> rho;
    detail::limited_values(rho_fit, cs.lo.template head<1>().eval(), cs.hi.template head<1>().eval(), psi_,
                           rho.data());
    for (int g = 0; g < gp_.per_cell; ++g) gp_.m[first + g] = gp_.local_w[g] * volume * rho[g][0];
  }

  /// Pass 1b: the sums of the neighbours of cells whose own fit failed on its conditioning, where pass 1 did not
  /// keep them.
  void keep_neighbour_sums() {
    gp_.grid.for_each_cell([&](std::size_t s) {
      const std::size_t c = gp_.cell_of_slot[s];
      if (needs_neighbours_[s] || near_sparse(c)) return;  // kept in pass 1
      bool needed = false;
      gp_.grid.for_each_cell_near(c, 1, [&](std::size_t n) { needed = needed || needs_neighbours_[gp_.slot(n)]; });
      MomentumTotals<Dim> unused;
      if (needed) keep_sums(s, sum_cell(c, unused));
    });
  }

  /// Pass 2: row sums, where a neighbourhood fit of pass 3 needs them (a cell without particles may still join
  /// its neighbours' sums). The neighbourhood fits move the sums of the neighbouring cells into their own frame
  /// (TaylorChange) instead of revisiting those cells' particles, separably: pass 2 sums each cell's row of three
  /// along axis 0, pass 3 the rows of three along axis 1, four one-axis moves per cell instead of eight general
  /// ones. With 2×2 particles per cell, where every velocity and stress fit needs the 3×3 neighbourhood, this and
  /// the fixed-size solve cut the two rebuilds of a MUSL step from 5570 to 2400 instructions per particle
  /// (callgrind; docs/RECONSTRUCTION.md). Neighbours weigh as much as own particles here
  /// (TlsOptions::neighbour_weight = 1, the thesis' choice): a separable sum cannot weigh them apart.
  void sum_rows() {
    gp_.grid.for_each_cell([&](std::size_t s) {
      const std::size_t c = gp_.cell_of_slot[s];
      if (!row_needed(c)) return;
      FitSystem& row = rows_[s];
      row = near_[s];
      const TaylorFrame<Dim> frame(tls_box(c));
      gp_.grid.for_each_neighbour_along(c, 0, [&](std::size_t n) {
        const FitSystem& ns = near_[gp_.slot(n)];
        const TaylorChange<Dim, Degree, 1u> change(TaylorFrame<Dim>(tls_box(n)), frame);
        // a reuse moves only the right-hand sides and Σ w ψ (D's first column), which pass 3 moves on
        if constexpr (Fit.reuse)
          row.template add_moved_rhs<true>(ns.D.col(0), ns.b, ns.shift, ns.points, change, 1.0);
        else
          row.add_moved(ns, change, 1.0);
      });
    });
  }
  bool row_needed(std::size_t c) const {
    bool needed = needs_neighbours_[gp_.slot(c)];
    if constexpr (Dim == 2)
      gp_.grid.for_each_neighbour_along(c, 1, [&](std::size_t n) { needed |= needs_neighbours_[gp_.slot(n)]; });
    return needed;
  }

  /// Pass 3: the neighbourhood fits of the cells whose own particles did not determine theirs.
  void fit_neighbourhoods() {
    gp_.grid.for_each_cell([&](std::size_t s) {
      if (!needs_neighbours_[s]) return;
      const std::size_t c = gp_.cell_of_slot[s];
      const CellBox<Dim> box = tls_box(c);
      const FitSystem& own = near_[s];
      const bool enough = own.points >= enough_points;
      FitSystem fit_sys;
      if (enough) fit_sys = own;
      else add_neighbours(s, c, box, fit_sys);
      auto fit = detail::complete_fit<Degree>(
          box, fit_sys, false, [&](auto& sys) { return enough && add_neighbours(s, c, box, sys); }, opt_);
      if (!enough && fit.status.stage == FitStage::full) fit.status.stage = FitStage::neighbour;
      count(fit.status);
      write_fit(c, box, bounds_[s], fit);
    });
  }
  /// The sums of cell c (slot s) and its neighbours into `sys`: the rows above and below moved to this one.
  /// Returns whether the neighbours added any particle.
  bool add_neighbours(std::size_t s, std::size_t c, const CellBox<Dim>& box, FitSystem& sys) {
    const TaylorFrame<Dim> frame(box);
    sys = rows_[s];
    if constexpr (Dim == 2)
      gp_.grid.for_each_neighbour_along(c, 1, [&](std::size_t n) {
        const TaylorChange<Dim, Degree, 2u> change(TaylorFrame<Dim>(tls_box(n)), frame);
        const FitSystem& row = rows_[gp_.slot(n)];
        if constexpr (Fit.reuse) sys.add_moved_rhs(row.D.col(0), row.b, row.shift, row.points, change, 1.0);
        else sys.add_moved(row, change, 1.0);
      });
    if constexpr (Fit.reuse) sys.D = kept_matrices_[s].neighbourhood_D;  // the same positions: the same matrix
    else kept_matrices_[s].neighbourhood_D = sys.D;
    return sys.points > near_[s].points;
  }

  GaussPointStore<Dim>& gp_;
  const ParticleView<Dim> p_;
  const CellBins<Dim>& cells_;
  const CellBins<Dim>& layout_;
  const Body& body_;
  const GaussRule& cell_rule_;  ///< 1D: the Gauss rule of a cell, on [0, 1]
  const unsigned* order_;
  const std::size_t ncells_;
  Extent1d extent_{-1e300, 1e300};
  // Σ m v, Σ m |v| per block of `layout` (written when Fit.velocity): summed serially at the end, a total per
  // cell was 1.4 % of a 2×2 TLS step
  std::vector<MomentumTotals<Dim>>& totals_;
  // What the neighbourhood fits read of a cell, kept by passes 1 and 1b for the cells whose sums they read: the
  // normal sums of the unconstrained fields, and the bounds and momentum. Not pass 1's whole record (box, frame,
  // the density's sums too: 416 bytes for the stress fits of 2D), which with 2×2 particles per cell, every cell
  // near a sparse one, was written for every cell and read back four times, and the neighbourhood passes waited
  // on those loads.
  std::vector<FitSystem>& near_;
  std::vector<Bounds>& bounds_;
  std::vector<RowSums>& rows_;
  std::vector<detail::TlsKeptFit<Dim, Degree>>& kept_;
  std::vector<detail::TlsKeptMatrices<Dim, Degree>>& kept_matrices_;
  std::vector<std::uint8_t>& needs_neighbours_;  ///< the cell's own particles did not determine its fit
  std::vector<Sparse>& sparse_;
  tbb::enumerable_thread_specific<FallbackCounts> counts_;
  std::atomic<bool> conditioning_failed_{false};  ///< pass 1b is needed
  std::array<TaylorVector<Dim, Degree>, GaussPointStore<Dim>::max_per_cell> psi_buffer_;
  std::span<const TaylorVector<Dim, Degree>> psi_;  ///< the Taylor basis at the Gauss points (limited_values)
  TlsOptions opt_;
};

template <int Dim>
class TlsReconstruction {
 public:
  static constexpr const char* name = "tls";
  explicit TlsReconstruction(const Scene& scene)
      : degree_(scene.algorithm.tls_degree), cell_rule_(gauss_legendre(scene.algorithm.gauss_per_cell[0])) {}

  /// ρ at the Gauss points of every cell that holds particles (conservative), ρv when `momentum` or not `stress`
  /// (the scatter reads it), σ and ρb when `stress` is set. Returns Σ m_p v_p, Σ m_p |v_p| when ρv is fitted.
  template <class Body>
  MomentumTotals<Dim> rebuild(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                              const CellBins<Dim>& layout, const Body& body, bool stress, bool momentum,
                              FallbackCounts& fallbacks) {
    kept_ = false;  // until this rebuild completes
    MomentumTotals<Dim> totals;
    if (!stress) totals = run<TlsFields{.velocity = true}>(gp, p, cells, layout, body, fallbacks);
    else if (momentum) totals = run<TlsFields{.velocity = true, .stress = true}>(gp, p, cells, layout, body, fallbacks);
    else totals = run<TlsFields{.stress = true}>(gp, p, cells, layout, body, fallbacks);
    kept_ = true;
    return totals;
  }

  /// The momentum again after a rebuild, when the particles' velocities are all that changed since: keeps that
  /// rebuild's density at the Gauss points, its density fallbacks and its own and neighbourhood normal matrices,
  /// and sums and fits only the velocity — the same numbers as rebuild(…, false, true), for a fraction of its cost.
  template <class Body>
  MomentumTotals<Dim> rebuild_momentum(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p,
                                       const CellBins<Dim>& cells, const CellBins<Dim>& layout, const Body& body,
                                       FallbackCounts& fallbacks) {
    if (!kept_) return rebuild(gp, p, cells, layout, body, false, true, fallbacks);
    return run<TlsFields{.velocity = true, .reuse = true}>(gp, p, cells, layout, body, fallbacks);
  }

 private:
  /// The passes of `Fit` at the scene's Taylor degree.
  template <TlsFields Fit, class Body>
  MomentumTotals<Dim> run(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                          const CellBins<Dim>& layout, const Body& body, FallbackCounts& fallbacks) {
    switch (degree_) {
      case 0: return TlsPasses<Dim, 0, Fit, Body>(gp, scratch_, cell_rule_, p, cells, layout, body).run(fallbacks);
      case 1: return TlsPasses<Dim, 1, Fit, Body>(gp, scratch_, cell_rule_, p, cells, layout, body).run(fallbacks);
      default: return TlsPasses<Dim, 2, Fit, Body>(gp, scratch_, cell_rule_, p, cells, layout, body).run(fallbacks);
    }
  }

  int degree_;
  GaussRule cell_rule_;  ///< 1D: the Gauss rule of a cell, on [0, 1]
  ScratchStore scratch_;
  bool kept_ = false;  ///< a rebuild left what rebuild_momentum reuses
};

}  // namespace mpm
