#pragma once
// The Gauss-point integration path of reconstructed mappings (paper eqs 22–25, thesis eqs 5.16–5.17):
// per active cell, density, momentum density, stress and body-force density are reconstructed from the cell's
// particles (TLS, thesis §5.3 / §6.1.1; or MLS, paper eqs 6–17) and evaluated at fixed Gauss points, which then
// take the particles' place in the P2G scatter. Gauss points never move: they are binned into coloured blocks
// once. TLS fixes each cell's first Taylor coefficient from the particle sums, so the grid receives exactly
// Σ m_p and Σ m_p v_p (Gauss rules with ≥ 2 points per axis integrate the quadratic Taylor basis exactly).
// In 1D the TLS cell is the occupied part of the cell: the cell clipped to the body's current extent
// (body_extent.hpp). Spreading a partly filled end cell's mass over the whole cell puts mass where there is no
// body and, measured on the column (4 particles per cell, 50 cells), made its displacement error 8e-2 against
// 4.7e-5 for direct mapping; on the clipped cell the Taylor basis is mean-free again, so eq. 5.9 still conserves.
//
// The cubic-spline (CS) mapping (1D, thesis §3.2) reconstructs globally instead: one cubic spline per field
// through all particles of the body, evaluated at `gauss_per_cell` Gauss points in each half of every knot
// span (thesis §3.2.3, Fig. 3.4: two per half), restricted to the body's current extent. It is the thesis'
// non-conservative comparison method: ∫ρ̂ and ∫ρv̂ differ from Σ m_p and Σ m_p v_p by the interpolation error.
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <stdexcept>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "engine/body_extent.hpp"
#include "engine/cell_bins.hpp"
#include "engine/parallel_over.hpp"
#include "engine/scene.hpp"
#include "kernels/cubic_spline.hpp"
#include "kernels/mls.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/taylor_ls.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

/// The reconstructed fields at the Gauss points, already multiplied by the quadrature weight ω_g.
template <int Dim>
struct GaussView {
  std::array<const double*, Dim> x{};
  const double* m = nullptr;                        ///< ρ̂ ω
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
    double xg[Dim];
    for (int d = 0; d < Dim; ++d) xg[d] = gp.x[d][ig];
    auto st = stencil_at<Dim, S>(basis, xg);
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

/// What a TLS rebuild fits besides the density: the velocity (for a scatter of momentum), the stress and the body
/// force (for a scatter of force). `reuse`: the velocity alone, the density and the normal matrices kept from the
/// last rebuild (GaussPoints::rebuild_momentum). Fitting only what the next scatter reads: MUSL's first P2G
/// scatters no momentum, and with no body force the ρb fits are zeros.
struct TlsFields {
  bool velocity = false;
  bool stress = false;
  bool reuse = false;
};

template <int Dim>
class GaussPoints {
 public:
  /// The Gauss points are stored cell by cell in the order of coloured blocks `block_width` cells wide, at
  /// least the narrowest width for the scene's stencil (CellBins::block_width_for, no slack: they never move).
  /// Given the width of the particles' bins, the TLS rebuild (which visits the cells in their block order) and
  /// the coloured scatter both run through the Gauss points front to back.
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
                              const CellBins<Dim>& layout, const Body& body, bool stress, bool momentum);

  /// The momentum again after a rebuild, when the particles' velocities are all that changed since (the second
  /// P2G of MUSL: positions, J and masses as in that rebuild). TLS keeps that rebuild's density at the Gauss
  /// points, its density fallbacks and its own and neighbourhood normal matrices, and sums and fits only the
  /// velocity: the same numbers as rebuild(…, false, true), for a fraction of its cost. MLS and the cubic spline
  /// rebuild as usual.
  template <class Body>
  MomentumTotals<Dim> rebuild_momentum(const ParticleView<Dim>& p, const CellBins<Dim>& particles_by_cell,
                                       const CellBins<Dim>& layout, const Body& body);

  /// P2G from the Gauss points into g (paper eqs 22–25), coloured blocks in parallel: in 2D on the uniform fast
  /// path whole cells at a time from tabulated weights (scatter_gauss_cells), else point by point (scatter_gauss).
  template <ScatterFields Fields, bool Body, int S, class Axis>
  void scatter(const TensorBasis<Dim, Axis>& basis, GridView<Dim> g) const;

  GaussView<Dim> view() const;
  /// The Gauss points as mass carriers, for the consistent-mass operator M_ij = Σ_g φ_i ρ̂ω φ_j (thesis eq. 3.9).
  ParticleView<Dim> mass_view();
  const CellBins<Dim>& bins() const { return bins_; }
  const FallbackCounts& fallbacks() const { return fallbacks_; }
  /// The reconstruction's name in the pipeline's stage names ("tls", "mls", "cubic-spline").
  const char* name() const {
    switch (mapping_) {
      case Mapping::mls: return "mls";
      case Mapping::cubic_spline: return "cubic-spline";
      default: return "tls";
    }
  }

