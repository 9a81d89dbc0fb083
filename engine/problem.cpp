#include "engine/problem.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "engine/body_extent.hpp"
#include "engine/material.hpp"
#include "engine/reference_1d.hpp"
#include "kernels/isa.hpp"
#include "kernels/vector_log.hpp"

namespace mpm {

using std::numbers::pi;

template <int Dim>
void Problem<Dim>::form_body_constants(std::array<const double*, Dim>, std::size_t,
                                       std::array<double*, 2 * Dim>) const {}

template <int Dim>
BodyForce<Dim> Problem<Dim>::body_force(double, BodyConstants<Dim>) const {
  return NoBodyForce{};
}

template <int Dim>
std::vector<PointLoad<Dim>> Problem<Dim>::point_loads(double, const ParticleView<Dim>&, std::size_t, bool) const {
  return {};
}

template <int Dim>
ExactState<Dim> Problem<Dim>::exact(const std::array<double, Dim>&, double) const {
  throw std::logic_error("this problem has no exact solution");
}

template <int Dim>
void Problem<Dim>::exact_batch(double t, std::array<const double*, Dim> X, std::size_t first, std::size_t count,
                               ExactState<Dim>* out) const {
  for (std::size_t j = 0; j < count; ++j) {
    std::array<double, Dim> Xp;
    for (int d = 0; d < Dim; ++d) Xp[d] = X[d][first + j];
    out[j] = exact(Xp, t);
  }
}

namespace {

ExactState<1> exact_1d(const Fields1d& f) {
  ExactState<1> e;
  e.u[0] = f.u;
  e.v[0] = f.v;
  e.sigma[0] = f.sigma;
  return e;
}

/// Bar with fixed ends (thesis §3.4.1): v(x,0) = v0 sin(πx/l), uniaxial strain modulus M = λ + 2μ.
class VibratingBar final : public Problem<1> {
 public:
  VibratingBar(const Scene& s) : mat_(s.material), l_(s.grid.length[0]), v0_(s.problem.v0) {
    const Lame k = Lame::from(mat_);
    M_ = k.lambda + 2 * k.mu;
    c_ = std::sqrt(M_ / mat_.density);
  }
  std::vector<Body> bodies() const override {
    return {{{0.0}, {l_}, mat_, [this](const std::array<double, 1>& X) {
               return std::array<double, 1>{v0_ * std::sin(pi * X[0] / l_)};
             }}};
  }
  bool has_exact() const override { return true; }
  ExactState<1> exact(const std::array<double, 1>& X, double t) const override {
    const double w = pi * c_ / l_;
    ExactState<1> e;
    e.u[0] = v0_ / w * std::sin(w * t) * std::sin(pi * X[0] / l_);
    e.v[0] = v0_ * std::cos(w * t) * std::sin(pi * X[0] / l_);
    e.sigma[0] = v0_ * mat_.density * c_ * std::sin(w * t) * std::cos(pi * X[0] / l_);  // M ∂u/∂X
    return e;
  }

