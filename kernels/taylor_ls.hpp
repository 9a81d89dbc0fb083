#pragma once
// Taylor least-squares (TLS) reconstruction on one cell: thesis §5.2 (1D), §6.1.1 (2D rectangles), §5.3
// (use in MPM). A field is fitted as f̂ = Σ_k c_k ψ_k with the local Taylor basis ψ_k of the cell. Every ψ_k
// except ψ_1 = 1 has zero mean over the cell (thesis eq. 5.7), so ∫_cell f̂ = c_0 |Ω_e| (eq. 5.8): fixing
// c_0 = c / |Ω_e| (eq. 5.9) preserves a prescribed integral c exactly — Σ m_p for the density, Σ m_p v_p for the
// momentum — and the other coefficients are a least-squares fit (eq. 5.1 without ψ_1, §5.3.1) of what ψ_1
// leaves: min Σ_p w_p (c_0 + Σ_{k≥1} c_k ψ_k(x_p) − f_p)². An unconstrained variant (all coefficients by least
// squares, §5.3.1 "standard least-squares approach") serves the stress and the body force.
//
// Rank deficiency (too few or badly placed samples: thesis Fig. 5.5 in 1D, §6.3.1 in 2D where runs crashed) is
// detected from a pivoted factorisation of the normal matrix, and the fit is completed in a fixed order, each
// step counted: neighbour samples (thesis §5.2.3, Fig. 5.7) → lower degree (§5.2.3) → constant. The constrained
// fit keeps c_0 from the integral in every stage, so it is conservative whatever happens.
//
// Coefficient index k = 0..N−1 here is the thesis' ψ_{k+1}. Bases are hierarchical: degree d uses the first
// taylor_size(d) functions of degree d+1, so a lower-degree fit is a leading block of the same normal system.
#include <array>
#include <cstddef>

#include "kernels/reconstruction.hpp"

