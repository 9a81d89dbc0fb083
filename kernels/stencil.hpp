#pragma once
// Tensor-product stencils: the S^Dim basis functions non-zero at a point, with their gradients.
// Keeps the index arithmetic out of the transfer kernels, which then read like the paper's sums.
//
// A stencil is a set of rows along axis 0 (one row in 1D, S rows in 2D). A row's axis-0 weights are padded with
// zeros to `stencil_lanes<S>` (a whole number of SIMD registers: 3 → 4) and held as one SIMD vector
// (std::experimental::simd, GCC's Parallelism TS v2: two SSE2 registers in a portable build, one AVX register with
// MPM_NATIVE), so the hot kernels handle a row of contiguous DOFs in a few vector instructions. The compiler does
// not find this by itself: it unrolls the 3-node loops and packs them poorly (measured 1.4× slower scatter). The padding lane adds 0.0 to the DOF just
// past the stencil: the grid reserves ghost columns for it (grid_stride) and the coloured blocks are wide enough
// that it never belongs to a block of the same colour (cell_bins.hpp), so no scatter races on it.
#include <array>
#include <cstddef>
#include <experimental/simd>
#include <type_traits>

#include "kernels/bspline.hpp"

#define MPM_INLINE [[gnu::always_inline]] inline
// The same for the row lambdas the kernels pass to for_each_row: without it, one more level of calls (scatter_p2g →
// scatter_rows → for_each_row → lambda) was enough for GCC to leave the lambda and the SIMD operators in it out of
// line — 1747 instead of 1253 instructions per 2D USL particle-step (callgrind).
#define MPM_INLINE_LAMBDA __attribute__((always_inline))