 private:
  /// TLS of the fields `Fit` names, at the scene's Taylor degree.
  template <TlsFields Fit, class Body>
  MomentumTotals<Dim> rebuild_tls(const ParticleView<Dim>& p, const CellBins<Dim>& cells, const CellBins<Dim>& layout,
                                  const Body& body);
  template <int Degree, TlsFields Fit, class Body>
  MomentumTotals<Dim> rebuild_tls_of_degree(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                            const CellBins<Dim>& layout, const Body& body);
  template <class Body>
  MomentumTotals<Dim> rebuild_mls(const ParticleView<Dim>& p, const CellBins<Dim>& cells, const Body& body,
                                  bool stress);
  template <class Body>
  MomentumTotals<Dim> rebuild_cubic_spline(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                           const Body& body, bool stress);
  /// The particles in order of position (1D), into sorted_; their totals Σ m_p v_p, Σ m_p |v_p|.
  MomentumTotals<Dim> sort_by_position(const ParticleView<Dim>& p, const CellBins<Dim>& cells);
  /// Places the Gauss points of half `half` of cell c on its part inside [lo, hi] (thesis Fig. 3.4); returns
  /// their weights into `w` (all zero when the half lies outside).
  void place_half_span(std::size_t c, int half, double lo, double hi, double* w);
  /// Places `rule` (on [0, 1]) on the part of [a, b] inside [lo, hi], as points first, first + 1, ... (1D); their
  /// weights into `w` (all zero, points spread over [a, b], when nothing is inside). Returns the part's length.
  double place_clipped(std::size_t first, const GaussRule& rule, double a, double b, double lo, double hi, double* w);
  /// The index of the first Gauss point of cell c (row-major): cells in the block order of bins_.
  std::size_t first_point(std::size_t c) const { return slot(c) * per_cell_; }
  /// Cell c's rank in bins_' block order: the index of its TLS scratch. Pass 1 of a rebuild visits the cells in
  /// that order and so writes the scratch front to back; indexed row-major, every block row of a block jumped a
  /// whole grid row ahead, to a page the prefetcher had not seen.
  std::size_t slot(std::size_t c) const { return slot_[c]; }
  /// Zeroes what Gauss point g carries.
  void clear_point(std::size_t g) {
    m_[g] = 0.0;
    for (int d = 0; d < Dim; ++d) q_[d][g] = fb_[d][g] = 0.0;
    for (auto& col : s_) col[g] = 0.0;
  }
  /// Inlined: the neighbourhood fits take their neighbours' frames from it, where the call had been 2 % of a 2×2
  /// TLS step.
  MPM_INLINE CellBox<Dim> cell_box(std::size_t c) const {
    CellBox<Dim> box;
    for (int d = 0; d < Dim; ++d) {
      int i = static_cast<int>(c);  // the last axis' index is what is left: one division fewer
      if (d + 1 < Dim) {
        i = static_cast<int>(c % cells_[d]);
        c /= cells_[d];
      }
      box.lo[d] = i * h_[d];
      box.hi[d] = (i + 1) * h_[d];
    }
    return box;
  }
  /// Storage of type T for n items that outlives a rebuild: no allocation per step once it is large enough, one
  /// store per type (the two rebuilds of a MUSL step use different ones; sharing one store reallocated it twice a
  /// step: 8 % of a 1e6-particle TLS step went to its page faults).
  template <class T>
  std::vector<T>& scratch(std::size_t n) {
    Scratch<T>* s = nullptr;
    for (const auto& store : scratch_)
      if ((s = dynamic_cast<Scratch<T>*>(store.get()))) break;
    if (!s) {
      auto fresh = std::make_unique<Scratch<T>>();
      s = fresh.get();
      scratch_.push_back(std::move(fresh));
    }
    s->items.resize(n);
    return s->items;
  }
  /// Calls f(c) for every cell c < ncells, in parallel, in chunks of 64 cells.
  template <class F>
  static void for_each_cell(std::size_t ncells, F&& f) {
    parallel_over(ncells, 64, [&](std::size_t begin, std::size_t end) {
      for (std::size_t c = begin; c < end; ++c) f(c);
    });
  }
  /// Calls f(n) for the cells n next to cell c along `axis` (one or two).
  template <class F>
  void for_each_neighbour_along(std::size_t c, int axis, F&& f) const {
    const std::size_t stride = axis == 0 ? 1 : static_cast<std::size_t>(cells_[0]);
    const int i = static_cast<int>(axis == 0 ? c % cells_[0] : c / cells_[0]);
    if (i > 0) f(c - stride);
    if (i + 1 < cells_[axis]) f(c + stride);
  }
  /// Calls f(n) for every cell n within `reach` cells of cell c along each axis (c included), row-major order.
  template <class F>
  void for_each_cell_near(std::size_t c, int reach, F&& f) const {
    std::array<int, Dim> ci;
    std::size_t rest = c;
    for (int d = 0; d < Dim; ++d) {
      ci[d] = static_cast<int>(rest % cells_[d]);
      rest /= cells_[d];
    }
    const int span1 = Dim > 1 ? reach : 0;
    for (int j = -span1; j <= span1; ++j)
      for (int i = -reach; i <= reach; ++i) {
        const int a = ci[0] + i, b = Dim > 1 ? ci[Dim - 1] + j : 0;
        if (a < 0 || a >= cells_[0] || (Dim > 1 && (b < 0 || b >= cells_[Dim - 1]))) continue;
        f(Dim > 1 ? a + static_cast<std::size_t>(cells_[0]) * b : static_cast<std::size_t>(a));
      }
  }

  Mapping mapping_;
  int tls_degree_;
  double mls_support_;
  std::array<int, Dim> cells_;
  std::array<double, Dim> h_;
  static constexpr int max_per_cell = 100;  ///< scene: gauss_per_cell ≤ 10 per axis (per-cell buffers on the stack)
  int per_cell_ = 1;                    ///< Gauss points per cell
  std::vector<std::array<double, Dim>> local_;  ///< Gauss points of the unit cell, in [0, 1]^Dim
  std::array<std::vector<double>, Dim> axis_points_;  ///< the tensor rule's points per axis (2D: local_ = their product)
  std::vector<double> local_w_;                 ///< their weights (sum 1)
  std::array<std::vector<double>, Dim> x_, q_, fb_;
  std::vector<double> m_;
  std::array<std::vector<double>, sym_components<Dim>> s_;
  CellBins<Dim> bins_;
  std::vector<unsigned> slot_;          ///< per cell (row-major): its rank in bins_' block order
  std::vector<unsigned> cell_of_slot_;  ///< the inverse: the cells (row-major) in bins_' block order
  FallbackCounts fallbacks_;
  struct ScratchBase {
    virtual ~ScratchBase() = default;
  };
  template <class T>
  struct Scratch : ScratchBase {
    std::vector<T> items;
  };
  std::vector<std::unique_ptr<ScratchBase>> scratch_;  ///< per-cell sums of TLS rebuilds, kept between passes
  bool tls_kept_ = false;  ///< a TLS rebuild left what rebuild_momentum reuses
  // cubic-spline mapping only (1D)
  GaussRule half_rule_;                                    ///< Gauss rule of a half knot span, on [0, 1]
  GaussRule cell_rule_;                                    ///< 1D TLS: the Gauss rule of a cell, on [0, 1]
  std::vector<unsigned> sorted_;                           ///< particle indices by position
  std::vector<MomentumTotals<Dim>> cell_totals_;
  CubicSpline<1 + Dim> mass_spline_;                       ///< ρ, ρv
  CubicSpline<sym_components<Dim> + Dim> stress_spline_;   ///< σ, ρb
};

}  // namespace mpm

