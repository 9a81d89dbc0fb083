#pragma once
// Moving least squares (MLS) with a linear basis, paper eqs 6–17 (Tran et al. 2019): at an evaluation point x
// (a Gauss point), the K fields are the value at x of the weighted least-squares plane through the samples,
//   u_h(x) = p(x)ᵀ A(x)⁻¹ B(x) U,  A = Σ_p w(x − x_p) p(x_p) p(x_p)ᵀ,  B U = Σ_p w(x − x_p) p(x_p) u_p,
// (eqs 9–13) with p = [1, x(, y)] (eq. 15) and the tensor-product quadratic-spline weight (eqs 16–17).
//
// The basis is shifted to x and scaled by the kernel width, p̃(x_p) = [1, (x_p − x)/(support h)], which spans
// the same space (so the value is the same) but keeps A well conditioned on any grid; then p̃(x) = e_1 and the
// value is the first row of A⁻¹ B U. A singular A (fewer than Dim+1 samples in the support, or all of them on a
// line) is detected by the pivoted factorisation and the value falls back to the Shepard estimate Σ w u / Σ w
// (degree 0), counted as FitStage::constant; no sample in the support gives zero, counted as FitStage::empty.
//
// Structure worth knowing (Tesserae.jl, wls.jl): for a B-spline weight whose support is fully covered by
// uniformly spaced particles, A is the same constant matrix at every x (diagonal, since the weight is even), so
// the solve can be skipped in the interior. Not exploited here: particles move, and the general solve is cheap.
#include <cmath>
#include <cstddef>

#include "kernels/reconstruction.hpp"

namespace mpm {

/// Quadratic spline of paper eq. 17, w(r) = 3/4 − r² (|r| ≤ 1/2), ½(3/2 − |r|)² (1/2 ≤ |r| ≤ 3/2), 0 beyond;
/// eq. 17 prints r where |r| is meant. It is the uniform quadratic B-spline: support |r| < 3/2, integral 1.
inline double quadratic_spline_weight(double r) {
  const double a = std::abs(r);
  if (a <= 0.5) return 0.75 - a * a;
  if (a < 1.5) return 0.5 * (1.5 - a) * (1.5 - a);
  return 0.0;
}

struct MlsOptions {
  /// r = (x − x_p) / (support · h) per axis; the paper prints support = 2 (eq. 16 text), i.e. weights non-zero
  /// for |x − x_p| < 3h. support = 1 gives ±1.5h.
  double support = 2.0;
  /// Relative pivot threshold of the rank test on the equilibrated moment matrix.
  double rank_threshold = 1e-10;
};

template <int K>
struct MlsValue {
  Eigen::Matrix<double, K, 1> value = Eigen::Matrix<double, K, 1>::Zero();
  FitStatus status;
};

/// MLS value of the K fields of `samples` at x (paper eq. 13), h the cell size per axis. The samples' weight()
/// multiplies the kernel weight (1 in the paper). Pass every sample that may lie in the support (|x − x_p| <
/// 1.5 · support · h per axis); samples outside get weight 0 and are skipped.
template <SampleSource S>
inline MlsValue<S::fields> mls_value(const Vec<S::dim>& x, const Vec<S::dim>& h, const S& samples,
                                     const MlsOptions& opt = {}) {
  constexpr int Dim = S::dim;
  constexpr int K = S::fields;
  constexpr int N = Dim + 1;  // p = [1, x(, y)], eq. 15
  const Vec<Dim> inv_width = (opt.support * h).cwiseInverse();
  Eigen::Matrix<double, N, N> A = Eigen::Matrix<double, N, N>::Zero();  // eq. 10
  Eigen::Matrix<double, N, K> BU = Eigen::Matrix<double, N, K>::Zero(); // eqs 11–12: B U
  std::size_t points = 0;
  samples.for_each([&](const Vec<Dim>& xp, const Eigen::Matrix<double, K, 1>& u, double weight) {
    const Vec<Dim> r = (x - xp).cwiseProduct(inv_width);         // eq. 16 text
    double w = weight;
    for (int d = 0; d < Dim; ++d) w *= quadratic_spline_weight(r[d]);  // eq. 16
    if (w == 0.0) return;
    Eigen::Matrix<double, N, 1> p;
    p[0] = 1.0;
    p.template tail<Dim>() = -r;  // p̃(x_p) = [1, (x_p − x)/(support h)]
    A.noalias() += (w * p) * p.transpose();
    BU.noalias() += (w * p) * u.transpose();
    ++points;
  });
  MlsValue<K> out;
  out.status.points = points;
  Eigen::Matrix<double, N, K> a;
  if (detail::solve_full_rank<N, K>(A, BU, opt.rank_threshold, a)) {  // eq. 9
    out.value = a.row(0).transpose();                                   // eq. 13 with p̃(x) = e_1
    out.status.stage = FitStage::full;
    out.status.degree = 1;
  } else if (A(0, 0) > 0.0) {
    out.value = BU.row(0).transpose() / A(0, 0);  // Shepard: Σ w u / Σ w
    out.status.stage = FitStage::constant;
  } else {
    out.status.stage = FitStage::empty;
  }
  return out;
}

}  // namespace mpm