namespace mpm {

/// Number of Taylor basis functions: 1D degree+1 (1, 2, 3); 2D (degree+1)(degree+2)/2 (1, 3, 6).
template <int Dim>
constexpr int taylor_size(int degree) {
  static_assert(Dim == 1 || Dim == 2, "TLS is implemented in 1D and 2D");
  return Dim == 1 ? degree + 1 : (degree + 1) * (degree + 2) / 2;
}

template <int Dim, int Degree>
using TaylorVector = Eigen::Matrix<double, taylor_size<Dim>(Degree), 1>;

/// Local Taylor basis at cell coordinates ξ = (x − x_c) / Δx (∈ [−1, 1] inside the cell, Δx the half width):
///   1D (thesis §5.2.2):  ψ = [1, ξ, ξ²/2 − 1/6]
///   2D (thesis eqs 6.1–6.6, 6.8–6.13 on a rectangle):  ψ = [1, ξ₁, ξ₂, ξ₁²/2 − 1/6, ξ₂²/2 − 1/6, ξ₁ξ₂]
/// The subtracted constants are the cell averages: mean of ξ²/2 over [−1, 1] is 1/6, of ξ₁ξ₂ over the square 0.
/// As plain scalars (taylor_basis_ref gives the same as a vector): for loops that broadcast each ψ_k, where an
/// Eigen vector assembled from scalar stores and reloaded as a packet stalled on store forwarding.
template <int Dim, int Degree>
inline std::array<double, taylor_size<Dim>(Degree)> taylor_basis_values(const Vec<Dim>& xi) {
  static_assert(Degree >= 0 && Degree <= 2, "Taylor degree 0, 1 or 2");
  std::array<double, taylor_size<Dim>(Degree)> psi;
  psi[0] = 1.0;                                                          // ψ_1, eq. 6.1
  if constexpr (Dim == 1) {
    if constexpr (Degree >= 1) psi[1] = xi[0];                           // ψ_2
    if constexpr (Degree >= 2) psi[2] = 0.5 * xi[0] * xi[0] - 1.0 / 6.0; // ψ_3
  } else {
    if constexpr (Degree >= 1) {
      psi[1] = xi[0];                                                    // ψ_2, eq. 6.2
      psi[2] = xi[1];                                                    // ψ_3, eq. 6.3
    }
    if constexpr (Degree >= 2) {
      psi[3] = 0.5 * xi[0] * xi[0] - 1.0 / 6.0;                          // ψ_4, eqs 6.4, 6.8–6.9
      psi[4] = 0.5 * xi[1] * xi[1] - 1.0 / 6.0;                          // ψ_5, eqs 6.5, 6.10–6.11
      psi[5] = xi[0] * xi[1];                                            // ψ_6, eqs 6.6, 6.12–6.13 (mean 0)
    }
  }
  return psi;
}

template <int Dim, int Degree>
inline TaylorVector<Dim, Degree> taylor_basis_ref(const Vec<Dim>& xi) {
  const auto psi = taylor_basis_values<Dim, Degree>(xi);
  return Eigen::Map<const TaylorVector<Dim, Degree>>(psi.data());
}

/// Centre and inverse half width of a cell: the map x ↦ ξ of the Taylor basis.
template <int Dim>
struct TaylorFrame {
  Vec<Dim> centre = Vec<Dim>::Zero(), inv_half = Vec<Dim>::Zero();
  TaylorFrame() = default;
  explicit TaylorFrame(const CellBox<Dim>& cell)
      : centre(cell.centre()), inv_half(cell.half_width().cwiseInverse()) {}
  Vec<Dim> xi(const Vec<Dim>& x) const { return (x - centre).cwiseProduct(inv_half); }
};

/// The change of Taylor frame: the N×N matrix G with ψ_to(x) = G ψ_from(x) for every x, so that the normal sums
/// of one cell's samples move to another cell's frame as G D Gᵀ and G b (TaylorNormalSystem::add_moved). With
/// ξ_to = a ξ_from + δ per axis (a = h_from / h_to, δ = (centre_from − centre_to) / h_to, h the half widths):
///   ξ_to                = δ + a ξ_from
///   ξ_to²/2 − 1/6       = (a²/6 + δ²/2 − 1/6) + aδ ξ_from + a² (ξ_from²/2 − 1/6)
///   ξ1_to ξ2_to         = δ1δ2 + a1δ2 ξ1 + a2δ1 ξ2 + a1a2 ξ1ξ2   (ξ of the from frame)
/// G is sparse: apply() multiplies by it from these formulas. `Axes` (bit d: axis d) says which axes the frames
/// differ in; along the others a = 1 and δ = 0 at compile time, so a move along one axis (the separable
/// neighbourhood sums of a TLS rebuild) costs a fraction of a general one.
template <int Dim, int Degree, unsigned Axes = (1u << Dim) - 1>
struct TaylorChange {
  static constexpr int N = taylor_size<Dim>(Degree);
  Vec<Dim> a, delta;
  TaylorChange(const TaylorFrame<Dim>& from, const TaylorFrame<Dim>& to)
      : a(to.inv_half.cwiseQuotient(from.inv_half)), delta((from.centre - to.centre).cwiseProduct(to.inv_half)) {}