// ---- implementation of the templates ----------------------------------------------------------------------

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
template <ScatterFields Fields, bool Body, int S, class Axis>
void GaussPoints<Dim>::scatter(const TensorBasis<Dim, Axis>& basis, GridView<Dim> g) const {
  const GaussView<Dim> gp = view();
  if constexpr (Dim == 2 && std::is_same_v<Axis, UniformAxis<S>>) {
    // 2D points sit at the same local coordinates in every cell, stored cell after cell in block order
    const GaussRowTable<S> table(basis, axis_points_);
    const bool two_by_two = table.n[0] == 2 && table.n[1] == 2;  // the default rule, unrolled
    bins_.for_each_block_coloured([&](std::size_t b, std::size_t e) {
      if (two_by_two)
        scatter_gauss_cells<Fields, Body, S, 2>(table, basis.axis[0], basis.axis[1], gp, g, cell_of_slot_.data(), b, e);
      else
        scatter_gauss_cells<Fields, Body, S>(table, basis.axis[0], basis.axis[1], gp, g, cell_of_slot_.data(), b, e);
    });
  } else {
    const unsigned* order = bins_.order().data();
    bins_.for_each_block_coloured(
        [&](std::size_t b, std::size_t e) { scatter_gauss<Fields, Body, Dim, S>(basis, gp, g, order, b, e); });
  }
}

template <int Dim>
template <class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                              const CellBins<Dim>& layout, const Body& body, bool stress,
                                              bool momentum) {
  if (mapping_ == Mapping::mls) return rebuild_mls(p, cells, body, stress);
  if (mapping_ == Mapping::cubic_spline) return rebuild_cubic_spline(p, cells, body, stress);
  if (!stress) return rebuild_tls<TlsFields{.velocity = true}>(p, cells, layout, body);
  if (momentum) return rebuild_tls<TlsFields{.velocity = true, .stress = true}>(p, cells, layout, body);
  return rebuild_tls<TlsFields{.stress = true}>(p, cells, layout, body);
}

template <int Dim>
template <class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild_momentum(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                                       const CellBins<Dim>& layout, const Body& body) {
  if (mapping_ != Mapping::tls || !tls_kept_) return rebuild(p, cells, layout, body, false, true);
  return rebuild_tls<TlsFields{.velocity = true, .reuse = true}>(p, cells, layout, body);
}

template <int Dim>
template <TlsFields Fit, class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild_tls(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                                  const CellBins<Dim>& layout, const Body& body) {
  switch (tls_degree_) {
    case 0: return rebuild_tls_of_degree<0, Fit>(p, cells, layout, body);
    case 1: return rebuild_tls_of_degree<1, Fit>(p, cells, layout, body);
    default: return rebuild_tls_of_degree<2, Fit>(p, cells, layout, body);
  }
}

/// Per-particle fields the fits read: (ρ, ρv) and (σ, ρb), with ρ = m / (J V0).
template <int Dim, class Body>
struct ParticleFields {
  const ParticleView<Dim>* p;
  const Body* body;
  double volume(std::size_t ip) const { return det(*p, ip) * p->V0[ip]; }  // V_p = J_p V0_p (eq. 2.42)
  double rho(std::size_t ip) const { return p->m[ip] / volume(ip); }
  Eigen::Matrix<double, 1 + Dim, 1> mass(std::size_t ip) const {
    Eigen::Matrix<double, 1 + Dim, 1> f;
    f[0] = rho(ip);
    for (int d = 0; d < Dim; ++d) f[1 + d] = f[0] * p->v[d][ip];
    return f;
  }
  Eigen::Matrix<double, sym_components<Dim> + Dim, 1> stress(std::size_t ip) const {
    Eigen::Matrix<double, sym_components<Dim> + Dim, 1> f;
    for (int c = 0; c < sym_components<Dim>; ++c) f[c] = p->s[c][ip];
    std::array<double, Dim> b{};
    if constexpr (Body::active) b = body->template at<Dim>(ip);
    const double r = rho(ip);
    for (int d = 0; d < Dim; ++d) f[sym_components<Dim> + d] = r * b[d];
    return f;
  }
};