 private:
  MaterialSpec mat_;
  double l_, v0_, M_, c_;
};

/// Axis-aligned vibrating plate, manufactured solution (paper eqs 38–42, PROBLEMS.md).
class VibratingPlate final : public Problem<2> {
 public:
  VibratingPlate(const Scene& s)
      : mat_(s.material), L_(s.grid.length[0]), A_(s.problem.amplitude), trig_(L_) {
    k_ = Lame::from(mat_);
    c_ = std::sqrt(mat_.E / mat_.density);
  }
  std::vector<Body> bodies() const override {
    return {{{0.0, 0.0}, {L_, L_}, mat_, [this](const std::array<double, 2>& X) { return exact(X, 0.0).v; }}};
  }
  bool has_body_force() const override { return true; }
  bool body_force_has_constants() const override { return true; }
  void form_body_constants(std::array<const double*, 2> X, std::size_t n,
                           std::array<double*, 4> out) const override {
    for (int d = 0; d < 2; ++d)
      for (std::size_t p = 0; p < n; ++p) {
        const double kX = 2 * pi / L_ * X[d][p];
        out[2 * d][p] = std::sin(kX);
        out[2 * d + 1][p] = std::cos(kX);
      }
  }
  BodyForce<2> body_force(double t, BodyConstants<2> trig) const override {
    return PlateBodyForce::at_time(trig, A_, L_, c_, k_.lambda, k_.mu, mat_.density, t);
  }
  bool has_exact() const override { return true; }
  ExactState<2> exact(const std::array<double, 2>& X, double t) const override {
    ExactState<2> e;
    exact_batch(t, {&X[0], &X[1]}, 0, 1, &e);
    return e;
  }
  void exact_batch(double t, std::array<const double*, 2> X, std::size_t first, std::size_t count,
                   ExactState<2>* out) const override {
    const double wt = c_ * pi * t / L_;
    const double sin_t[2] = {std::sin(wt), std::sin(wt + pi)}, cos_t[2] = {std::cos(wt), std::cos(wt + pi)};
    // the logs in a loop of their own, which runs in vector lanes in the AVX2 code (log_for), as PlateBodyForce does;
    // the rest stays in the build's own code, so that the initial velocities (exact at t = 0) do not depend on the
    // instruction set
    constexpr std::size_t lanes = 64;
    for (std::size_t begin = 0; begin < count; begin += lanes) {
      const std::size_t n = std::min(lanes, count - begin);
      double F[2][lanes], J[lanes], lnJ[lanes];  // the diagonal of F, its determinant and log
      for (std::size_t j = 0; j < n; ++j) {
        for (int d = 0; d < 2; ++d) {
          const auto [s, c] = trig_(X[d][first + begin + j]);
          out[begin + j].u[d] = A_ * s * sin_t[d];
          out[begin + j].v[d] = A_ * c_ * pi / L_ * s * cos_t[d];
          F[d][j] = 1 + (2 * pi * A_ / L_) * c * sin_t[d];
        }
        J[j] = F[0][j] * F[1][j];
      }
      with_active_isa([&](auto isa) {
        for (std::size_t j = 0; j < n; ++j) lnJ[j] = log_for<isa>(J[j]);
      });
      for (std::size_t j = 0; j < n; ++j)
        out[begin + j].sigma = {(k_.lambda * lnJ[j] + k_.mu * (F[0][j] * F[0][j] - 1)) / J[j], 0.0, 0.0,
                                (k_.lambda * lnJ[j] + k_.mu * (F[1][j] * F[1][j] - 1)) / J[j]};
    }
  }

 private:
  MaterialSpec mat_;
  Lame k_;
  double L_, A_, c_;
  PeriodicSine trig_;  ///< sin and cos of 2π X/L for the exact solution
};

/// Column compaction (thesis §5.4.2, PROBLEMS.md): [0, H] fixed at the bottom, body force ramped to b_f over t_f;
/// exact solution for the linear-elastic law (docs/COLUMN_COMPACTION.md).
class ColumnCompactionProblem final : public Problem<1> {
 public:
  ColumnCompactionProblem(const Scene& s) {
    c_.height = s.problem.height;
    c_.max_body_force = s.problem.max_body_force;
    c_.ramp_time = s.problem.ramp_time;
    c_.material = s.material;
  }
  std::vector<Body> bodies() const override {
    return {{{0.0}, {c_.height}, c_.material, [](const std::array<double, 1>&) { return std::array<double, 1>{}; }}};
  }
  bool has_body_force() const override { return true; }
  BodyForce<1> body_force(double t, BodyConstants<1>) const override {
    return UniformBodyForce<1>{{c_.body_force(t)}};
  }
  bool has_exact() const override { return c_.material.model == MaterialModel::linear_elastic; }
  ExactState<1> exact(const std::array<double, 1>& X, double t) const override {
    return exact_1d(column_compaction_exact(c_, X[0], t));
  }