  /// G M, for M with N rows; column by column (contiguous in Eigen's column-major storage).
  template <class Derived>
  Eigen::Matrix<double, N, Derived::ColsAtCompileTime> apply(const Eigen::MatrixBase<Derived>& M) const {
    Eigen::Matrix<double, N, Derived::ColsAtCompileTime> r;
    for (int j = 0; j < M.cols(); ++j) {
      const double m0 = M(0, j);
      r(0, j) = m0;
      if constexpr (Degree >= 1) {
        row_linear<0>(M, j, m0, r);
        if constexpr (Dim == 2) row_linear<1>(M, j, m0, r);
      }
      if constexpr (Degree >= 2) {
        row_square<0>(M, j, m0, r);
        if constexpr (Dim == 2) {
          row_square<1>(M, j, m0, r);
          r(5, j) = scale<0>() * scale<1>() * M(5, j);
          if constexpr (moves<1>()) r(5, j) += scale<0>() * delta[1] * M(1, j);
          if constexpr (moves<0>()) r(5, j) += scale<1>() * delta[0] * M(2, j);
          if constexpr (moves<0>() && moves<1>()) r(5, j) += delta[0] * delta[1] * m0;
        }
      }
    }
    return r;
  }
  /// G D Gᵀ for a symmetric D (the result is symmetric).
  Eigen::Matrix<double, N, N> congruence(const Eigen::Matrix<double, N, N>& D) const {
    return apply(apply(D).transpose());
  }
  Eigen::Matrix<double, N, N> matrix() const { return apply(Eigen::Matrix<double, N, N>::Identity()); }

 private:
  template <int D>
  static constexpr bool moves() {
    return (Axes >> D) & 1u;
  }
  template <int D>
  double scale() const {
    if constexpr (moves<D>()) return a[D];
    return 1.0;
  }
  template <int D, class M, class R>
  void row_linear(const M& m, int j, double m0, R& r) const {  // ψ of ξ_D
    if constexpr (moves<D>()) r(1 + D, j) = delta[D] * m0 + a[D] * m(1 + D, j);
    else r(1 + D, j) = m(1 + D, j);
  }
  template <int D, class M, class R>
  void row_square(const M& m, int j, double m0, R& r) const {  // ψ of ξ_D²/2 − 1/6
    constexpr int q = 1 + Dim + D;
    if constexpr (moves<D>())
      r(q, j) = (a[D] * a[D] / 6.0 + 0.5 * delta[D] * delta[D] - 1.0 / 6.0) * m0 + a[D] * delta[D] * m(1 + D, j) +
                a[D] * a[D] * m(q, j);
    else r(q, j) = m(q, j);
  }
};

/// Taylor basis of `cell` at the physical point x.
template <int Dim, int Degree>
inline TaylorVector<Dim, Degree> taylor_basis(const CellBox<Dim>& cell, const Vec<Dim>& x) {
  return taylor_basis_ref<Dim, Degree>(TaylorFrame<Dim>(cell).xi(x));
}

/// A Taylor fit of K fields on one cell: f̂_j(x) = Σ_k c(k, j) ψ_k(x). After a fallback to a lower degree the
/// unused (higher) coefficients are zero, so evaluation always uses the full basis.
template <int Dim, int Degree, int K>
struct TaylorFit {
  static constexpr int size = taylor_size<Dim>(Degree);
  CellBox<Dim> cell;
  Eigen::Matrix<double, size, K> c = Eigen::Matrix<double, size, K>::Zero();
  FitStatus status;

