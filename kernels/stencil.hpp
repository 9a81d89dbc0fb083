#pragma once
// Tensor-product stencils: the S^Dim basis functions non-zero at a point, with their gradients.
// Keeps the index arithmetic out of the transfer kernels, which then read like the paper's sums.
#include <array>

#include "kernels/bspline.hpp"

namespace mpm {

/// A basis on a Dim-dimensional grid: one axis basis per axis (UniformAxis or CoxDeBoorAxis), all of width S.
template <int Dim, class Axis>
struct TensorBasis {
  using axis_type = Axis;
  static constexpr int width = Axis::width;  ///< functions per axis non-zero at a point
  std::array<Axis, Dim> axis;
  std::array<int, Dim> functions;  ///< number of basis functions per axis (DOFs = product)
};

/// The stencil of one point: per axis the first function index, values and derivatives.
template <int Dim, int S>
struct Stencil {
  std::array<AxisWeights<S>, Dim> a;
};

template <int Dim, int S, class Axis>
inline Stencil<Dim, S> stencil_at(const TensorBasis<Dim, Axis>& basis, const double* x) {
  Stencil<Dim, S> st;
  for (int d = 0; d < Dim; ++d) st.a[d] = basis.axis[d](x[d]);
  return st;
}

/// Calls f(dof, weight, gradient) for every DOF of the stencil, in a fixed order (axis 0 fastest).
/// `stride1` is the number of functions along axis 0 (DOF = i0 + stride1 * i1).
template <int Dim, int S, class F>
inline void for_each_node(const Stencil<Dim, S>& st, int stride1, F&& f) {
  if constexpr (Dim == 1) {
    const auto& a = st.a[0];
    for (int i = 0; i < S; ++i) f(a.first + i, a.w[i], std::array<double, 1>{a.dw[i]});
  } else {
    static_assert(Dim == 2, "dimension 1 or 2");
    const auto& a = st.a[0];
    const auto& b = st.a[1];
    for (int j = 0; j < S; ++j) {
      const int row = (b.first + j) * stride1 + a.first;
      for (int i = 0; i < S; ++i)
        f(row + i, a.w[i] * b.w[j], std::array<double, 2>{a.dw[i] * b.w[j], a.w[i] * b.dw[j]});
    }
  }
}

}  // namespace mpm
