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
#include "engine/scene.hpp"
#include "kernels/transfer.hpp"
#include "kernels/vector_log.hpp"

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

/// The columns of a body force's per-particle constants (Field::body_constants), null where not stored.
template <int Dim>
using BodyConstants = std::array<const double*, 2 * Dim>;

/// The manufactured body force of the vibrating plate (paper eq. 42 with π², PROBLEMS.md) at one time. What depends
/// on time alone is formed once per step (at_time), and what depends on the fixed reference position alone, sin k X_d
/// and cos k X_d, once per run (VibratingPlate::form_body_constants, kept with the particles), so a particle costs a
/// log and a few products: with libm's sin and cos per particle and step the large plate ran at 0.6× the throughput
/// of a scene without body force, and with a table of them (PeriodicSine) the plate's scatter still took twice the
/// time of the block's (docs/PERFORMANCE.md). The scatter asks for a batch of particles (at_batch): the column reads come
/// first, then the arithmetic and the log (log_for, vector_log in AVX2 code) run in vector lanes.
struct PlateBodyForce {
  static constexpr bool active = true;
  /// columns sin k X_0, cos k X_0, sin k X_1, cos k X_1 (k = 2π/L)
  BodyConstants<2> trig;
  std::array<double, 2> u_amp;  ///< A sin(ωt), A sin(ωt + π): u_d = u_amp_d sin(k X_d)
  std::array<double, 2> F_amp;  ///< k u_amp: F_dd = 1 + F_amp_d cos(k X_d)
  double lambda, mu, rho0, common, scale;  ///< common = 4μ/ρ₀ − c², scale = π²/L²

  static PlateBodyForce at_time(BodyConstants<2> trig, double A, double L, double c, double lambda, double mu,
                                double rho0, double t) {
    const double pi = std::numbers::pi, wt = c * pi * t / L, k = 2 * pi / L;
    const std::array<double, 2> u_amp{A * std::sin(wt), A * std::sin(wt + pi)};
    return {trig, u_amp, {k * u_amp[0], k * u_amp[1]}, lambda, mu, rho0, 4 * mu / rho0 - c * c, pi * pi / (L * L)};
  }

  template <int D>
  std::array<double, D> at(std::size_t p) const {
    if constexpr (D != 2) return {};
    else return force(trig[0][p], trig[1][p], trig[2][p], trig[3][p]);
  }

  /// out[j] = at(index[j]) for j < count ≤ body_force_batch, by the same arithmetic, in code compiled for I.
  template <int D, Isa I = Isa::baseline>
  void at_batch(const unsigned* index, std::size_t count, std::array<double, D>* out) const {
    if constexpr (D == 2) {
      double c[4][body_force_batch];  // the column reads (gathers)
      for (std::size_t j = 0; j < count; ++j)
        for (int k = 0; k < 4; ++k) c[k][j] = trig[k][index[j]];
      for (std::size_t j = 0; j < count; ++j)  // unit-stride arithmetic: vectorised
        out[j] = force<I>(c[0][j], c[1][j], c[2][j], c[3][j]);
    }
  }

 private:
  template <Isa I = Isa::baseline>
  std::array<double, 2> force(double sin_x, double cos_x, double sin_y, double cos_y) const {
    const double F11 = 1 + F_amp[0] * cos_x, F22 = 1 + F_amp[1] * cos_y;
    const double kk = lambda * (log_for<I>(F11 * F22) - 1) - mu;
    return {scale * u_amp[0] * sin_x * (common - 4 * kk / (rho0 * F11 * F11)),
            scale * u_amp[1] * sin_y * (common - 4 * kk / (rho0 * F22 * F22))};
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
  /// Forms the body force's constants of n particles from their reference positions X (2 Dim columns of n).
  virtual void form_body_constants(std::array<const double*, Dim> X, std::size_t n,
                                   std::array<double*, 2 * Dim> out) const;
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
