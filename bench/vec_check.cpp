// Not a benchmark: a small translation unit for the vectorisation check in docs/PERFORMANCE.md.
//   cmake --build build-bench --target bench_vec_report
// compiles it with g++ -O3 -fopt-info-vec-optimized (baseline x86-64 and -march=native) and prints which loops
// the compiler vectorised. Each function isolates one way the fast-path weights are used.
#include <cstddef>

#include "kernels/bspline.hpp"
#include "kernels/stencil.hpp"

namespace vec_check {

/// (1) One point, as the transfer kernels call it: the k-loop over the 3 functions (SLP inside one point).
void one_point(const mpm::UniformAxis<3>& axis, double x, mpm::AxisWeights<3>* out) { *out = axis(x); }

/// (2) Many points into SoA outputs: can the compiler vectorise across particles (loop vectoriser)?
void many_points(const mpm::UniformAxis<3>& axis, const double* __restrict x, std::size_t n, int* __restrict first,
                 double* __restrict w0, double* __restrict w1, double* __restrict w2, double* __restrict d0,
                 double* __restrict d1, double* __restrict d2) {
  for (std::size_t p = 0; p < n; ++p) {
    const auto a = axis(x[p]);
    first[p] = a.first;
    w0[p] = a.w[0];
    w1[p] = a.w[1];
    w2[p] = a.w[2];
    d0[p] = a.dw[0];
    d1[p] = a.dw[1];
    d2[p] = a.dw[2];
  }
}

/// (3) The 2D tensor product of one point: 9 values and 18 gradient components (for_each_node).
void tensor_2d(const mpm::TensorBasis<2, mpm::UniformAxis<3>>& basis, const double* xp, double* __restrict w,
               double* __restrict gx, double* __restrict gy) {
  const auto st = mpm::stencil_at<2, 3>(basis, xp);
  int k = 0;
  mpm::for_each_node(st, basis.functions[0], [&](int, double wi, const std::array<double, 2>& g) {
    w[k] = wi;
    gx[k] = g[0];
    gy[k] = g[1];
    ++k;
  });
}

}  // namespace vec_check
