#pragma once
// The Gauss-point integration path of reconstructed mappings (paper eqs 22–25, thesis eqs 5.16–5.17): per active
// cell, density, momentum density, stress and body-force density are reconstructed from the particles and
// evaluated at fixed Gauss points (gauss_point_store.hpp), which then take the particles' place in the P2G scatter
// (kernels/gauss_scatter.hpp). One unit per reconstruction method, each with the same two calls, rebuild and
// rebuild_momentum: TLS (tls_rebuild.hpp, thesis §5.3 / §6.1.1, conservative), MLS (mls_rebuild.hpp, paper
// eqs 6–17) and the cubic spline (cubic_spline_rebuild.hpp, thesis §3.2, 1D). The scene's choice is a variant
// alternative, resolved once per rebuild.
#include <type_traits>
#include <variant>

#include "engine/cell_bins.hpp"
#include "engine/cubic_spline_rebuild.hpp"
#include "engine/gauss_point_store.hpp"
#include "engine/mls_rebuild.hpp"
#include "engine/scene.hpp"
#include "engine/tls_rebuild.hpp"
#include "kernels/gauss_scatter.hpp"
#include "kernels/isa.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

template <int Dim>
class GaussPoints {
 public:
  /// The Gauss points in blocks `block_width` cells wide (GaussPointStore), given the width of the particles'
  /// bins so that the TLS rebuild and the coloured scatter both run through them front to back.
  GaussPoints(const Scene& scene, int block_width);
  /// The narrowest block width.
  explicit GaussPoints(const Scene& scene);

  /// Reconstructs at the Gauss points of every cell that holds particles: ρ always (TLS: conservative), ρv when
  /// `momentum` or not `stress` (the scatter reads it), σ and ρb when `stress` is set. `particles_by_cell` must bin
  /// the particles by single cells (block width 1); `layout`: the bins whose block order the particle columns
  /// follow (TLS visits the cells in that order). Returns the particle momentum Σ m_p v_p, Σ m_p |v_p| (for the
  /// conservation check) when ρv is reconstructed, else zero.
  template <class Body>
  MomentumTotals<Dim> rebuild(const ParticleView<Dim>& p, const CellBins<Dim>& particles_by_cell,
                              const CellBins<Dim>& layout, const Body& body, bool stress, bool momentum) {
    return std::visit(
        [&](auto& method) {
          return method.rebuild(store_, p, particles_by_cell, layout, body, stress, momentum, fallbacks_);
        },
        method_);
  }

  /// The momentum again after a rebuild, when the particles' velocities are all that changed since (the second
  /// P2G of MUSL: positions, J and masses as in that rebuild): the same numbers as rebuild(…, false, true). A method
  /// that can reuse the rebuild's work has a rebuild_momentum of its own (TLS: the density and normal matrices).
  template <class Body>
  MomentumTotals<Dim> rebuild_momentum(const ParticleView<Dim>& p, const CellBins<Dim>& particles_by_cell,
                                       const CellBins<Dim>& layout, const Body& body) {
    return std::visit(
        [&](auto& method) {
          if constexpr (requires { method.rebuild_momentum(store_, p, particles_by_cell, layout, body, fallbacks_); })
            return method.rebuild_momentum(store_, p, particles_by_cell, layout, body, fallbacks_);
          else
            return method.rebuild(store_, p, particles_by_cell, layout, body, false, true, fallbacks_);
        },
        method_);
  }

  /// P2G from the Gauss points into g (paper eqs 22–25), coloured blocks in parallel: in 2D on the uniform fast
  /// path whole cells at a time from tabulated weights (scatter_gauss_cells), else point by point (scatter_gauss).
  template <ScatterFields Fields, bool Body, int S, class Axis>
  void scatter(const TensorBasis<Dim, Axis>& basis, GridView<Dim> g) const {
    const GaussView<Dim> gp = view();
    const CellBins<Dim>& bins = store_.bins;
    if constexpr (Dim == 2 && std::is_same_v<Axis, UniformAxis<S>>) {
      // 2D points sit at the same local coordinates in every cell, stored cell after cell in block order
      const GaussRowTable<S> table(basis, store_.axis_points);
      const bool two_by_two = table.n[0] == 2 && table.n[1] == 2;  // the default rule, unrolled
      const unsigned* cells = store_.cell_of_slot.data();
      bins.for_each_block_coloured([&](std::size_t b, std::size_t e) {
        with_active_isa([&](auto) {
          if (two_by_two)
            scatter_gauss_cells<Fields, Body, S, 2>(table, basis.axis[0], basis.axis[1], gp, g, cells, b, e);
          else
            scatter_gauss_cells<Fields, Body, S>(table, basis.axis[0], basis.axis[1], gp, g, cells, b, e);
        });
      });
    } else {
      const unsigned* order = bins.order().data();
      bins.for_each_block_coloured([&](std::size_t b, std::size_t e) {
        with_active_isa([&](auto) { scatter_gauss<Fields, Body, Dim, S>(basis, gp, g, order, b, e); });
      });
    }
  }

  /// The Gauss points and their fields; as MassCarriers, the carriers of the consistent mass
  /// M_ij = Σ_g φ_i ρ̂ω φ_j (thesis eq. 3.9).
  GaussView<Dim> view() const { return store_.view(); }
  const CellBins<Dim>& bins() const { return store_.bins; }
  const FallbackCounts& fallbacks() const { return fallbacks_; }
  /// The reconstruction's name in the pipeline's stage names ("tls", "mls", "cubic-spline").
  const char* name() const {
    return std::visit([](const auto& method) { return method.name; }, method_);
  }

 private:
  using Method = std::variant<TlsReconstruction<Dim>, MlsReconstruction<Dim>, CubicSplineReconstruction<Dim>>;
  static Method method_of(const Scene& scene);

  GaussPointStore<Dim> store_;
  Method method_;
  FallbackCounts fallbacks_;
};


}  // namespace mpm