namespace detail {

/// Bounds the reconstruction at the Gauss points by the data it came from (a Barth–Jespersen-type limiter):
/// per field, the deviations from the cell mean are scaled by the largest α ∈ [0, 1] that keeps every Gauss-point
/// value inside [min, max] of the cell's samples and its mean (`lo`, `hi`: the samples' bounds). The higher
/// Taylor functions integrate to zero over the cell, so scaling them leaves the integral — mass, momentum —
/// exactly as the constraint set it. Without it, a fit through a few clustered particles of a strongly compressed
/// cell extrapolates to wild (even negative) densities at the Gauss points, which is how 2D MPM–TLS diverges
/// (thesis §6.3.1).
/// `psi`: the Taylor basis at the Gauss points, the same in every cell's frame. Inlined: as a call, it reloaded
/// the fit its caller had just stored (the 2×2 TLS step 1–2 % faster inlined, two A/B runs of 5).
template <int Dim, int Degree, int K>
MPM_INLINE void limited_values(const TaylorFit<Dim, Degree, K>& fit, const Eigen::Matrix<double, K, 1>& lo,
                               const Eigen::Matrix<double, K, 1>& hi, std::span<const TaylorVector<Dim, Degree>> psi,
                               Eigen::Matrix<double, K, 1>* values) {
  constexpr int N = TaylorFit<Dim, Degree, K>::size;
  const std::size_t points = psi.size();
  for (int k = 0; k < K; ++k) {
    // The deviations from the mean c_0 are the higher terms alone, Σ_{n≥1} c_n ψ_n: summed directly, not as the
    // value less the mean. (The Eigen form, on 1–3 fields at a time, took 12 % of a 2×2 TLS step's time; these
    // plain loops made the step 3 % faster.)
    const double mean = fit.c(0, k);
    double dev_max = 0.0, dev_min = 0.0;
    for (std::size_t g = 0; g < points; ++g) {
      double dev = 0.0;
      for (int n = 1; n < N; ++n) dev += fit.c(n, k) * psi[g][n];
      values[g][k] = dev;
      dev_max = std::max(dev_max, dev);
      dev_min = std::min(dev_min, dev);
    }
    // α = min(1, (hi − mean) / max dev, (mean − lo) / |min dev|) over the bounds widened to the mean: each ratio
    // falls as |dev| grows (and correctly rounded division keeps that order), so the extreme deviations alone
    // decide — two divisions per field and no branch. A side without deviations divides by +0 and gives +inf or
    // NaN, both of which std::min(α, ·) passes over.
    const double up = std::max(hi[k], mean) - mean, down = mean - std::min(lo[k], mean);
    const double alpha = std::min(std::min(1.0, up / std::abs(dev_max)), down / std::abs(dev_min));
    for (std::size_t g = 0; g < points; ++g) values[g][k] = mean + alpha * values[g][k];
  }
}

/// What a neighbourhood fit needs of its own cell besides the normal sums: the bounds of the unconstrained fields
/// over the cell's particles (for the limiter) and the cell's momentum (for the momentum shift).
template <int Dim, int KF>
struct TlsFitBounds {
  Eigen::Matrix<double, KF, 1> lo, hi;
  Eigen::Matrix<double, Dim, 1> momentum;
};

/// What a TLS rebuild sums per cell over the cell's own particles, in the cell's Taylor frame, in its first pass:
/// the normal system of all K fields (ρ | v | σ | ρb, those the rebuild fits; the fits share the samples, hence D),
/// the fields' bounds for the limiter, and the cell's mass and momentum for the constraints. The last KF fields
/// are the unconstrained fits (the row sums of pass 2 hold them alone).
template <int Dim, int Degree, int K, int KF>
struct TlsCellSums {
  CellBox<Dim> box;         ///< the TLS cell (1D: clipped to the body)
  TaylorFrame<Dim> frame;   ///< its Taylor frame, in which the sums are taken
  TaylorNormalSystem<Dim, Degree, K> sys;
  Eigen::Matrix<double, K, 1> lo = Eigen::Matrix<double, K, 1>::Zero();  ///< the fields' bounds over the cell's
  Eigen::Matrix<double, K, 1> hi = Eigen::Matrix<double, K, 1>::Zero();  ///< particles
  double mass = 0.0;
  Eigen::Matrix<double, Dim, 1> momentum = Eigen::Matrix<double, Dim, 1>::Zero();
  /// What the unconstrained fits' limiter and the momentum shift read of the cell.
  TlsFitBounds<Dim, KF> bounds() const { return {lo.template tail<KF>(), hi.template tail<KF>(), momentum}; }
  /// Fields [first, first + count) of the system, as a system of their own.
  template <int First, int Count>
  TaylorNormalSystem<Dim, Degree, Count> fields() const {
    TaylorNormalSystem<Dim, Degree, Count> f;
    f.D = sys.D;
    f.b = sys.b.template middleCols<Count>(First);
    f.shift = sys.shift.template segment<Count>(First);
    f.shift_set = sys.shift_set;
    f.points = sys.points;
    return f;
  }
};

/// What a TLS rebuild keeps of a cell for a later momentum-only rebuild of the same particle positions
/// (GaussPoints::rebuild_momentum), all of which depends on the positions only: the density fit's outcome (its
/// values stay at the Gauss points); whether the cell's own particles determined its fit, and then the factors
/// of their normal matrix (refactorising it was 4.5 % of a 2×2 MUSL-TLS step). 72 bytes in 2D at degree 1.
template <int Dim, int Degree>
struct TlsKeptFit {
  FitStatus rho;
  bool near_sparse = false;  ///< next to a cell too sparse for its own fit: the neighbourhood fits read its sums
  bool own_fitted = false;
  PivotedLdlt<taylor_size<Dim>(Degree)> own_factors;
};

/// The same for the cells whose sums the neighbourhood fits read: their own normal matrix and, for those fitted
/// to their neighbourhood, its matrix. Apart from TlsKeptFit, which every cell writes: with these in it, the
/// record of every cell was 216 bytes, most of them unused.
template <int Dim, int Degree>
struct TlsKeptMatrices {
  static constexpr int N = taylor_size<Dim>(Degree);
  Eigen::Matrix<double, N, N> own_D, neighbourhood_D;
};

}  // namespace detail

