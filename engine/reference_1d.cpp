#include "engine/reference_1d.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <variant>

#include "engine/material.hpp"

namespace mpm {

using std::numbers::pi;

// ---------------------------------------------------------------------------------------------------------------
// 1D material law

double uniaxial_modulus(const MaterialSpec& m) {
  const Lame k = Lame::from(m);
  return k.lambda + 2 * k.mu;
}

double uniaxial_stress(const MaterialSpec& m, double F) {
  double s = 0.0;
  std::visit([&](const auto& law) { law.template stress<1>(&F, &s); }, make_material(m));
  return s;
}

namespace {

/// dσ/dF of the 1D laws: M (eq. 2.13); λ(1 − ln F)/F² + μ(1 + 1/F²) (eq. 2.14 with J = F).
double uniaxial_tangent(const MaterialSpec& m, double F) {
  const Lame k = Lame::from(m);
  if (m.model == MaterialModel::linear_elastic) return k.lambda + 2 * k.mu;
  return k.lambda * (1 - std::log(F)) / (F * F) + k.mu * (1 + 1 / (F * F));
}

}  // namespace

double uniaxial_stretch(const MaterialSpec& m, double sigma) {
  const double M = uniaxial_modulus(m);
  if (m.model == MaterialModel::linear_elastic) return 1.0 + sigma / M;
  // bracket the root (σ → −∞ as F → 0⁺, σ → +∞ as F → ∞), then Newton safeguarded by bisection
  double lo = 1.0, hi = 1.0;
  while (uniaxial_stress(m, lo) > sigma) lo *= 0.5;
  while (uniaxial_stress(m, hi) < sigma) hi *= 2.0;
  double F = std::clamp(1.0 + sigma / M, lo, hi);
  for (int it = 0; it < 200; ++it) {
    const double r = uniaxial_stress(m, F) - sigma;
    if (r == 0.0) break;
    (r < 0 ? lo : hi) = F;
    double next = F - r / uniaxial_tangent(m, F);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - F) <= 1e-16 * F) return next;
    F = next;
  }
  return F;
}

// ---------------------------------------------------------------------------------------------------------------
// Column compaction (docs/COLUMN_COMPACTION.md)

double ColumnCompaction::body_force(double t) const { return max_body_force * std::min(t, ramp_time) / ramp_time; }

namespace {

void require_linear(const ColumnCompaction& c) {
  if (c.material.model != MaterialModel::linear_elastic)
    throw std::invalid_argument("column compaction: the exact dynamic solution needs a linear-elastic material");
}

}  // namespace

Fields1d column_compaction_exact(const ColumnCompaction& c, double X, double t) {
  require_linear(c);
  const double H = c.height, rho0 = c.material.density, M = uniaxial_modulus(c.material);
  const double cw = std::sqrt(M / rho0), beta = c.max_body_force / c.ramp_time;
  const double w = H * X - 0.5 * X * X;  // Σ a_n sin(k_n X)/k_n² = H X − X²/2 (eq. C5)
  const bool loading = t < c.ramp_time;
  Fields1d f;
  // quasi-static part: the static solution under the current load b(min(t, t_f)) (eqs C1–C2, C5)
  f.u = rho0 * c.body_force(t) * w / M;
  f.v = loading ? beta * w / (cw * cw) : 0.0;
  f.sigma = rho0 * c.body_force(t) * (H - X);
  // dynamic remainder, D_n(t) = −(a_n β/ω_n³)[sin ω_n t − 𝟙(t > t_f) sin ω_n (t − t_f)] (eq. C6)
  for (int n = 1; n <= c.terms; ++n) {
    const double k = (2 * n - 1) * pi / (2 * H), om = cw * k, a = 2 / (H * k);
    double S = std::sin(om * t), C = std::cos(om * t);
    if (!loading) {
      S -= std::sin(om * (t - c.ramp_time));
      C -= std::cos(om * (t - c.ramp_time));
    }
    const double D = -a * beta * S / (om * om * om), Ddot = -a * beta * C / (om * om);
    f.u += D * std::sin(k * X);
    f.v += Ddot * std::sin(k * X);
    f.sigma += M * D * k * std::cos(k * X);  // σ = M ∂u/∂X (eq. C7)
  }
  return f;
}

Fields1d column_compaction_modal_series(const ColumnCompaction& c, double X, double t, int terms) {
  require_linear(c);
  const double H = c.height, M = uniaxial_modulus(c.material);
  const double cw = std::sqrt(M / c.material.density), beta = c.max_body_force / c.ramp_time;
  Fields1d f;
  for (int n = 1; n <= terms; ++n) {  // eq. C4
    const double k = (2 * n - 1) * pi / (2 * H), om = cw * k, a = 2 / (H * k);
    const double q = a * beta * (t / (om * om) - std::sin(om * t) / (om * om * om));
    const double qdot = a * beta * (1 - std::cos(om * t)) / (om * om);
    f.u += q * std::sin(k * X);
    f.v += qdot * std::sin(k * X);
    f.sigma += M * q * k * std::cos(k * X);
  }
  return f;
}

