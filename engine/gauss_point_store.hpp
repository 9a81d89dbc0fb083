#pragma once
// The Gauss points of a reconstructed mapping and what they carry (paper eqs 22–25, thesis eqs 5.16–5.17): fixed
// points in every cell, stored cell by cell in the order of coloured blocks, binned once (they never move). A
// reconstruction method (tls_rebuild.hpp, mls_rebuild.hpp, cubic_spline_rebuild.hpp) writes ρ̂ω, ρv̂ω, σ̂ω and
// ρb̂ω at them; the scatter (kernels/gauss_scatter.hpp) reads them.
#include <array>
#include <cstddef>
#include <vector>

#include "engine/cell_bins.hpp"
#include "engine/cell_grid.hpp"
#include "engine/scene.hpp"
#include "kernels/gauss_scatter.hpp"
#include "kernels/quadrature.hpp"

namespace mpm {

template <int Dim>
struct GaussPointStore {
  /// The points are stored cell by cell in the order of coloured blocks `block_width` cells wide, at least the
  /// narrowest width for the scene's stencil (CellBins::block_width_for, no slack: they never move). Given the
  /// width of the particles' bins, the TLS rebuild (which visits the cells in their block order) and the coloured
  /// scatter both run through the points front to back.
  GaussPointStore(const Scene& scene, int block_width);

  static constexpr int max_per_cell = 100;  ///< scene: gauss_per_cell ≤ 10 per axis (per-cell buffers on the stack)

  /// The index of the first Gauss point of cell c (row-major): cells in the block order of bins.
  std::size_t first_point(std::size_t c) const { return slot(c) * per_cell; }
  /// Cell c's rank in bins' block order: the index of its per-cell scratch. Pass 1 of a TLS rebuild visits the
  /// cells in that order and so writes the scratch front to back; indexed row-major, every block row of a block
  /// jumped a whole grid row ahead, to a page the prefetcher had not seen.
  std::size_t slot(std::size_t c) const { return slot_of_cell[c]; }
  /// Zeroes what Gauss point g carries.
  void clear_point(std::size_t g) {
    m[g] = 0.0;
    for (int d = 0; d < Dim; ++d) q[d][g] = fb[d][g] = 0.0;
    for (auto& col : s) col[g] = 0.0;
  }
  /// Places `rule` (on [0, 1]) on the part of [a, b] inside [lo, hi], as points first, first + 1, ... (1D); their
  /// weights into `w` (all zero, points spread over [a, b], when nothing is inside). Returns the part's length.
  double place_clipped(std::size_t first, const GaussRule& rule, double a, double b, double lo, double hi, double* w);
  GaussView<Dim> view() const;

  CellGrid<Dim> grid;
  int per_cell = 1;                                  ///< Gauss points per cell
  std::vector<std::array<double, Dim>> local;        ///< Gauss points of the unit cell, in [0, 1]^Dim
  std::array<std::vector<double>, Dim> axis_points;  ///< the tensor rule's points per axis (2D: local = their product)
  std::vector<double> local_w;                       ///< their weights (sum 1)
  std::array<std::vector<double>, Dim> x, q, fb;     ///< positions; ρv̂ω, ρb̂ω
  std::vector<double> m;                             ///< ρ̂ω
  std::array<std::vector<double>, sym_components<Dim>> s;  ///< σ̂ω
  CellBins<Dim> bins;
  std::vector<unsigned> slot_of_cell;  ///< per cell (row-major): its rank in bins' block order
  std::vector<unsigned> cell_of_slot;  ///< the inverse: the cells (row-major) in bins' block order
};

extern template struct GaussPointStore<1>;
extern template struct GaussPointStore<2>;

}  // namespace mpm
