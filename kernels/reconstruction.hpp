#pragma once
// Shared pieces of the per-cell least-squares reconstructions (TLS: kernels/taylor_ls.hpp, thesis §5.2, §6.1;
// MLS: kernels/mls.hpp, paper eqs 6–17): how scattered samples (particles) are read, the rank-revealing solve of
// a small normal system, and the record of which fallback a solve needed.
//
// Everything is fixed-size (Eigen::Matrix<double, N, M> with N, M known at compile time): no allocation.
#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>

namespace mpm {

template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;

/// An axis-aligned cell [lo, hi] (a knot span of the grid).
template <int Dim>
struct CellBox {
  Vec<Dim> lo = Vec<Dim>::Zero(), hi = Vec<Dim>::Zero();
  Vec<Dim> centre() const { return 0.5 * (lo + hi); }
  Vec<Dim> half_width() const { return 0.5 * (hi - lo); }  ///< Δx_k of thesis §5.2.2 / §6.1.1
  double volume() const { return (hi - lo).prod(); }      ///< |Ω_e|, thesis eq. 6.7
};

/// Scattered samples as a reconstruction reads them: size() and a visit of every sample in a fixed order,
/// f(position, values, weight), with K = S::fields values and a least-squares weight (1 for the thesis' and the
/// paper's unweighted sums). A visitor, not random access, so that a source can be several ranges of a
/// cell-sorted particle order (a cell and its neighbours) and compute values on the fly, e.g.
///
///   struct CellParticles {                      // ρ, ρv_x, ρv_y of the particles order[b..e) in 2D
///     static constexpr int dim = 2, fields = 3;
///     std::size_t size() const { return e - b; }
///     template <class F> void for_each(F&& f) const {
///       for (auto k = b; k < e; ++k) { auto p = order[k]; double rho = m[p] / V[p];
///         f(Vec<2>(x0[p], x1[p]), Eigen::Vector3d(rho, rho * v0[p], rho * v1[p]), 1.0); } }
///     ...
///   };
template <class S>
concept SampleSource = requires(const S& s) {
  { S::dim } -> std::convertible_to<int>;
  { S::fields } -> std::convertible_to<int>;
  { s.size() } -> std::convertible_to<std::size_t>;
  s.for_each([](const Vec<S::dim>&, const Eigen::Matrix<double, S::fields, 1>&, double) {});
};

/// Samples stored column-wise (SoA), optionally through an index list (e.g. a cell's range of the sort order).
template <int Dim, int K>
struct SoaSamples {
  static constexpr int dim = Dim;
  static constexpr int fields = K;
  std::array<const double*, Dim> x{};  ///< positions, one column per axis
  std::array<const double*, K> f{};    ///< values, one column per field
  const double* w = nullptr;           ///< least-squares weight per sample (e.g. V_p); null: all 1
  const unsigned* index = nullptr;     ///< sample i is row index[i] of the columns; null: row i
  std::size_t count = 0;

  std::size_t size() const { return count; }
  template <class F>
  void for_each(F&& visit) const {
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t r = index ? index[i] : i;
      Vec<Dim> p;
      for (int d = 0; d < Dim; ++d) p[d] = x[d][r];
      Eigen::Matrix<double, K, 1> v;
      for (int k = 0; k < K; ++k) v[k] = f[k][r];
      visit(p, v, w ? w[r] : 1.0);
    }
  }
};

/// No samples (e.g. "no neighbour particles supplied").
template <int Dim, int K>
struct NoSamples {
  static constexpr int dim = Dim;
  static constexpr int fields = K;
  std::size_t size() const { return 0; }
  template <class F>
  void for_each(F&&) const {}
};

/// Which stage of the fixed completion order produced a fit (DESIGN.md "Per-cell solves"):
/// the cell's own samples at the requested degree → plus neighbour samples → lower degree → constant.
enum class FitStage : std::uint8_t {
  full,       ///< own samples, requested degree: no fallback
  neighbour,  ///< requested degree, with the neighbour samples added
  degree,     ///< a lower, non-constant degree (neighbours included when supplied)
  constant,   ///< constant only (TLS: c_0 from the integral; LS: sample mean; MLS: Shepard estimate)
  empty       ///< no sample at all and nothing prescribed: zero
};

struct FitStatus {
  FitStage stage = FitStage::full;
  int degree = 0;            ///< Taylor (or MLS) degree actually used
  std::size_t points = 0;    ///< samples that entered the least-squares sums
};