template <int Dim>
template <int Degree, TlsFields Fit, class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild_tls_of_degree(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                                            const CellBins<Dim>& layout, const Body& body) {
  constexpr int KR = Fit.reuse ? 0 : 1;                     // ρ, the constrained fit (a reuse keeps it)
  constexpr int KV = Fit.velocity ? Dim : 0;                // v
  constexpr int KS = Fit.stress ? sym_components<Dim> : 0;  // σ
  constexpr int KB = Fit.stress && Body::active ? Dim : 0;  // ρb
  constexpr int KF = KV + KS + KB;                          // the unconstrained fits
  constexpr int K = KR + KF;
  static_assert(KF > 0, "a TLS rebuild fits the velocity or the stress");
  static_assert(!Fit.reuse || (Fit.velocity && !Fit.stress), "a reuse refits the velocity alone");
  constexpr std::size_t enough_points = static_cast<std::size_t>(taylor_size<Dim>(Degree)) + 1;
  using Sums = detail::TlsCellSums<Dim, Degree, K, KF>;
  using Values = Eigen::Matrix<double, K, 1>;  // what a particle gives: ρ | v | σ | ρb
  using FitValues = Eigen::Matrix<double, KF, 1>;
  using FitSystem = detail::TaylorNormalSystem<Dim, Degree, KF>;
  std::size_t ncells = 1;
  for (int d = 0; d < Dim; ++d) ncells *= cells_[d];
  // Σ m v, Σ m |v| per block of `layout` (written when Fit.velocity): summed serially at the end, a total per
  // cell was 1.4 % of a 2×2 TLS step
  std::vector<MomentumTotals<Dim>>& totals = scratch<MomentumTotals<Dim>>(layout.blocks());
  if constexpr (Fit.velocity) std::fill(totals.begin(), totals.end(), MomentumTotals<Dim>{});
  // Fallbacks are counted per thread (integers: the same sum for any partition), and a fit without one costs a
  // comparison: a count per cell was written by every cell and summed serially.
  tbb::enumerable_thread_specific<FallbackCounts> counts;
  auto count = [&](const FitStatus& status) {
    if (status.stage != FitStage::full) counts.local().add(status);
  };
  // What the neighbourhood fits read of a cell, kept by passes 1 and 1b for the cells whose sums they read: the
  // normal sums of the unconstrained fields, and the bounds and momentum. Not pass 1's whole record (box, frame,
  // the density's sums too: 416 bytes for the stress fits of 2D), which with 2×2 particles per cell, every cell
  // near a sparse one, was written for every cell and read back four times, and the neighbourhood passes waited
  // on those loads.
  std::vector<FitSystem>& near = scratch<FitSystem>(ncells);
  std::vector<detail::TlsFitBounds<Dim, KF>>& bounds = scratch<detail::TlsFitBounds<Dim, KF>>(ncells);
  // The unconstrained fields of a cell and its two neighbours along axis 0, in the cell's frame: the first half of
  // a separable 3×3 (1D: 3) neighbourhood sum, summed only where a neighbourhood fit needs it. (A type of its own:
  // the scratch is one store per type.)
  struct RowSums : FitSystem {};
  std::vector<RowSums>& rows = scratch<RowSums>(ncells);
  std::vector<detail::TlsKeptFit<Dim, Degree>>& kept = scratch<detail::TlsKeptFit<Dim, Degree>>(ncells);
  std::vector<detail::TlsKeptMatrices<Dim, Degree>>& kept_matrices =
      scratch<detail::TlsKeptMatrices<Dim, Degree>>(ncells);
  std::vector<std::uint8_t>& needs_neighbours = scratch<std::uint8_t>(ncells);  // the cell's own particles did not do
  if (!Fit.reuse) tls_kept_ = false;  // until this rebuild completes
  const unsigned* order = cells.order().data();
  Extent1d extent{-1e300, 1e300};
  if constexpr (Dim == 1) extent = body_extent_1d(p, cells.order().size());
  // In 1D the TLS cell is the occupied part of the cell (see the top of this file).
  auto tls_box = [&](std::size_t c) {
    CellBox<Dim> box = cell_box(c);
    if constexpr (Dim == 1)
      if (std::max(box.lo[0], extent.lo) < std::min(box.hi[0], extent.hi)) {
        box.lo[0] = std::max(box.lo[0], extent.lo);
        box.hi[0] = std::min(box.hi[0], extent.hi);
      }
    return box;
  };
  // the per-cell scratch is indexed by slot (see slot())
  auto keep_sums = [&](std::size_t s, const Sums& cs) {
    near[s] = cs.template fields<KR, KF>();
    bounds[s] = cs.bounds();
    if constexpr (Fit.reuse) near[s].D = kept_matrices[s].own_D;  // a reuse sums no D (add_samples<false>)
    else kept_matrices[s].own_D = cs.sys.D;
  };
  // The Gauss points sit at the same place of every TLS cell (1D: of its occupied part): ξ = 2 local − 1.
  std::array<TaylorVector<Dim, Degree>, max_per_cell> psi_buffer;
  for (int g = 0; g < per_cell_; ++g) {
    Vec<Dim> xi;
    for (int d = 0; d < Dim; ++d) xi[d] = 2.0 * local_[g][d] - 1.0;
    psi_buffer[g] = taylor_basis_ref<Dim, Degree>(xi);
  }
  const std::span<const TaylorVector<Dim, Degree>> psi(psi_buffer.data(), per_cell_);

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
  constexpr double own_fit_pivot = 1e-3;
  TlsOptions opt;
  opt.rank_threshold = own_fit_pivot;

  // The limiter and the Gauss-point values of a cell's unconstrained fit.
  auto write_fit = [&](std::size_t c, const CellBox<Dim>& box, const detail::TlsFitBounds<Dim, KF>& cb,
                       const TaylorFit<Dim, Degree, KF>& fit) {
    const std::size_t first = first_point(c);
    const double volume = box.volume();
    std::array<FitValues, max_per_cell> values;
    detail::limited_values(fit, cb.lo, cb.hi, psi, values.data());
    // Momentum as ρ̂ v̂, not a fit of ρv (beyond the thesis, which fits ρv, eq. 5.9): v̂ is bounded by the cell's
    // particle velocities, so a nodal velocity Σφρ̂v̂ω / Σφρ̂ω is a weighted mean of bounded values even where the
    // nodal mass is tiny. Fitting ρ and ρv apart let their ratio run away at such nodes (v ≈ 2e4 m/s on the
    // 64² plate with 2×2 particles per cell). The mean of v̂ is shifted so that Σ_g ρ̂v̂ω = Σ m_p v_p exactly.
    if constexpr (Fit.velocity) {
      double m_g = 0.0;
      Eigen::Matrix<double, Dim, 1> q_g = Eigen::Matrix<double, Dim, 1>::Zero();
      for (int g = 0; g < per_cell_; ++g) {
        m_g += m_[first + g];
        q_g += m_[first + g] * values[g].template head<Dim>();
      }
      const Eigen::Matrix<double, Dim, 1> shift = (cb.momentum - q_g) / m_g;
      for (int g = 0; g < per_cell_; ++g)
        for (int d = 0; d < Dim; ++d) q_[d][first + g] = m_[first + g] * (values[g][d] + shift[d]);
    }
    if constexpr (Fit.stress)
      for (int g = 0; g < per_cell_; ++g) {
        const double w = local_w_[g] * volume;
        for (int k = 0; k < KS; ++k) s_[k][first + g] = w * values[g][KV + k];
        for (int d = 0; d < KB; ++d) fb_[d][first + g] = w * values[g][KV + KS + d];
      }
  };

  // The sums of a cell's own particles (positions, ρ, v, σ, ρb as `Fit` names them) and its bounds, mass and
  // momentum, in its Taylor frame; `total`: Σ m v (the momentum constraint) and Σ m |v|. The view is captured by
  // value: through the reference GCC reloaded every column pointer after each store to the sums.
  auto sum_cell = [&, p = p](std::size_t c, MomentumTotals<Dim>& total) {
    const auto range = cells.block_range(c);  // (clang 14 cannot capture structured bindings)
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
  };
  // Whose sums passes 2 and 3 read: the cells within one cell of a cell with particles too few for its own fit,
  // which the bins' counts tell before any particle is read. Every other cell keeps its sums in pass 1's locals:
  // written to the scratch and read back, that record of ≈ 70 doubles was the pass's largest memory traffic. A
  // cell with enough particles whose own fit fails on its conditioning alone (rare) has its neighbours' sums
  // taken in pass 1b.
  // Which cells are sparse is taken from the bins' counts once, into a byte per cell in row-major order: looked up
  // through the bins (rank, then block start) for the nine cells around every cell, in pass 1's block order,
  // those dependent loads were a quarter of pass 1 with 2×2 particles per cell.
  struct Sparse {
    bool value;
  };
  // A reuse reads what the rebuild before it found (TlsKeptFit::near_sparse): the same particles in the same cells.
  std::vector<Sparse>& sparse = scratch<Sparse>(ncells);
  if constexpr (!Fit.reuse)
    for_each_cell(ncells, [&](std::size_t c) {
      const auto range = cells.block_range(c);
      const std::size_t n = range.second - range.first;
      sparse[c].value = n > 0 && n < enough_points;
    });
  auto near_sparse = [&](std::size_t c) {
    if constexpr (Fit.reuse) return kept[slot(c)].near_sparse;
    bool any = false;
    for_each_cell_near(c, 1, [&](std::size_t n) { any |= sparse[n].value; });
    return any;
  };
  std::atomic<bool> conditioning_failed{false};  // pass 1b is needed

  // Pass 1: each particle is read once, into the sums of its cell, and the cell fits what its own particles
  // determine; the cells in the order of `layout`'s blocks, which the particle columns follow (a row-major sweep
  // jumped between the colour classes of the blocks).
  layout.for_each_cell_by_block([&](std::size_t block, std::size_t c) {
    const std::size_t s = slot(c);
    MomentumTotals<Dim> total;
    const Sums cs = sum_cell(c, total);
    if constexpr (Fit.velocity) totals[block].add(total);
    needs_neighbours[s] = 0;
    const bool keep = near_sparse(c);
    if constexpr (!Fit.reuse) kept[s].near_sparse = keep;
    if (keep) keep_sums(s, cs);
    const std::size_t first = first_point(c);
    if (cs.sys.points == 0) {  // an empty cell carries nothing: nothing to conserve there
      for (int g = 0; g < per_cell_; ++g) clear_point(first + g);
      return;
    }
    const CellBox<Dim>& box = cs.box;
    const double volume = box.volume();

    // The density fit uses the cell's own particles only: completing it from the neighbouring cells (thesis
    // §5.2.3) was measured to bias the slopes of compressed cells (plate, A = 0.1: 64-cell error 2.4x larger);
    // a cell its own particles do not determine drops to a lower degree instead, conservative all the same.
    // The cell's mass Σ m_p fixes the first Taylor coefficient of ρ (thesis eq. 5.9).
    // A reuse keeps the density at the Gauss points (m_): the particles it came from are unchanged.
    if constexpr (!Fit.reuse) {
      if constexpr (Dim == 1) {  // the occupied part of the cell: its Gauss points move there
        const CellBox<Dim> whole = cell_box(c);
        double w[16];            // ≤ 10 points per cell (scene range of gauss_per_cell)
        place_clipped(first, cell_rule_, whole.lo[0], whole.hi[0], extent.lo, extent.hi, w);
      }
      auto rho_sys = cs.template fields<0, 1>();
      rho_sys.reshift(Eigen::Matrix<double, 1, 1>(cs.mass / volume));
      const auto rho_fit =
          detail::complete_fit<Degree>(box, rho_sys, true, [](auto&) { return false; }, TlsOptions{});
      kept[s].rho = rho_fit.status;
      std::array<Eigen::Matrix<double, 1, 1>, max_per_cell> rho;
      detail::limited_values(rho_fit, cs.lo.template head<1>().eval(), cs.hi.template head<1>().eval(), psi,
                             rho.data());
      for (int g = 0; g < per_cell_; ++g) m_[first + g] = local_w_[g] * volume * rho[g][0];
    }
    count(kept[s].rho);

    // the own fit as detail::own_fit would make it, through factors a reuse keeps
    detail::TlsKeptFit<Dim, Degree>& k = kept[s];
    if constexpr (!Fit.reuse)
      k.own_fitted = cs.sys.points >= enough_points && k.own_factors.factor(cs.sys.D, own_fit_pivot);
    if (k.own_fitted) {
      TaylorFit<Dim, Degree, KF> fit;
      detail::fit_with(box, k.own_factors, cs.sys.b.template middleCols<KF>(KR), cs.sys.shift.template segment<KF>(KR),
                       cs.sys.points, fit);
      write_fit(c, box, cs.bounds(), fit);
      return;
    }
    needs_neighbours[s] = 1;
    if (keep) return;
    keep_sums(s, cs);
    conditioning_failed.store(true, std::memory_order_relaxed);
  });

  // Pass 1b: the sums of the neighbours of cells whose own fit failed on its conditioning, where pass 1 did not
  // keep them.
  if (conditioning_failed.load())
    for_each_cell(ncells, [&](std::size_t s) {
      const std::size_t c = cell_of_slot_[s];
      if (needs_neighbours[s] || near_sparse(c)) return;  // kept in pass 1
      bool needed = false;
      for_each_cell_near(c, 1, [&](std::size_t n) { needed = needed || needs_neighbours[slot(n)]; });
      MomentumTotals<Dim> unused;
      if (needed) keep_sums(s, sum_cell(c, unused));
    });

  // Pass 2: row sums, where a neighbourhood fit of pass 3 needs them (a cell without particles may still join
  // its neighbours' sums). The neighbourhood fits move the sums of the neighbouring cells into their own frame
  // (TaylorChange) instead of revisiting those cells' particles, separably: pass 2 sums each cell's row of three
  // along axis 0, pass 3 the rows of three along axis 1, four one-axis moves per cell instead of eight general
  // ones. With 2×2 particles per cell, where every velocity and stress fit needs the 3×3 neighbourhood, this and
  // the fixed-size solve cut the two rebuilds of a MUSL step from 5570 to 2400 instructions per particle
  // (callgrind; docs/RECONSTRUCTION.md). Neighbours weigh as much as own particles here
  // (TlsOptions::neighbour_weight = 1, the thesis' choice): a separable sum cannot weigh them apart.
  auto row_needed = [&](std::size_t c) {
    bool needed = needs_neighbours[slot(c)];
    if constexpr (Dim == 2)
      for_each_neighbour_along(c, 1, [&](std::size_t n) { needed |= needs_neighbours[slot(n)]; });
    return needed;
  };
  for_each_cell(ncells, [&](std::size_t s) {
    const std::size_t c = cell_of_slot_[s];
    if (!row_needed(c)) return;
    FitSystem& row = rows[s];
    row = near[s];
    const TaylorFrame<Dim> frame(tls_box(c));
    for_each_neighbour_along(c, 0, [&](std::size_t n) {
      const FitSystem& ns = near[slot(n)];
      const TaylorChange<Dim, Degree, 1u> change(TaylorFrame<Dim>(tls_box(n)), frame);
      // a reuse moves only the right-hand sides and Σ w ψ (D's first column), which pass 3 moves on
      if constexpr (Fit.reuse)
        row.template add_moved_rhs<true>(ns.D.col(0), ns.b, ns.shift, ns.points, change, 1.0);
      else
        row.add_moved(ns, change, 1.0);
    });
  });

  // Pass 3: the neighbourhood fits of the cells whose own particles did not determine theirs.
  for_each_cell(ncells, [&](std::size_t s) {
    if (!needs_neighbours[s]) return;
    const std::size_t c = cell_of_slot_[s];
    const CellBox<Dim> box = tls_box(c);
    const TaylorFrame<Dim> frame(box);
    const FitSystem& own = near[s];
    auto add_neighbours = [&](FitSystem& sys) {  // own + neighbours: the rows above and below moved to this one
      sys = rows[s];
      if constexpr (Dim == 2)
        for_each_neighbour_along(c, 1, [&](std::size_t n) {
          const TaylorChange<Dim, Degree, 2u> change(TaylorFrame<Dim>(tls_box(n)), frame);
          const FitSystem& row = rows[slot(n)];
          if constexpr (Fit.reuse) sys.add_moved_rhs(row.D.col(0), row.b, row.shift, row.points, change, 1.0);
          else sys.add_moved(row, change, 1.0);
        });
      if constexpr (Fit.reuse) sys.D = kept_matrices[s].neighbourhood_D;  // the same positions: the same matrix
      else kept_matrices[s].neighbourhood_D = sys.D;
      return sys.points > own.points;
    };
    const bool enough = own.points >= enough_points;
    FitSystem fit_sys;
    if (enough) fit_sys = own;
    else add_neighbours(fit_sys);
    auto fit = detail::complete_fit<Degree>(box, fit_sys, false,
                                            [&](auto& sys) { return enough && add_neighbours(sys); }, opt);
    if (!enough && fit.status.stage == FitStage::full) fit.status.stage = FitStage::neighbour;
    count(fit.status);
    write_fit(c, box, bounds[s], fit);
  });
  for (const auto& c : counts) fallbacks_ += c;
  tls_kept_ = true;
  if constexpr (!Fit.velocity) return MomentumTotals<Dim>{};
  return sum_totals(totals);
}