namespace mpm {

/// DOFs per stencil row in the kernels' inner loops: the stencil width rounded up to an even count.
constexpr int stencil_reach(int width) { return width + width % 2; }
template <int S>
inline constexpr int stencil_lanes = stencil_reach(S);

/// Functions per grid row in memory: the functions along axis 0 plus the ghost columns of the padding lanes of a
/// stencil `width` functions wide.
constexpr int grid_stride(int functions0, int width) { return functions0 + width % 2; }

/// One stencil row of weights or grid values, a SIMD vector of stencil_lanes<S> doubles.
/// The ABI is the target's native vector of that width where there is one (AVX: one __m256d), else fixed_size:
/// with fixed_size on an AVX target GCC passed the stencil's rows through the stack and general registers.
template <int S>
using RowVector = std::experimental::simd<double, std::experimental::simd_abi::deduce_t<double, stencil_lanes<S>>>;

/// The row of grid values starting at p (any alignment).
template <class V>
MPM_INLINE V load_row(const double* p) {
  return V(p, std::experimental::element_aligned);
}

/// p[0..lanes) += x.
template <class V>
MPM_INLINE void add_to_row(double* p, const V& x) {
  V y = load_row<V>(p);
  y += x;
  y.copy_to(p, std::experimental::element_aligned);
}

/// A basis on a Dim-dimensional grid: one axis basis per axis (UniformAxis or CoxDeBoorAxis), all of width S.
template <int Dim, class Axis>
struct TensorBasis {
  using axis_type = Axis;
  static constexpr int width = Axis::width;  ///< functions per axis non-zero at a point
  std::array<Axis, Dim> axis;
  std::array<int, Dim> functions;  ///< number of basis functions per axis (DOFs = product)
};

/// The stencil of one point: the DOF of its first node, the padded axis-0 weights and the axis-1 weights.
template <int Dim, int S>
struct Stencil {
  int first0 = 0, first1 = 0;                       ///< first function index per axis
  RowVector<S> wx, dwx;                              ///< axis 0: φ and dφ/dx, zero in the padding lanes
  double wy[stencil_lanes<S>], dwy[stencil_lanes<S>];  ///< axis 1 (2D only; the first S are the functions)
};

/// The functions of one axis non-zero at a point, as padded SIMD rows (zero in the padding lanes).
template <int S>
struct AxisRow {
  int first;           ///< index of the first function
  RowVector<S> w, dw;  ///< φ and dφ/dx
};

namespace detail {
/// UniformAxis<S>::coefficients padded with zeros to stencil_lanes<S>: one SIMD load per power.
template <int S>
constexpr auto padded_uniform_coefficients() {
  constexpr auto& table = UniformAxis<S>::coefficients;
  std::array<std::array<std::array<double, stencil_lanes<S>>, 3>, table.size()> padded{};
  for (std::size_t c = 0; c < table.size(); ++c)
    for (int power = 0; power < 3; ++power)
      for (int k = 0; k < S; ++k) padded[c][power][k] = table[c][power][k];
  return padded;
}
template <int S>
inline constexpr auto padded_uniform = padded_uniform_coefficients<S>();
}  // namespace detail

/// The fast path evaluates its S polynomials as vectors, a + ξ (b + ξ c) and (b + 2ξ c)/h, in the lanes of a row
/// (the same arithmetic per function as UniformAxis::operator()); the generic path fills the lanes from its values.
/// The row of a point at local coordinate ξ in cell `cell` of span class `span_class` (UniformAxis::locate).
template <int S>
MPM_INLINE AxisRow<S> uniform_row(const UniformAxis<S>& axis, int cell, int span_class, double xi) {
  const auto& q = detail::padded_uniform<S>[span_class];
  const RowVector<S> a = load_row<RowVector<S>>(q[0].data()), b = load_row<RowVector<S>>(q[1].data()),
                     c = load_row<RowVector<S>>(q[2].data());
  return {cell, a + xi * (b + xi * c), (b + (2.0 * xi) * c) * axis.inv_h};
}

template <int S, class Axis>
MPM_INLINE AxisRow<S> axis_row(const Axis& axis, double x) {
  if constexpr (std::is_same_v<Axis, UniformAxis<S>>) {
    const auto at = axis.locate(x);
    return uniform_row<S>(axis, at.cell, at.span_class, at.xi);
  } else {
    const AxisWeights<S> a = axis(x);
    return {a.first, RowVector<S>([&](int i) { return i < S ? a.w[i] : 0.0; }),
            RowVector<S>([&](int i) { return i < S ? a.dw[i] : 0.0; })};
  }
}

template <int Dim, int S, class Axis>
MPM_INLINE Stencil<Dim, S> stencil_at(const TensorBasis<Dim, Axis>& basis, const double* x) {
  Stencil<Dim, S> st;
  const AxisRow<S> a = axis_row<S>(basis.axis[0], x[0]);
  st.first0 = a.first;
  st.wx = a.w;
  st.dwx = a.dw;
  if constexpr (Dim == 2) {
    const AxisRow<S> b = axis_row<S>(basis.axis[1], x[1]);
    st.first1 = b.first;
    b.w.copy_to(st.wy, std::experimental::element_aligned);
    b.dw.copy_to(st.dwy, std::experimental::element_aligned);
  }
  return st;
}

/// An axis whose particle stencils are evaluated once per step and read back by particle index, for a basis that
/// is costly to evaluate (max-ent: a Newton solve per point), which every transfer of a step would otherwise
/// evaluate again at the same positions (three times per MUSL step). Simulation::cache_stencils fills the cache
/// at the start of a step and empties it at the end; points of other columns (Gauss points, loads) are evaluated
/// by the axis itself.
template <class Axis>
struct StencilCached : Axis {
  using Axis::Axis;
  const double* cached_x0 = nullptr;  ///< the axis-0 column of the points the cache holds; null: no cache
  const void* stencils = nullptr;     ///< Stencil<Dim, width>[point], for the Dim of the basis
};

/// The stencil of point i of the position columns x (one pointer per axis): the prologue of every transfer.
template <int Dim, int S, class Axis, class Columns>
MPM_INLINE Stencil<Dim, S> stencil_of(const TensorBasis<Dim, Axis>& basis, const Columns& x, std::size_t i) {
  if constexpr (requires { basis.axis[0].stencils; })
    if (x[0] == basis.axis[0].cached_x0) return static_cast<const Stencil<Dim, S>*>(basis.axis[0].stencils)[i];
  double xi[Dim];
  for (int d = 0; d < Dim; ++d) xi[d] = x[d][i];
  return stencil_at<Dim, S>(basis, xi);
}

/// Calls f(dof, wy, dwy) for every row of the stencil: `dof` is the row's first DOF, (wy, dwy) the axis-1 factor
/// of its weights (1 and 0 in 1D). Node i of the row has weight wx[i]·wy and gradient (dwx[i]·wy, wx[i]·dwy).
/// `stride` is the grid's row length in memory (grid_stride).
template <int Dim, int S, class F>
MPM_INLINE void for_each_row(const Stencil<Dim, S>& st, int stride, F&& f) {
  if constexpr (Dim == 1) {
    f(st.first0, 1.0, 0.0);
  } else {
    static_assert(Dim == 2, "dimension 1 or 2");
    for (int j = 0; j < S; ++j) f((st.first1 + j) * stride + st.first0, st.wy[j], st.dwy[j]);
  }
}

/// Calls f(dof, weight, gradient) for every node of the stencil (no padding), in a fixed order (axis 0 fastest).
template <int Dim, int S, class F>
MPM_INLINE void for_each_node(const Stencil<Dim, S>& st, int stride, F&& f) {
  for_each_row(st, stride, [&](int row, double wy, double dwy) MPM_INLINE_LAMBDA {
    for (int i = 0; i < S; ++i) {
      if constexpr (Dim == 1) f(row + i, st.wx[i], std::array<double, 1>{st.dwx[i]});
      else f(row + i, st.wx[i] * wy, std::array<double, 2>{st.dwx[i] * wy, st.wx[i] * dwy});
    }
  });
}

}  // namespace mpm
