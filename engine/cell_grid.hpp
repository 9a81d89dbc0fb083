#pragma once
// The cells of the grid as the per-cell reconstructions see them: row-major cell indices, the box of a cell and
// its neighbours within a reach. One decomposition for the TLS and MLS rebuilds and the Gauss points they fill.
#include <array>
#include <cstddef>

#include "engine/parallel_over.hpp"
#include "kernels/reconstruction.hpp"
#include "kernels/stencil.hpp"

namespace mpm {

template <int Dim>
struct CellGrid {
  std::array<int, Dim> cells{};  ///< per axis
  std::array<double, Dim> h{};   ///< cell size per axis, m

  /// `cells` and `length` of the scene's grid (first Dim entries).
  template <class Cells, class Length>
  static CellGrid of(const Cells& cells, const Length& length) {
    CellGrid g;
    for (int d = 0; d < Dim; ++d) {
      g.cells[d] = cells[d];
      g.h[d] = length[d] / cells[d];
    }
    return g;
  }

  std::size_t count() const {
    std::size_t n = 1;
    for (int d = 0; d < Dim; ++d) n *= cells[d];
    return n;
  }

  /// Cell c as a box. Inlined: the neighbourhood fits take their neighbours' frames from it, where the call had
  /// been 2 % of a 2×2 TLS step.
  MPM_INLINE CellBox<Dim> box(std::size_t c) const {
    CellBox<Dim> b;
    for (int d = 0; d < Dim; ++d) {
      int i = static_cast<int>(c);  // the last axis' index is what is left: one division fewer
      if (d + 1 < Dim) {
        i = static_cast<int>(c % cells[d]);
        c /= cells[d];
      }
      b.lo[d] = i * h[d];
      b.hi[d] = (i + 1) * h[d];
    }
    return b;
  }

  /// Calls f(c) for every cell c (or every index c < count() of a per-cell array), in parallel, in chunks of 64.
  template <class F>
  void for_each_cell(F&& f) const {
    parallel_over(count(), 64, [&](std::size_t begin, std::size_t end) {
      for (std::size_t c = begin; c < end; ++c) f(c);
    });
  }

  /// Calls f(n) for the cells n next to cell c along `axis` (one or two).
  template <class F>
  void for_each_neighbour_along(std::size_t c, int axis, F&& f) const {
    const std::size_t stride = axis == 0 ? 1 : static_cast<std::size_t>(cells[0]);
    const int i = static_cast<int>(axis == 0 ? c % cells[0] : c / cells[0]);
    if (i > 0) f(c - stride);
    if (i + 1 < cells[axis]) f(c + stride);
  }

  /// Calls f(n) for every cell n within `reach` cells of cell c along each axis (c included), row-major order.
  template <class F>
  void for_each_cell_near(std::size_t c, int reach, F&& f) const {
    std::array<int, Dim> ci;
    std::size_t rest = c;
    for (int d = 0; d < Dim; ++d) {
      ci[d] = static_cast<int>(rest % cells[d]);
      rest /= cells[d];
    }
    const int span1 = Dim > 1 ? reach : 0;
    for (int j = -span1; j <= span1; ++j)
      for (int i = -reach; i <= reach; ++i) {
        const int a = ci[0] + i, b = Dim > 1 ? ci[Dim - 1] + j : 0;
        if (a < 0 || a >= cells[0] || (Dim > 1 && (b < 0 || b >= cells[Dim - 1]))) continue;
        f(Dim > 1 ? a + static_cast<std::size_t>(cells[0]) * b : static_cast<std::size_t>(a));
      }
  }
};

}  // namespace mpm