template <int Dim>
template <class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild_mls(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                                  const Body& body, bool stress) {
  constexpr int KM = 1 + Dim, KS = sym_components<Dim> + Dim;
  const ParticleFields<Dim, Body> fields{&p, &body};
  std::size_t ncells = 1;
  for (int d = 0; d < Dim; ++d) ncells *= cells_[d];
  const std::size_t np = cells.order().size();
  std::vector<MomentumTotals<Dim>> totals(ncells);
  std::vector<FallbackCounts> counts(ncells);
  const unsigned* order = cells.order().data();
  const int reach = static_cast<int>(std::ceil(1.5 * mls_support_));  // cells within the weight's support
  const MlsOptions opt{mls_support_};
  Vec<Dim> h;
  for (int d = 0; d < Dim; ++d) h[d] = h_[d];

  // K fields per particle: ρ, ρv, and σ, ρb when the stress is fitted.
  auto fit = [&]<int K>() {
    // Each particle's fields once per rebuild: the sums below visit a particle once for every Gauss point of the
    // cells around it (4 × 49 times with 2×2 Gauss points and the printed support), and computing its fields at
    // each visit (a determinant, a division, the plate's body force with its sines and cosines) was most of
    // the time of an MLS step.
    using Values = Eigen::Matrix<double, K, 1>;
    std::vector<Values>& values = scratch<Values>(np);
    parallel_over(np, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t ip = b; ip < e; ++ip) {
        values[ip].template head<KM>() = fields.mass(ip);
        if constexpr (K > KM) values[ip].template tail<KS>() = fields.stress(ip);
      }
    });
    auto value_of = [&](std::size_t ip) -> const Values& { return values[ip]; };
    for_each_cell(ncells, [&](std::size_t c) {
      const auto own_range = cells.block_range(c);
      const std::size_t first = first_point(c);
      for (int g = 0; g < per_cell_; ++g) clear_point(first + g);
      if (own_range.first == own_range.second) return;
      for (std::size_t k = own_range.first; k < own_range.second; ++k) {
        const std::size_t ip = order[k];
        double v[Dim];
        for (int d = 0; d < Dim; ++d) v[d] = p.v[d][ip];
        totals[c].add(p.m[ip], v);
      }
      detail::ParticleRanges<Dim, K, decltype(value_of)> src{&p, order, value_of};
      for_each_cell_near(c, reach, [&](std::size_t n) { src.add(cells.block_range(n)); });
      const double volume = cell_box(c).volume();
      for (int g = 0; g < per_cell_; ++g) {
        Vec<Dim> xg;
        for (int d = 0; d < Dim; ++d) xg[d] = x_[d][first + g];
        const double w = local_w_[g] * volume;
        // One moment matrix A for all fields (paper eq. 10 depends on the positions and weights only): the mass
        // and the stress fits share it, so they are one solve with K right-hand sides and the same outcome.
        const auto val = mls_value(xg, h, src, opt);  // paper eq. 13
        counts[c].add(val.status);
        m_[first + g] = w * val.value[0];
        for (int d = 0; d < Dim; ++d) q_[d][first + g] = w * val.value[1 + d];
        if constexpr (K > KM) {
          counts[c].add(val.status);  // the stress fit, counted as it was when it had a solve of its own
          for (int k = 0; k < sym_components<Dim>; ++k) s_[k][first + g] = w * val.value[KM + k];
          for (int d = 0; d < Dim; ++d) fb_[d][first + g] = w * val.value[KM + sym_components<Dim> + d];
        }
      }
    });
  };
  if (stress) fit.template operator()<KM + KS>();
  else fit.template operator()<KM>();
  for (const auto& c : counts) fallbacks_ += c;
  return sum_totals(totals);
}

