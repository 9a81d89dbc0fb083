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

/// The factors of the pivoted LDLᵀ of solve_full_rank (below), kept to solve for other right-hand sides with the
/// same D (a momentum-only TLS rebuild refits the velocity on the positions of the rebuild before it).
/// solve_full_rank is factor() then solve().
template <int N>
struct PivotedLdlt {
  std::uint8_t pivot[N];  ///< the index eliminated at step s
  double inverse[N];      ///< 1 / its pivot
  /// The multiplier at step s of the index eliminated at step t > s, at at(t, s): the strict lower triangle only,
  /// for a compact record where the factors are kept.
  std::array<double, N*(N - 1) / 2> multiplier;
  static constexpr int at(int t, int s) { return t * (t - 1) / 2 + s; }

  /// Factorises D; false when its rank is below N by the relative test of solve_full_rank (factors undefined).
  template <class DerivedD>
  bool factor(const Eigen::MatrixBase<DerivedD>& D, double threshold) {
    double A[N][N], diagonal[N];
    for (int i = 0; i < N; ++i) {
      diagonal[i] = D(i, i);
      if (!(diagonal[i] > 0.0)) return false;  // a zero column: rank < N
      for (int j = 0; j < N; ++j) A[i][j] = D(i, j);
    }
    double L[N][N];  // L[i][s]: the multiplier of index i at step s (i eliminated later)
    bool left[N];    // not yet eliminated
    int step_of[N];  // the step that eliminates index i
    for (int i = 0; i < N; ++i) left[i] = true;
    for (int s = 0; s < N; ++s) {
      int p = -1;  // the largest pivot relative to its diagonal: A_ii / d_i > A_pp / d_p without dividing
      for (int i = 0; i < N; ++i)
        if (left[i] && (p < 0 || A[i][i] * diagonal[p] > A[p][p] * diagonal[i])) p = i;
      if (!(A[p][p] > threshold * diagonal[p])) return false;
      pivot[s] = static_cast<std::uint8_t>(p);
      step_of[p] = s;
      left[p] = false;
      inverse[s] = 1.0 / A[p][p];
      for (int i = 0; i < N; ++i) {
        if (!left[i]) continue;
        const double l = A[i][p] * inverse[s];
        L[i][s] = l;
        for (int j = 0; j <= i; ++j)  // Schur complement, lower triangle, mirrored
          if (left[j]) A[j][i] = A[i][j] -= l * A[p][j];
      }
    }
    for (int i = 0; i < N; ++i)
      for (int s = 0; s < step_of[i]; ++s) multiplier[at(step_of[i], s)] = L[i][s];
    return true;
  }

  /// x = D⁻¹ r for K right-hand sides.
  template <int K, class DerivedR>
  void solve(const Eigen::MatrixBase<DerivedR>& r, Eigen::Matrix<double, N, K>& x) const {
    double y[N][K];  // in step order
    for (int s = 0; s < N; ++s)
      for (int k = 0; k < K; ++k) y[s][k] = r(pivot[s], k);
    for (int s = 0; s < N; ++s)  // forward substitution with L
      for (int t = s + 1; t < N; ++t)
        for (int k = 0; k < K; ++k) y[t][k] -= multiplier[at(t, s)] * y[s][k];
    for (int s = N - 1; s >= 0; --s)  // D⁻¹, then back substitution with Lᵀ
      for (int k = 0; k < K; ++k) {
        double v = y[s][k] * inverse[s];
        for (int t = s + 1; t < N; ++t) v -= multiplier[at(t, s)] * y[t][k];
        y[s][k] = v;
      }
    for (int s = 0; s < N; ++s)
      for (int k = 0; k < K; ++k) x(pivot[s], k) = y[s][k];
  }
};

/// Solves the symmetric positive semi-definite normal system D x = r (N unknowns, K right-hand sides) if D has
/// full rank; returns false without touching x otherwise. Rank is decided by a Cholesky factorisation with
/// diagonal pivoting (LDLᵀ) and a relative pivot test: the pivot of index i counts as zero below `threshold`
/// times D_ii, its diagonal before elimination. That is the test on the Jacobi-equilibrated matrix S D S
/// (S = diag(D_ii^{-1/2}), unit diagonal): its Schur complements are those of D scaled by S on both sides, so its
/// pivots are D's divided by D_ii, and the pivot order — the largest ratio first — is the same. On a
/// semi-definite matrix the largest entry is on the diagonal and every Schur complement stays semi-definite, so
/// this is what full pivoting would choose: a rank-revealing factorisation for such matrices. The relative test
/// makes the decision independent of the scaling of the basis functions and of the sample weights; since
/// D = Bᵀ W B, a relative threshold τ on D is √τ on the singular values of the sample matrix B (τ = 1e-10:
/// columns dependent to 1e-5 count as dependent). Never detected afterwards by NaN.
/// Written out for fixed N ≤ 6 instead of Eigen's FullPivLU, whose solve goes through the dynamic-size
/// triangular-solve and GEMM kernels (a third of a TLS rebuild's instructions, callgrind, 2D plate). The
/// factorisation works on D itself, in its own index order: the equilibration as ratios needs no square roots
/// and the pivoting as a choice of index moves no rows. Scaling D explicitly (3 square roots and 3 divisions for
/// N = 3), a division in every Schur update and rows swapped in memory and reloaded as vectors (store-forwarding
/// stalls) had made these solves 14 % of a 2D MUSL-TLS step with 3×3 particles per cell (perf).
template <int N, int K, class DerivedD, class DerivedR>
inline bool solve_full_rank(const Eigen::MatrixBase<DerivedD>& D, const Eigen::MatrixBase<DerivedR>& r,
                            double threshold, Eigen::Matrix<double, N, K>& x) {
  PivotedLdlt<N> f;
  if (!f.factor(D, threshold)) return false;
  f.solve(r, x);
  return true;
}

}  // namespace detail

}  // namespace mpm