/// Fallback counters, one per stage; a solve is counted once, in the stage that produced its result.
/// Accumulate per thread and add (operator+=), or add each FitStatus with add().
struct FallbackCounts {
  std::size_t neighbour = 0;
  std::size_t degree = 0;
  std::size_t constant = 0;
  std::size_t empty = 0;

  void add(const FitStatus& s) {
    switch (s.stage) {
      case FitStage::full: break;
      case FitStage::neighbour: ++neighbour; break;
      case FitStage::degree: ++degree; break;
      case FitStage::constant: ++constant; break;
      case FitStage::empty: ++empty; break;
    }
  }
  FallbackCounts& operator+=(const FallbackCounts& o) {
    neighbour += o.neighbour;
    degree += o.degree;
    constant += o.constant;
    empty += o.empty;
    return *this;
  }
  std::size_t total() const { return neighbour + degree + constant + empty; }
  friend bool operator==(const FallbackCounts&, const FallbackCounts&) = default;
};

namespace detail {

/// Solves the symmetric positive semi-definite normal system D x = r (N unknowns, K right-hand sides) if D has
/// full rank; returns false without touching x otherwise. Rank is decided by a Cholesky factorisation with
/// diagonal pivoting (LDLᵀ) of the Jacobi-equilibrated matrix S D S (S = diag(D_ii^{-1/2})), a pivot counting as
/// zero below `threshold` times the first (largest) one. On a semi-definite matrix the largest entry is on the
/// diagonal and every Schur complement stays semi-definite, so this is what full pivoting would choose: a
/// rank-revealing factorisation for such matrices. The equilibration makes the test independent of the scaling
/// of the basis functions and of the sample weights; since D = Bᵀ W B, a relative threshold τ on D is √τ on the
/// singular values of the sample matrix B (τ = 1e-10: columns dependent to 1e-5 count as dependent). Never
/// detected afterwards by NaN. Written out for fixed N ≤ 6 instead of Eigen's FullPivLU, whose solve goes
/// through the dynamic-size triangular-solve and GEMM kernels: per cell of a TLS rebuild that was a third of
/// the reconstruction's instructions (callgrind, 2D plate, 2×2 particles per cell).
template <int N, int K, class DerivedD, class DerivedR>
inline bool solve_full_rank(const Eigen::MatrixBase<DerivedD>& D, const Eigen::MatrixBase<DerivedR>& r,
                            double threshold, Eigen::Matrix<double, N, K>& x) {
  Eigen::Matrix<double, N, 1> s;
  for (int i = 0; i < N; ++i) {
    if (!(D(i, i) > 0.0)) return false;  // a zero column: rank < N
    s[i] = 1.0 / std::sqrt(D(i, i));
  }
  Eigen::Matrix<double, N, N> A = s.asDiagonal() * D * s.asDiagonal();  // unit diagonal
  Eigen::Matrix<double, N, K> y = s.asDiagonal() * r;
  std::array<int, N> perm;
  double first = 0.0;
  for (int k = 0; k < N; ++k) {
    int p = k;
    for (int i = k + 1; i < N; ++i)
      if (A(i, i) > A(p, p)) p = i;
    if (k == 0) first = A(p, p);
    if (!(A(p, p) > threshold * first)) return false;
    perm[k] = p;
    if (N > 1 && p != k) {  // symmetric swap of k and p, and of the right-hand sides (N > 1: g++ 12 warns else)
      A.row(k).swap(A.row(p));
      A.col(k).swap(A.col(p));
      y.row(k).swap(y.row(p));
    }
    for (int i = k + 1; i < N; ++i)  // Schur complement (both triangles: the next pivot swap reads whole rows)
      for (int j = k + 1; j <= i; ++j) A(j, i) = A(i, j) -= A(i, k) * A(j, k) / A(k, k);
    for (int i = k + 1; i < N; ++i) {  // column k below the pivot becomes L(:, k)
      A(i, k) /= A(k, k);
      y.row(i) -= A(i, k) * y.row(k);  // forward substitution with L, interleaved
    }
  }
  for (int k = N - 1; k >= 0; --k) {  // D⁻¹, then back substitution with Lᵀ
    y.row(k) /= A(k, k);
    for (int i = k + 1; i < N; ++i) y.row(k) -= A(i, k) * y.row(i);
  }
  for (int k = N - 1; k >= 0; --k)  // undo the swaps, last first
    if (N > 1 && perm[k] != k) y.row(k).swap(y.row(perm[k]));
  x = s.asDiagonal() * y;
  return true;
}

}  // namespace detail

}  // namespace mpm
