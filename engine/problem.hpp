#pragma once
// Built-in problems (PROBLEMS.md) and user-described scenes: initial state, body force, fixed sides and, where
// one exists, the exact solution. Problems are consulted at set-up and observation only; the body force they
// return is a concrete functor that the scatter kernel inlines.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <numbers>
#include <variant>
#include <vector>

#include "engine/periodic_sine.hpp"
#include "engine/reference_axes.hpp"
#include "engine/scene.hpp"
#include "kernels/transfer.hpp"
#include "kernels/isa.hpp"

namespace mpm {

/// Constant body force per unit mass (gravity, or a load uniform in space at the current time).
template <int Dim>
struct UniformBodyForce {
  static constexpr bool active = true;
  std::array<double, Dim> b;
  template <int D>
  std::array<double, D> at(std::size_t) const { return b; }
  template <int D, Isa = Isa::baseline>
  void at_batch(const unsigned*, std::size_t count, std::array<double, D>* out) const {
    std::fill_n(out, count, b);
  }
};

/// A body force's per-particle constants: the packed ranks of each particle's reference coordinates
/// (Field::body_constants, null where not stored) and the distinct coordinates they rank (ReferenceAxes).
template <int Dim>
struct BodyConstants {
  const double* key = nullptr;
  const ReferenceAxes<Dim>* axes = nullptr;
};

/// The manufactured body force of the vibrating plate (paper eq. 42 with π², PROBLEMS.md) at one time. It is
/// separable in the reference position: with F_dd = 1 + k u_d cos k X_d, ln J = ln F_11 + ln F_22 and
/// s_d = (π²/L²) u_d sin k X_d (u_d the displacement amplitudes at this time, k = 2π/L),
///   b_d = s_d (4μ/ρ₀ − c²) − s_d 4/(ρ₀ F_dd²) (λ (ln F_dd − 1) − μ + λ ln F_ee),   e the other axis,
/// so VibratingPlate::body_force forms the terms of each distinct reference coordinate once per step
/// (ReferenceAxes: 2 × 1024 at 512² cells) and a particle reads two of them through its ranks and combines them in
/// two multiply-adds: no log, no division, no trigonometry per particle. (Per particle, with sin k X_d and cos k X_d
/// in four columns, the plate's scatter took 76 instructions more per particle-step than the block's, and its step
/// ran at 0.82× the block's throughput: docs/PERFORMANCE.md.)
struct PlateBodyForce {
  static constexpr bool active = true;
  /// The terms of one reference coordinate X_d: b_d = P − Q (R + Λ_e).
  struct AxisTerms {
    double P;       ///< s_d (4μ/ρ₀ − c²)
    double Q;       ///< s_d 4/(ρ₀ F_dd²)
    double R;       ///< λ (ln F_dd − 1) − μ
    double Lambda;  ///< λ ln F_dd, the other axis' share of λ ln J
  };
  const double* key;  ///< per particle, its packed ranks (axis_ranks)
  std::array<std::shared_ptr<const std::vector<AxisTerms>>, 2> terms;  ///< per axis, by rank

  template <int D>
  std::array<double, D> at(std::size_t p) const {
    if constexpr (D != 2) return {};
    else {
      const auto r = axis_ranks<2>(key[p]);
      return combine((*terms[0])[r[0]], (*terms[1])[r[1]]);
    }
  }

  /// out[j] = at(index[j]) for j < count ≤ body_force_batch, by the same arithmetic.
  template <int D, Isa = Isa::baseline>
  void at_batch(const unsigned* index, std::size_t count, std::array<double, D>* out) const {
    if constexpr (D == 2)
      for (std::size_t j = 0; j < count; ++j) out[j] = at<2>(index[j]);
  }

 private:
  static std::array<double, 2> combine(const AxisTerms& x, const AxisTerms& y) {
    return {x.P - x.Q * (x.R + y.Lambda), y.P - y.Q * (y.R + x.Lambda)};
  }
};

template <int Dim>
using BodyForce = std::conditional_t<Dim == 2, std::variant<NoBodyForce, UniformBodyForce<Dim>, PlateBodyForce>,
                                     std::variant<NoBodyForce, UniformBodyForce<Dim>>>;

/// A force concentrated at a point of the current configuration: a traction on a boundary point of a 1D body
/// (thesis §4.6.2: τ(x⁰, t) = δ(x⁰ − l) σ(l, t)). Its grid share is the boundary term of thesis eq. 2.21,
/// f_i += φ_i(x) force (unit cross-section), added after the internal forces (engine/point_load.hpp).
template <int Dim>
struct PointLoad {
  std::array<double, Dim> x{};      ///< where it acts now
  std::array<double, Dim> force{};  ///< N (per unit cross-section in 1D: Pa)
};

/// Exact fields at a reference position and time.
template <int Dim>
struct ExactState {
  std::array<double, Dim> u{}, v{};
  std::array<double, Dim * Dim> sigma{};  ///< full Cauchy stress, row-major
};

template <int Dim>
class Problem {
 public:
  /// A rectangular body: box, material and initial velocity as a function of the reference position.
  struct Body {
    std::array<double, Dim> lo, hi;
    MaterialSpec material;
    std::function<std::array<double, Dim>(const std::array<double, Dim>&)> velocity;
  };

  virtual ~Problem() = default;
  virtual std::vector<Body> bodies() const = 0;
  virtual bool has_body_force() const { return false; }
  /// Whether the body force takes constants from the reference position (then X and the constants are stored per
  /// particle, Field::body_constants).
  virtual bool body_force_has_constants() const { return false; }
  /// The body force at time t; `constants` its columns (null if not stored).
  virtual BodyForce<Dim> body_force(double t, BodyConstants<Dim> constants) const;
  /// Whether the problem loads the grid with point forces (then point_loads is called at every force scatter).
  virtual bool has_point_loads() const { return false; }
  /// The point forces at time t on the particles (n of them), placed in the current configuration, or in the
  /// reference one (`reference`) for a basis that moves with the body.
  virtual std::vector<PointLoad<Dim>> point_loads(double t, const ParticleView<Dim>& p, std::size_t n,
                                                  bool reference = false) const;
  virtual bool has_exact() const { return false; }
  virtual ExactState<Dim> exact(const std::array<double, Dim>& X, double t) const;
  /// out[j] = exact(X at particle first + j, t) for j < count; `X` the reference columns. A batch lets a problem
  /// form what depends on t alone once for all of it (the plate's sines and cosines of ωt), not once per particle.
  virtual void exact_batch(double t, std::array<const double*, Dim> X, std::size_t first, std::size_t count,
                           ExactState<Dim>* out) const;
};

/// The problem a scene describes: a built-in one by name, or the scene's own bodies, gravity and sides.
template <int Dim>
std::unique_ptr<Problem<Dim>> make_problem(const Scene& scene);

}  // namespace mpm
