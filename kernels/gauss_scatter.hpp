#pragma once
// P2G from the Gauss points of a reconstructed mapping (paper eqs 22–25, thesis eqs 5.16–5.17): the Gauss points
// take the particles' place in the scatter, carrying the reconstructed fields times their quadrature weight.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "kernels/stencil.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

/// The reconstructed fields at the Gauss points, already multiplied by the quadrature weight ω_g: the points as
/// mass carriers (x, and m = ρ̂ω) and what else they carry.
template <int Dim>
struct GaussView : MassCarriers<Dim> {
  std::array<const double*, Dim> q{};               ///< ρv̂ ω
  std::array<const double*, sym_components<Dim>> s{};  ///< σ̂ ω
  std::array<const double*, Dim> fb{};              ///< ρb̂ ω
};

/// P2G from Gauss points order[begin..end) (paper eqs 22–25): m_i += φ_i ρ̂ω, q_i += φ_i ρv̂ω,
/// f_i += −∇φ_i·σ̂ω + φ_i ρb̂ω. The points of a cell share the nodes of their stencils (a cell is a knot span) and
/// come one after another: their shares are summed into a stencil-sized local buffer by the particles' kernel
/// (scatter_rows) and added to the grid once per run of points with the same first node. With 2×2 points per cell
/// that is a quarter of the read-modify-writes of grid rows, and none of the store-forwarding stalls of a point
/// reloading the rows the one before it just wrote.
template <ScatterFields Fields, bool Body, int Dim, int S, class Axis>
inline void scatter_gauss(const TensorBasis<Dim, Axis>& basis, GaussView<Dim> gp, GridView<Dim> g,
                          const unsigned* order, std::size_t begin, std::size_t end) {
  constexpr int lanes = stencil_lanes<S>, rows = Dim == 1 ? 1 : S, size = rows * lanes;
  alignas(64) double m[size], q[Dim][size], f[Dim][size];
  GridView<Dim> local;  // the buffer as a grid of one stencil, first node (0, 0)
  local.stride1 = lanes;
  local.m = m;
  for (int d = 0; d < Dim; ++d) {
    local.q[d] = q[d];
    local.f[d] = f[d];
  }
  int first0 = -1, first1 = 0;
  auto flush = [&] {
    if (first0 < 0) return;
    for (int j = 0; j < rows; ++j) {
      const int row = (first1 + j) * g.stride1 + first0, at = j * lanes;
      if constexpr (Fields.mass) add_to_row(g.m + row, load_row<RowVector<S>>(m + at));
      for (int d = 0; d < Dim; ++d) {
        if constexpr (Fields.momentum) add_to_row(g.q[d] + row, load_row<RowVector<S>>(q[d] + at));
        if constexpr (Fields.force) add_to_row(g.f[d] + row, load_row<RowVector<S>>(f[d] + at));
      }
    }
  };
  for (std::size_t k = begin; k < end; ++k) {
    const std::size_t ig = order[k];
    auto st = stencil_of<Dim, S>(basis, gp.x, ig);
    if (st.first0 != first0 || st.first1 != first1) {  // another cell: the buffer goes to the grid
      flush();
      first0 = st.first0;
      first1 = st.first1;
      if constexpr (Fields.mass) std::fill_n(m, size, 0.0);
      for (int d = 0; d < Dim; ++d) {
        if constexpr (Fields.momentum) std::fill_n(q[d], size, 0.0);
        if constexpr (Fields.force) std::fill_n(f[d], size, 0.0);
      }
    }
    st.first0 = st.first1 = 0;
    double mv[Dim] = {}, Vsig[Dim][Dim] = {}, mb[Dim] = {};
    for (int d = 0; d < Dim; ++d) {
      if constexpr (Fields.momentum) mv[d] = gp.q[d][ig];
      if constexpr (Body && Fields.force) mb[d] = gp.fb[d][ig];
      if constexpr (Fields.force)
        for (int l = 0; l < Dim; ++l) Vsig[l][d] = gp.s[sym_index<Dim>(l, d)][ig];
    }
    scatter_rows<Fields>(st, local, Fields.mass ? gp.m[ig] : 0.0, mv, Vsig, mb);
  }
  flush();
}

/// The B-spline rows of a cell's Gauss points in 2D, per axis and span class: on a uniform grid every cell of a
/// span class (UniformAxis::span_class) sees its points at the same local coordinates, so their weights are
/// evaluated once per scatter instead of once per point. Axis 0 as SIMD rows, axis 1 as scalars (one per row).
template <int S>
struct GaussRowTable {
  /// quadratic: interior, first cell, last cell, first and last (one cell); linear: one (UniformAxis::span_class)
  static constexpr int classes = static_cast<int>(UniformAxis<S>::coefficients.size());
  static constexpr int max_points = 10;  ///< per axis (the scene caps gauss_per_cell at 10)
  std::array<int, 2> n{};            ///< points per axis
  std::array<std::array<RowVector<S>, max_points>, classes> wx, dwx;
  std::array<std::array<std::array<double, S>, max_points>, classes> wy, dwy;