 private:
  ColumnCompaction c_;
};

/// Bar with a dynamic traction at its free end (thesis §4.6.2, PROBLEMS.md): [0, l] in a longer grid, fixed at
/// X = 0, at rest, loaded at its material end X = l by τ(t) (thesis eq. 4.93 at x⁰ = l). The thesis writes the
/// load as τ = δ(x⁰ − l) σ: a point force on the material end, wherever that end is now. The end is not a
/// particle: it is the outer edge of the last particle's domain, x_M + V_M/2 with V = J V0 (the same current
/// extent the cubic-spline mapping integrates over, thesis Fig. 3.3), and the load reaches the grid through the
/// basis functions there, f_i += φ_i(x_end) τ (eq. 2.21). Exact solution: the linear wave of eq. 4.93 — exact for
/// the linear-elastic law; for the thesis' neo-Hookean bar it is first order in the strain A/M (1 %), as the
/// thesis compares it (Fig. 4.8).
class VibratingBarTraction final : public Problem<1> {
 public:
  VibratingBarTraction(const Scene& s) : mat_(s.material) {
    bar_.density = mat_.density;
    bar_.modulus = uniaxial_modulus(mat_);
  }
  std::vector<Body> bodies() const override {
    return {{{0.0}, {bar_.length}, mat_, [](const std::array<double, 1>&) { return std::array<double, 1>{}; }}};
  }
  bool has_point_loads() const override { return true; }
  std::vector<PointLoad<1>> point_loads(double t, const ParticleView<1>& p, std::size_t n, bool reference) const override {
    return {{{body_extent_1d(p, n, reference).hi}, {bar_.traction(t)}}};  // outward normal +1: force = σ(l, t)
  }
  bool has_exact() const override { return true; }
  ExactState<1> exact(const std::array<double, 1>& X, double t) const override {
    return exact_1d(traction_bar_exact(bar_, X[0], t));
  }

 private:
  MaterialSpec mat_;
  TractionBar bar_;
};

/// A scene's own bodies with uniform initial velocity, and gravity.
template <int Dim>
class UserScene final : public Problem<Dim> {
 public:
  using Body = typename Problem<Dim>::Body;
  UserScene(const Scene& s) {
    for (const auto& b : s.bodies) {
      Body body;
      std::array<double, Dim> v;
      for (int d = 0; d < Dim; ++d) {
        body.lo[d] = b.lo[d];
        body.hi[d] = b.hi[d];
        v[d] = b.velocity[d];
      }
      body.material = b.material.value_or(s.material);
      body.velocity = [v](const std::array<double, Dim>&) { return v; };
      bodies_.push_back(body);
    }
    for (int d = 0; d < Dim; ++d) {
      gravity_[d] = s.gravity[d];
      has_gravity_ = has_gravity_ || s.gravity[d] != 0.0;
    }
  }
  std::vector<Body> bodies() const override { return bodies_; }
  bool has_body_force() const override { return has_gravity_; }
  BodyForce<Dim> body_force(double, BodyConstants<Dim>) const override {
    if (!has_gravity_) return NoBodyForce{};
    return UniformBodyForce<Dim>{gravity_};
  }

 private:
  std::vector<Body> bodies_;
  std::array<double, Dim> gravity_{};
  bool has_gravity_ = false;
};

}  // namespace

template <int Dim>
std::unique_ptr<Problem<Dim>> make_problem(const Scene& scene) {
  switch (scene.problem.name) {
    case ProblemName::none: return std::make_unique<UserScene<Dim>>(scene);
    case ProblemName::vibrating_bar:
      if constexpr (Dim == 1) return std::make_unique<VibratingBar>(scene);
      break;
    case ProblemName::column_compaction:
      if constexpr (Dim == 1) return std::make_unique<ColumnCompactionProblem>(scene);
      break;
    case ProblemName::vibrating_bar_traction:
      if constexpr (Dim == 1) return std::make_unique<VibratingBarTraction>(scene);
      break;
    case ProblemName::vibrating_plate:
      if constexpr (Dim == 2) return std::make_unique<VibratingPlate>(scene);
      break;
    default: break;
  }
  throw SceneError("scene: problem.name: this problem is not available in " + std::to_string(Dim) + "D yet");
}

template class Problem<1>;
template class Problem<2>;
template std::unique_ptr<Problem<1>> make_problem<1>(const Scene&);
template std::unique_ptr<Problem<2>> make_problem<2>(const Scene&);

}  // namespace mpm