StaticColumn column_static(const MaterialSpec& m, double height, double body_force, double X) {
  const auto sigma = [&](double Y) { return m.density * body_force * (height - Y); };  // eq. C1
  // u(X) = ∫_0^X (F(σ(Y)) − 1) dY (eq. C2): 5-point Gauss–Legendre on 32 panels; the integrand is analytic
  static constexpr double gx[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
                                   0.9061798459386640};
  static constexpr double gw[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665,
                                   0.2369268850561891, 0.2369268850561891};
  constexpr int panels = 32;
  const double len = X / panels;
  double u = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double mid = (p + 0.5) * len;
    for (int g = 0; g < 5; ++g) u += 0.5 * len * gw[g] * (uniaxial_stretch(m, sigma(mid + 0.5 * len * gx[g])) - 1.0);
  }
  return {u, sigma(X), uniaxial_stretch(m, sigma(X))};
}

// ---------------------------------------------------------------------------------------------------------------
// Bar with a dynamic traction (thesis eq. 4.93)

double TractionBar::wave_speed() const { return std::sqrt(modulus / density); }

namespace {

/// The incoming stress pulse f(s) = −A sin(ωs) on [0, 2l/c) and its integral ∫_0^s f.
struct TractionPulse {
  double A, omega, duration;
  double f(double s) const { return s >= 0 && s < duration ? -A * std::sin(omega * s) : 0.0; }
  double integral(double s) const { return s >= 0 && s < duration ? A * (std::cos(omega * s) - 1) / omega : 0.0; }
};

TractionPulse pulse_of(const TractionBar& b) {
  const double c = b.wave_speed();
  return {b.amplitude, pi * c / b.length, 2 * b.length / c};
}

}  // namespace

double TractionBar::traction(double t) const {
  const TractionPulse p = pulse_of(*this);
  return p.f(t) + p.f(t - p.duration);  // σ(l, t): the pulse and its reflection from the fixed end
}

Fields1d traction_bar_exact(const TractionBar& b, double X, double t) {
  const TractionPulse p = pulse_of(b);
  const double c = b.wave_speed(), z = b.density * c;  // z: impedance
  const double s_in = t - (b.length - X) / c, s_ref = t - (b.length + X) / c;
  return {(p.integral(s_in) - p.integral(s_ref)) / z, (p.f(s_in) - p.f(s_ref)) / z, p.f(s_in) + p.f(s_ref)};
}

// ---------------------------------------------------------------------------------------------------------------
// ULFEM

namespace {

/// Steps to reach `end` with step dt; the engine's rule (the last step is shortened if dt does not divide end).
long count_steps(double end, double dt) {
  if (end <= 0) return 0;
  const double n = end / dt;
  const long rounded = std::lround(n);
  return std::abs(n - rounded) < 1e-9 * std::max(1.0, n) ? std::max(1L, rounded) : static_cast<long>(std::ceil(n));
}

[[noreturn]] void bad_setup(const std::string& what, double value, const std::string& expected) {
  std::ostringstream msg;
  msg << "ulfem: " << what << " = " << value << ": expected " << expected;
  throw std::invalid_argument(msg.str());
}

/// Refuses a set-up the solver cannot run, naming the value and what was expected.
void check_setup(const Ulfem1dSetup& s) {
  if (!(s.length > 0)) bad_setup("length", s.length, "> 0");
  if (s.elements < 1) bad_setup("elements", s.elements, ">= 1");
  if (!(s.material.density > 0) || !(s.material.E > 0)) bad_setup("material.E or density", s.material.E, "> 0");
  if (!(s.end >= 0)) bad_setup("end", s.end, ">= 0");
  const double h = s.length / s.elements, c0 = std::sqrt(uniaxial_modulus(s.material) / s.material.density);
  if (!(s.dt > 0) || s.dt > h / c0 * (1 + 1e-12)) {
    std::ostringstream bound;
    bound << "in (0, h/c] = (0, " << h / c0 << "] (the critical step of the reference state)";
    bad_setup("dt", s.dt, bound.str());
  }
}

}  // namespace