template <int Dim>
template <class Body>
MomentumTotals<Dim> GaussPoints<Dim>::rebuild_cubic_spline(const ParticleView<Dim>& p, const CellBins<Dim>& cells,
                                                           const Body& body, bool stress) {
  if constexpr (Dim != 1) {
    throw std::logic_error("GaussPoints: the cubic-spline mapping is 1D only (the scene refuses it in 2D)");
  } else {
    const MomentumTotals<Dim> totals = sort_by_position(p, cells);
    const ParticleFields<Dim, Body> fields{&p, &body};
    // Particles closer than this are one data point (kernels/cubic_spline.hpp): far below any spacing a run
    // survives, far above the round-off of positions.
    const double merge = 1e-10 * h_[0];
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
    if (mass_spline_.size() < 2) ++fallbacks_.constant;
    // The body's current extent: the end particles' domains, x_p ∓ V_p/2, reach the body's ends, and the
    // spline is extrapolated there (thesis Fig. 3.3); outside it no Gauss point carries anything.
    const Extent1d extent = body_extent_1d(p, sorted_.size());
    const double lo = extent.lo, hi = extent.hi;  // (clang 14 cannot capture structured bindings)
    const int n = static_cast<int>(half_rule_.x.size());
    for_each_cell(static_cast<std::size_t>(cells_[0]), [&](std::size_t c) {
      for (int half = 0; half < 2; ++half) {
        double w[16];  // ≤ 10 points per half (scene range of gauss_per_cell)
        place_half_span(c, half, lo, hi, w);
        for (int j = 0; j < n; ++j) {
          const std::size_t g = first_point(c) + half * n + j;
          clear_point(g);
          if (w[j] == 0.0) continue;
          // ρ̂ω and ρv̂ω (thesis eqs 3.8–3.9), σ̂ω and ρb̂ω (eq. 3.7)
          const auto mv = mass_spline_(x_[0][g]);
          m_[g] = w[j] * mv[0];
          q_[0][g] = w[j] * mv[1];
          if (!stress) continue;
          const auto sv = stress_spline_(x_[0][g]);
          s_[0][g] = w[j] * sv[0];
          fb_[0][g] = w[j] * sv[1];
        }
      }
    });
    return totals;
  }
}

}  // namespace mpm