  /// f̂(x) = ψ(x)ᵀ c  (thesis eq. 5.5 with the coefficients found).
  Eigen::Matrix<double, K, 1> operator()(const Vec<Dim>& x) const {
    return c.transpose() * taylor_basis<Dim, Degree>(cell, x);
  }
  /// The same at many points (e.g. a cell's Gauss points), ξ-frame computed once. out[g] = f̂(x[g]).
  template <class Points, class Out>
  void evaluate(const Points& x, Out& out) const {
    const TaylorFrame<Dim> fr(cell);
    for (std::size_t g = 0; g < std::size(x); ++g)
      out[g] = c.transpose() * taylor_basis_ref<Dim, Degree>(fr.xi(x[g]));
  }
  /// ∫_cell f̂ = c_0 |Ω_e|, exactly (thesis eq. 5.8).
  Eigen::Matrix<double, K, 1> integral() const { return c.row(0).transpose() * cell.volume(); }
};

struct TlsOptions {
  /// Relative pivot threshold of the rank test on the equilibrated normal matrix (see detail::solve_full_rank).
  double rank_threshold = 1e-10;
  /// Least-squares weight of a neighbour sample relative to the cell's own (thesis Fig. 5.7 uses them as is: 1).
  double neighbour_weight = 1.0;
  /// Accept a stage only with at least as many samples as Taylor functions of its degree (ψ_1 included), even if
  /// the constrained matrix happens to have full rank — thesis §5.3.1: "optimal performance of the TLS technique
  /// requires at least three particles in each element" (n_b = 3). Without it, 2 samples fix the 2 slopes of a
  /// 2D linear fit exactly (the constraint acts as a third datum at the centroid), with no redundancy.
  bool require_points_per_function = true;
};

namespace detail {

/// Normal equations of one cell, thesis eqs 5.1–5.4 with weights: D = Σ w ψ ψᵀ, b = Σ w ψ (f − shift)ᵀ.
/// The shift (c_0 for the constrained fit; the first sample's values otherwise) keeps b free of cancellation
/// when a field has a large mean and small variation (momentum of a translating body); it is added back to c_0.
template <int Dim, int Degree, int K>
struct TaylorNormalSystem {
  static constexpr int N = taylor_size<Dim>(Degree);
  Eigen::Matrix<double, N, N> D = Eigen::Matrix<double, N, N>::Zero();
  Eigen::Matrix<double, N, K> b = Eigen::Matrix<double, N, K>::Zero();
  Eigen::Matrix<double, K, 1> shift = Eigen::Matrix<double, K, 1>::Zero();
  bool shift_set = false;
  std::size_t points = 0;