  GaussRowTable(const TensorBasis<2, UniformAxis<S>>& basis, const std::array<std::vector<double>, 2>& local) {
    for (int d = 0; d < 2; ++d) n[d] = static_cast<int>(local[d].size());
    for (int c = 0; c < classes; ++c) {
      for (int i = 0; i < n[0]; ++i) {
        const AxisRow<S> r = uniform_row<S>(basis.axis[0], 0, c, local[0][i]);
        wx[c][i] = r.w;
        dwx[c][i] = r.dw;
      }
      for (int j = 0; j < n[1]; ++j) {
        const AxisRow<S> r = uniform_row<S>(basis.axis[1], 0, c, local[1][j]);
        for (int b = 0; b < S; ++b) {
          wy[c][j][b] = r.w[b];
          dwy[c][j][b] = r.dw[b];
        }
      }
    }
  }
};

/// P2G from the Gauss points of whole cells in 2D on a uniform grid (paper eqs 22–25, as scatter_gauss): the
/// points of cell slots [begin, end) / per cell, tabulated rows (GaussRowTable), `N` points per axis (0: as the
/// table says). A cell's points all write its S × S nodes, so the sums are contracted along axis 0 over the
/// points of each point row first (one SIMD row per point row and field), then along axis 1 into the S node rows,
/// each added to the grid once: with 2×2 points about a tenth of the instructions of a stencil per point.
template <ScatterFields Fields, bool Body, int S, int N = 0>
void scatter_gauss_cells(const GaussRowTable<S>& t, const UniformAxis<S>& axis0, const UniformAxis<S>& axis1,
                         GaussView<2> gp, GridView<2> g, const unsigned* cell_of_slot, std::size_t begin,
                         std::size_t end) {
  const int n0 = N > 0 ? N : t.n[0], n1 = N > 0 ? N : t.n[1], per_cell = n0 * n1;
  constexpr int rows = N > 0 ? N : GaussRowTable<S>::max_points;
  for (std::size_t first = begin; first < end; first += per_cell) {
    const std::size_t c = cell_of_slot[first / per_cell];
    const int i = static_cast<int>(c % axis0.cells), j = static_cast<int>(c / axis0.cells);
    const int cx = axis0.span_class(i), cy = axis1.span_class(j);
    // per point row gj, Σ over its points of: wx ρ̂ω; wx ρv̂ω; wx ρb̂ω − dwx σ̂_0dω (times wy later); wx σ̂_1dω (dwy)
    RowVector<S> m_y[rows], q_y[2][rows], f_wy[2][rows], f_dwy[2][rows];
    for (int gj = 0; gj < n1; ++gj) {
      m_y[gj] = 0.0;
      for (int d = 0; d < 2; ++d) q_y[d][gj] = f_wy[d][gj] = f_dwy[d][gj] = 0.0;
      for (int gi = 0; gi < n0; ++gi) {
        const std::size_t ig = first + gi + static_cast<std::size_t>(n0) * gj;
        const RowVector<S>& wx = t.wx[cx][gi];
        if constexpr (Fields.mass) m_y[gj] += wx * gp.m[ig];
        for (int d = 0; d < 2; ++d) {
          if constexpr (Fields.momentum) q_y[d][gj] += wx * gp.q[d][ig];
          if constexpr (Fields.force) {
            if constexpr (Body) f_wy[d][gj] += wx * gp.fb[d][ig];
            f_wy[d][gj] -= t.dwx[cx][gi] * gp.s[sym_index<2>(0, d)][ig];
            f_dwy[d][gj] += wx * gp.s[sym_index<2>(1, d)][ig];
          }
        }
      }
    }
    for (int b = 0; b < S; ++b) {
      RowVector<S> m_row = 0.0, q_row[2] = {0.0, 0.0}, f_row[2] = {0.0, 0.0};
      for (int gj = 0; gj < n1; ++gj) {
        const double wy = t.wy[cy][gj][b], dwy = t.dwy[cy][gj][b];
        if constexpr (Fields.mass) m_row += wy * m_y[gj];
        for (int d = 0; d < 2; ++d) {
          if constexpr (Fields.momentum) q_row[d] += wy * q_y[d][gj];
          if constexpr (Fields.force) f_row[d] += wy * f_wy[d][gj] - dwy * f_dwy[d][gj];
        }
      }
      const int row = (j + b) * g.stride1 + i;
      if constexpr (Fields.mass) add_to_row(g.m + row, m_row);
      for (int d = 0; d < 2; ++d) {
        if constexpr (Fields.momentum) add_to_row(g.q[d] + row, q_row[d]);
        if constexpr (Fields.force) add_to_row(g.f[d] + row, f_row[d]);
      }
    }
  }
}

}  // namespace mpm