Ulfem1dResult solve_ulfem_1d(const Ulfem1dSetup& s) {
  check_setup(s);
  const int ne = s.elements;
  const double h = s.length / ne;

  const std::size_t nn = ne + 1;
  std::vector<double> X(nn), x(nn), v(nn, 0.0), m(nn, 0.0), f(nn);
  for (std::size_t i = 0; i < nn; ++i) {
    X[i] = s.length * static_cast<double>(i) / ne;
    x[i] = X[i];
    if (s.initial_velocity) v[i] = s.initial_velocity(X[i]);
  }
  for (int e = 0; e < ne; ++e) {  // lumped mass, thesis eq. 2.24: M_ii = ∫ φ_i ρ dΩ = ρ0 h/2 per element end
    m[e] += 0.5 * s.material.density * h;
    m[e + 1] += 0.5 * s.material.density * h;
  }
  const auto fixed = [&](std::size_t i) { return (i == 0 && s.fix_left) || (i == nn - 1 && s.fix_right); };
  for (std::size_t i = 0; i < nn; ++i)
    if (fixed(i)) v[i] = 0.0;

  // F_e from the current nodes: for linear elements the updated-Lagrangian increment F ← (1 + Δt ∂v/∂x) F
  // (thesis eq. 2.41) telescopes to this exactly, so updated and total Lagrangian agree in 1D.
  const auto stretch = [&](int e, long step) {
    const double F = (x[e + 1] - x[e]) / h;
    if (!(F > 0) || !std::isfinite(F)) {
      std::ostringstream msg;
      msg << "ulfem: element " << e << " has F = " << F << " at step " << step << " (inverted or unstable)";
      throw std::runtime_error(msg.str());
    }
    return F;
  };

  const Material law = make_material(s.material);
  const auto stress = [&law](double F) {
    double sig = 0.0;
    std::visit([&](const auto& l) { l.template stress<1>(&F, &sig); }, law);
    return sig;
  };

  const long steps = count_steps(s.end, s.dt);
  double t = 0.0;
  for (long n = 0; n < steps; ++n) {
    const double dt = n + 1 == steps ? s.end - s.dt * static_cast<double>(n) : s.dt;
    // f_i = −Σ_e ∂φ_i/∂x σ_e V_e with ∂φ/∂x = ∓1/(F h), V_e = F h (eq. 2.21, one-point quadrature)
    std::fill(f.begin(), f.end(), 0.0);
    for (int e = 0; e < ne; ++e) {
      const double sig = stress(stretch(e, n));
      f[e] += sig;
      f[e + 1] -= sig;
    }
    const double b = s.body_force ? s.body_force(t) : 0.0;  // ∫ φ_i ρ b dΩ = M_ii b (eq. 2.21)
    if (s.right_traction) f[nn - 1] += s.right_traction(t);  // ∫ φ_i τ dΓ (eq. 2.21): unit area, unchanged in 1D
    for (std::size_t i = 0; i < nn; ++i) {
      const double a = fixed(i) ? 0.0 : f[i] / m[i] + b;  // eq. 2.19 with the lumped mass
      v[i] += dt * a;  // eq. 2.26
      x[i] += dt * v[i];  // eq. 2.27
    }
    t = n + 1 == steps ? s.end : s.dt * static_cast<double>(n + 1);
  }

  Ulfem1dResult r;
  r.X = X;
  r.v = v;
  r.u.resize(nn);
  for (std::size_t i = 0; i < nn; ++i) r.u[i] = x[i] - X[i];
  for (int e = 0; e < ne; ++e) {
    r.element_X.push_back(0.5 * (X[e] + X[e + 1]));
    r.element_F.push_back(stretch(e, steps));
    r.element_stress.push_back(stress(r.element_F.back()));
  }
  r.time = t;
  r.steps = steps;
  return r;
}

namespace {

/// Element index and local coordinate ξ ∈ [0, 1] of X on the uniform reference mesh (clamped to the bar).
std::pair<std::size_t, double> locate(const std::vector<double>& nodes, double X) {
  const std::size_t ne = nodes.size() - 1;
  const double h = (nodes.back() - nodes.front()) / static_cast<double>(ne);
  const double q = std::clamp((X - nodes.front()) / h, 0.0, static_cast<double>(ne));
  const std::size_t e = std::min(static_cast<std::size_t>(q), ne - 1);
  return {e, q - static_cast<double>(e)};
}

double linear(const std::vector<double>& nodes, const std::vector<double>& values, double X) {
  const auto [e, xi] = locate(nodes, X);
  return (1 - xi) * values[e] + xi * values[e + 1];
}

}  // namespace

double Ulfem1dResult::u_at(double Xq) const { return linear(X, u, Xq); }
double Ulfem1dResult::v_at(double Xq) const { return linear(X, v, Xq); }

double Ulfem1dResult::stress_at(double Xq, StressInterpolation how) const {
  const std::size_t ne = element_stress.size();
  if (how == StressInterpolation::piecewise_constant || ne == 1) return element_stress[locate(X, Xq).first];
  const double h = (X.back() - X.front()) / static_cast<double>(ne);
  const double q = (Xq - element_X.front()) / h;  // in element-centre spacings
  const std::size_t j = static_cast<std::size_t>(std::clamp(std::floor(q), 0.0, static_cast<double>(ne - 2)));
  const double w = q - static_cast<double>(j);  // < 0 or > 1 in the outer half-elements: linear extrapolation
  return (1 - w) * element_stress[j] + w * element_stress[j + 1];
}

double relative_l2(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size() || b.empty()) throw std::invalid_argument("relative_l2: sizes differ or are zero");
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - b[i]) * (a[i] - b[i]);
    den += b[i] * b[i];
  }
  if (den == 0.0) throw std::invalid_argument("relative_l2: the reference is zero");
  return std::sqrt(num / den);
}

}  // namespace mpm