  template <SampleSource S>
  void add(const TaylorFrame<Dim>& fr, const S& s, double scale) {
    add_samples([&](auto&& add_one) {
      s.for_each([&](const Vec<Dim>& x, const Eigen::Matrix<double, K, 1>& f, double weight) {
        add_one(fr.xi(x), f, scale * weight);
      });
    });
    points += s.size();
  }
  /// One sample at ξ (cell coordinates) with values f and weight w; `points` is the caller's to count.
  void add_sample(const Vec<Dim>& xi, const Eigen::Matrix<double, K, 1>& f, double w) {
    add_samples([&](auto&& add_one) { add_one(xi, f, w); });
  }
  /// Many samples: visit(add_one) calls add_one(ξ, f, w) for each; `points` is the caller's to count. The sums
  /// are kept in locals while the samples stream in, the right-hand sides field-major (column k of `bt` is
  /// Σ w ψ_k (f − shift): K contiguous values, one vector FMA per Taylor function and sample) and D as its lower
  /// triangle, and written back once. Summing into the members directly made every sample a round trip through
  /// memory (the caller's particle columns may alias them): a TLS rebuild's first pass was 23 % of a 2D MUSL-TLS
  /// step (perf, 3×3 particles per cell) at ≈ 160 cycles per particle.
  /// Matrix = false sums the right-hand sides only, for samples whose D the caller already has (the same
  /// positions as an earlier sum: a momentum-only TLS rebuild); D is left as it is.
  template <bool Matrix = true, class Visit>
  void add_samples(Visit&& visit) {
    Eigen::Matrix<double, K, N> bt = b.transpose();
    Eigen::Matrix<double, N, N> lower = D;
    Eigen::Matrix<double, K, 1> s = shift;
    bool have_shift = shift_set;
    visit([&](const Vec<Dim>& xi, const Eigen::Matrix<double, K, 1>& f, double w) {
      if (!have_shift) {
        s = f;
        have_shift = true;
      }
      const Eigen::Matrix<double, K, 1> g = f - s;
      // ψ_k, at degree ≤ 1 read from ξ itself (ψ = [1, ξ]): through the array alone, the native build stored ψ by
      // scalars and reloaded it in pairs for the D updates, and the failed store forwarding was a third of the loop
      const auto basis = taylor_basis_values<Dim, Degree>(xi);
      auto psi = [&](int k) { return Degree <= 1 && k > 0 ? xi[k - 1] : basis[k]; };
      for (int k = 0; k < N; ++k) bt.col(k) += (w * psi(k)) * g;
      if constexpr (Matrix)
        for (int i = 0; i < N; ++i)
          for (int j = 0; j <= i; ++j) lower(i, j) += (w * psi(i)) * psi(j);
    });
    if constexpr (Matrix) {
      for (int i = 0; i < N; ++i)
        for (int j = 0; j < i; ++j) lower(j, i) = lower(i, j);
      D = lower;
    }
    b = bt.transpose();
    shift = s;
    shift_set = have_shift;
  }
  /// The same sums with `s` subtracted instead of the current shift: b += Σ w ψ (shift − s)ᵀ, and Σ w ψ is the
  /// first column of D (ψ_1 = 1).
  void reshift(const Eigen::Matrix<double, K, 1>& s) {
    if (shift_set) b.noalias() += D.col(0) * (shift - s).transpose();
    shift = s;
    shift_set = true;
  }
  /// Adds samples summed in another cell's frame, `change` = TaylorChange(that frame, this frame): their D, b
  /// (shifted by `their_shift`) and count. Equal to adding those samples one by one, up to round-off.
  void add_moved(const TaylorNormalSystem& o, const auto& change, double scale) {
    add_moved(o.D, o.b, o.shift, o.points, change, scale);
  }
  template <unsigned Axes, class DerivedB, class DerivedS>
  void add_moved(const Eigen::Matrix<double, N, N>& their_D, const Eigen::MatrixBase<DerivedB>& their_b,
                 const Eigen::MatrixBase<DerivedS>& their_shift, std::size_t their_points,
                 const TaylorChange<Dim, Degree, Axes>& change, double scale) {
    if (their_points == 0) return;
    add_moved_rhs(their_D.col(0), their_b, their_shift, their_points, change, scale);
    D += scale * change.congruence(their_D);
  }
  /// The right-hand sides and count of add_moved, not D: for samples at the positions of an earlier add_moved
  /// whose D (G D Gᵀ) the caller kept. `their_weights` is their Σ w ψ (the first column of their D); with
  /// `weights` set, D's first column is moved too (G D Gᵀ e₁ = G D e₁, since ψ_1 = 1 in every frame), for a
  /// caller that moves these sums on once more.
  template <bool Weights = false, unsigned Axes, class DerivedW, class DerivedB, class DerivedS>
  void add_moved_rhs(const Eigen::MatrixBase<DerivedW>& their_weights, const Eigen::MatrixBase<DerivedB>& their_b,
                     const Eigen::MatrixBase<DerivedS>& their_shift, std::size_t their_points,
                     const TaylorChange<Dim, Degree, Axes>& change, double scale) {
    if (their_points == 0) return;
    if constexpr (Weights) D.col(0) += scale * change.apply(their_weights);
    if (!shift_set) {
      shift = their_shift;
      shift_set = true;
    }
    Eigen::Matrix<double, N, K> bo;  // their b with this system's shift
    for (int k = 0; k < K; ++k) {
      const double dk = their_shift[k] - shift[k];
      for (int i = 0; i < N; ++i) bo(i, k) = their_b(i, k) + their_weights[i] * dk;
    }
    b += scale * change.apply(bo);
    points += their_points;
  }

