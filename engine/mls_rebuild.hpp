#pragma once
// The MLS reconstruction at the Gauss points (paper eqs 6–17): per Gauss point, a linear moving least-squares fit
// of ρ, ρv (and σ, ρb when the force is scattered) to the particles within the weight's support. Not conservative.
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

#include "engine/cell_bins.hpp"
#include "engine/gauss_point_store.hpp"
#include "engine/parallel_over.hpp"
#include "engine/particle_fields.hpp"
#include "engine/scratch_store.hpp"
#include "engine/scene.hpp"
#include "kernels/mls.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

namespace detail {

/// The particles of up to 49 cells (a cell and its neighbours) as a sample source; values(ip) gives K fields.
template <int Dim, int K, class Values>
struct ParticleRanges {
  static constexpr int dim = Dim;
  static constexpr int fields = K;
  static constexpr int max_ranges = 49;
  const ParticleView<Dim>* p;
  const unsigned* order;
  Values values;
  std::array<std::pair<std::size_t, std::size_t>, max_ranges> r{};
  int n = 0;
  void add(std::pair<std::size_t, std::size_t> range) {
    if (range.first < range.second && n < max_ranges) r[n++] = range;
  }
  std::size_t size() const {
    std::size_t s = 0;
    for (int i = 0; i < n; ++i) s += r[i].second - r[i].first;
    return s;
  }
  template <class F>
  void for_each(F&& f) const {
    for (int i = 0; i < n; ++i)
      for (std::size_t k = r[i].first; k < r[i].second; ++k) {
        const std::size_t ip = order[k];
        Vec<Dim> x;
        for (int d = 0; d < Dim; ++d) x[d] = p->x[d][ip];
        f(x, values(ip), 1.0);
      }
  }
};

}  // namespace detail

template <int Dim>
class MlsReconstruction {
 public:
  static constexpr const char* name = "mls";
  explicit MlsReconstruction(const Scene& scene) : support_(scene.algorithm.mls_support) {}

  /// ρ and ρv at the Gauss points of every cell that holds particles, and σ, ρb when `stress` is set; returns the
  /// particle momentum Σ m_p v_p, Σ m_p |v_p|.
  template <class Body>
  MomentumTotals<Dim> rebuild(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                              const CellBins<Dim>&, const Body& body, bool stress, bool, FallbackCounts& fallbacks) {
    constexpr int KM = 1 + Dim, KS = sym_components<Dim> + Dim;
    std::vector<MomentumTotals<Dim>> totals(gp.grid.count());
    std::vector<FallbackCounts> counts(gp.grid.count());
    if (stress) fit<KM + KS>(gp, p, cells, body, totals, counts);
    else fit<KM>(gp, p, cells, body, totals, counts);
    for (const auto& c : counts) fallbacks += c;
    return sum_totals(totals);
  }

 private:
  /// K fields per particle: ρ, ρv, and σ, ρb when the stress is fitted.
  template <int K, class Body>
  void fit(GaussPointStore<Dim>& gp, const ParticleView<Dim>& p, const CellBins<Dim>& cells, const Body& body,
           std::vector<MomentumTotals<Dim>>& totals, std::vector<FallbackCounts>& counts) {
    constexpr int KM = 1 + Dim;
    const std::size_t np = cells.order().size();
    const unsigned* order = cells.order().data();
    const int reach = static_cast<int>(std::ceil(1.5 * support_));  // cells within the weight's support
    const MlsOptions opt{support_};
    Vec<Dim> h;
    for (int d = 0; d < Dim; ++d) h[d] = gp.grid.h[d];
    // Each particle's fields once per rebuild: the sums below visit a particle once for every Gauss point of the
    // cells around it (4 × 49 times with 2×2 Gauss points and the printed support), and computing its fields at
    // each visit (a determinant, a division, the plate's body force with its sines and cosines) was most of
    // the time of an MLS step.
    using Values = Eigen::Matrix<double, K, 1>;
    const ParticleFields<Dim, Body> fields{&p, &body};
    std::vector<Values>& values = scratch_.get<Values>(np);
    parallel_over(np, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t ip = b; ip < e; ++ip) {
        values[ip].template head<KM>() = fields.mass(ip);
        if constexpr (K > KM) values[ip].template tail<K - KM>() = fields.stress(ip);
      }
    });
    auto value_of = [&](std::size_t ip) -> const Values& { return values[ip]; };
    gp.grid.for_each_cell([&](std::size_t c) {
      const auto own_range = cells.block_range(c);
      const std::size_t first = gp.first_point(c);
      for (int g = 0; g < gp.per_cell; ++g) gp.clear_point(first + g);
      if (own_range.first == own_range.second) return;
      for (std::size_t k = own_range.first; k < own_range.second; ++k) {
        const std::size_t ip = order[k];
        double v[Dim];
        for (int d = 0; d < Dim; ++d) v[d] = p.v[d][ip];
        totals[c].add(p.m[ip], v);
      }
      detail::ParticleRanges<Dim, K, decltype(value_of)> src{&p, order, value_of};
      gp.grid.for_each_cell_near(c, reach, [&](std::size_t n) { src.add(cells.block_range(n)); });
      const double volume = gp.grid.box(c).volume();
      for (int g = 0; g < gp.per_cell; ++g) {
        Vec<Dim> xg;
        for (int d = 0; d < Dim; ++d) xg[d] = gp.x[d][first + g];
        const double w = gp.local_w[g] * volume;
        // One moment matrix A for all fields (paper eq. 10 depends on the positions and weights only): the mass
        // and the stress fits share it, so they are one solve with K right-hand sides and the same outcome.
        const auto val = mls_value(xg, h, src, opt);  // paper eq. 13
        counts[c].add(val.status);
        gp.m[first + g] = w * val.value[0];
        for (int d = 0; d < Dim; ++d) gp.q[d][first + g] = w * val.value[1 + d];
        if constexpr (K > KM) {
          counts[c].add(val.status);  // the stress fit, counted as it was when it had a solve of its own
          for (int k = 0; k < sym_components<Dim>; ++k) gp.s[k][first + g] = w * val.value[KM + k];
          for (int d = 0; d < Dim; ++d) gp.fb[d][first + g] = w * val.value[KM + sym_components<Dim> + d];
        }
      }
    });
  }

  double support_;  ///< the weight's scaling, in cells (algorithm.mls_support, paper eq. 9)
  ScratchStore scratch_;
};

}  // namespace mpm