  /// Least squares at degree Deg ≤ Degree. Constrained: unknowns c_1..c_{n−1} (c_0 is fixed and already
  /// subtracted through the shift), the block of D without ψ_1 (§5.3.1). Unconstrained: all n coefficients.
  template <int Deg, bool Constrained>
  bool solve(const TlsOptions& opt, Eigen::Matrix<double, N, K>& c) const {
    constexpr int n = taylor_size<Dim>(Deg);
    constexpr int off = Constrained ? 1 : 0;
    constexpr int m = n - off;
    if constexpr (m == 0) {
      return true;  // constrained degree 0: c_0 alone, nothing to fit
    } else {
      if (opt.require_points_per_function && points < static_cast<std::size_t>(n)) return false;
      Eigen::Matrix<double, m, K> x;
      if (!solve_full_rank<m, K>(D.template block<m, m>(off, off), b.template block<m, K>(off, 0),
                                 opt.rank_threshold, x))
        return false;
      c.setZero();
      c.template block<m, K>(off, 0) = x;
      return true;
    }
  }
};

/// A fit to the cell's own samples, its coefficients solved for: the shift added back to c_0, the stage recorded.
template <int Dim, int Degree, int K, class DerivedS>
inline void complete_own_fit(TaylorFit<Dim, Degree, K>& fit, const Eigen::MatrixBase<DerivedS>& shift,
                             std::size_t points) {
  fit.c.row(0) += shift.transpose();
  fit.status = {FitStage::full, Degree, points};
}

/// Stage 1 of the completion order alone: the fit to the cell's own samples (`sys`) at the requested degree
/// (constrained: c_0 is the shift). False, `fit` undefined, when they do not determine it: the caller completes
/// with complete_fit.
template <int Degree, int Dim, int K>
inline bool own_fit(const CellBox<Dim>& cell, const TaylorNormalSystem<Dim, Degree, K>& sys, bool constrained,
                    const TlsOptions& opt, TaylorFit<Dim, Degree, K>& fit) {
  fit.cell = cell;
  if (!(constrained ? sys.template solve<Degree, true>(opt, fit.c) : sys.template solve<Degree, false>(opt, fit.c)))
    return false;
  complete_own_fit(fit, sys.shift, sys.points);
  return true;
}

/// own_fit's unconstrained fit from the factors of the samples' D (PivotedLdlt::factor, with the rank test
/// own_fit would apply): the same numbers, for the right-hand sides `b` (shifted by `shift`) of `points` samples.
/// A caller that fits other values at the same positions factorises D once.
template <int Degree, int Dim, int K, class DerivedB, class DerivedS>
inline void fit_with(const CellBox<Dim>& cell, const PivotedLdlt<taylor_size<Dim>(Degree)>& factors,
                     const Eigen::MatrixBase<DerivedB>& b, const Eigen::MatrixBase<DerivedS>& shift,
                     std::size_t points, TaylorFit<Dim, Degree, K>& fit) {
  fit.cell = cell;
  factors.solve(b, fit.c);
  complete_own_fit(fit, shift, points);
}

/// The completion order shared by the constrained and the unconstrained fit, on a normal system that holds the
/// cell's own samples (constrained: shifted by c_0, which the fit keeps). add_neighbours(sys) adds the neighbour
/// samples to it and returns false if there are none.
template <int Degree, int Dim, int K, class AddNeighbours>
inline TaylorFit<Dim, Degree, K> complete_fit(const CellBox<Dim>& cell, const TaylorNormalSystem<Dim, Degree, K>& own,
                                              bool constrained, AddNeighbours&& add_neighbours,
                                              const TlsOptions& opt) {
  TaylorFit<Dim, Degree, K> fit;
  // 1. The cell's own samples at the requested degree.
  if (own_fit(cell, own, constrained, opt, fit)) return fit;
  TaylorNormalSystem<Dim, Degree, K> sys = own;  // the later stages add to a copy: the first copies nothing
  // Own-sample constant for the unconstrained constant stage: Σ w (f − shift) / Σ w over the cell's samples.
  const double own_w = own.D(0, 0);
  const Eigen::Matrix<double, K, 1> own_b = own.b.row(0).transpose();

  auto done = [&](FitStage stage, int degree) {
    fit.c.row(0) += sys.shift.transpose();
    fit.status = {stage, degree, sys.points};
    return fit;
  };
  auto solve = [&]<int Deg>() {
    return constrained ? sys.template solve<Deg, true>(opt, fit.c) : sys.template solve<Deg, false>(opt, fit.c);
  };

  // 2. (a) add the neighbour samples (thesis §5.2.3, Fig. 5.7), same degree.
  if (add_neighbours(sys) && solve.template operator()<Degree>()) return done(FitStage::neighbour, Degree);
  // 3. (b) lower the degree (thesis §5.2.3: "reducing the number of basis functions"), neighbours kept.
  if constexpr (Degree >= 2) {
    static_assert(Degree == 2, "Taylor degree 0, 1 or 2");
    if (solve.template operator()<1>()) return done(FitStage::degree, 1);
  }
  // 4. (c) constant. Constrained: c_0 from the integral (it is the shift). Unconstrained: weighted mean of the
  //    cell's own samples, or of the neighbours when the cell has none; zero when there is nothing at all.
  fit.c.setZero();
  if (!constrained) {
    if (own_w > 0.0) {
      fit.c.row(0) = (own_b / own_w).transpose();
    } else if (sys.D(0, 0) > 0.0) {
      fit.c.row(0) = sys.b.row(0) / sys.D(0, 0);
    } else {
      fit.status = {FitStage::empty, 0, 0};
      return fit;  // no sample: zero
    }
  }
  return done(FitStage::constant, 0);
}

/// complete_fit on sample sources, c_0 given (constrained) or nullptr (unconstrained).
template <int Degree, int Dim, int K, SampleSource Own, SampleSource Nb>
inline TaylorFit<Dim, Degree, K> taylor_fit(const CellBox<Dim>& cell, const Own& own, const Nb& neighbours,
                                            const Eigen::Matrix<double, K, 1>* c0, const TlsOptions& opt) {
  static_assert(Own::dim == Dim && Nb::dim == Dim, "sample dimension must match the cell");
  static_assert(Own::fields == K && Nb::fields == K, "sample field count must match");
  const TaylorFrame<Dim> fr(cell);
  TaylorNormalSystem<Dim, Degree, K> sys;
  if (c0) sys.reshift(*c0);
  sys.add(fr, own, 1.0);
  auto add_neighbours = [&](TaylorNormalSystem<Dim, Degree, K>& s) {
    if (neighbours.size() == 0) return false;
    s.add(fr, neighbours, opt.neighbour_weight);
    return true;
  };
  return complete_fit<Degree>(cell, sys, c0 != nullptr, add_neighbours, opt);
}

}  // namespace detail

/// Conservative TLS of K fields on `cell` (thesis §5.2.3, §5.3.1 eq. 5.14): c_0 = integral / |Ω_e| (eq. 5.9),
/// so ∫_cell f̂ = integral exactly in every stage; c_1.. by least squares on f_p − c_0 over `own` (the cell's
/// particles), completed with `neighbours` (particles of the adjacent cells; pass NoSamples if none) only if
/// the own samples do not determine the fit. `integral`: e.g. Σ m_p for ρ, Σ m_p v_p for ρv.
template <int Degree, int Dim, int K, SampleSource Own, SampleSource Nb>
inline TaylorFit<Dim, Degree, K> reconstruct_tls(const CellBox<Dim>& cell, const Own& own, const Nb& neighbours,
                                                 const Eigen::Matrix<double, K, 1>& integral,
                                                 const TlsOptions& opt = {}) {
  const Eigen::Matrix<double, K, 1> c0 = integral / cell.volume();  // thesis eq. 5.9
  return detail::taylor_fit<Degree>(cell, own, neighbours, &c0, opt);
}

/// Unconstrained least squares in the Taylor basis (thesis §5.3.1, eq. 5.12: stress; paper eq. 20: body force):
/// all coefficients from eq. 5.1, same completion order; the constant stage is the weighted sample mean.
template <int Degree, int Dim, SampleSource Own, SampleSource Nb>
inline TaylorFit<Dim, Degree, Own::fields> reconstruct_ls(const CellBox<Dim>& cell, const Own& own,
                                                          const Nb& neighbours, const TlsOptions& opt = {}) {
  return detail::taylor_fit<Degree>(cell, own, neighbours,
                                    static_cast<const Eigen::Matrix<double, Own::fields, 1>*>(nullptr), opt);
}

}  // namespace mpm
