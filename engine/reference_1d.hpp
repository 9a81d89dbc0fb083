#pragma once
// Reference solutions for the 1D benchmarks (PROBLEMS.md): the column-compaction exact solution (thesis §5.4.2,
// derivation in docs/COLUMN_COMPACTION.md), the linear wave solution of the bar with a dynamic traction (thesis
// eq. 4.93) and an updated-Lagrangian finite-element solver (ULFEM, thesis §5.4.1 compares with one) for the
// large-deformation cases that have no closed form.
//
// Convention shared with the engine (1D uniaxial strain, unit cross-section): the stress σ(F) is the axis
// component of thesis eq. 2.13 or 2.14 with J = F, and forces are f_i = −Σ ∂φ_i/∂x σ V with V = F V0. Since
// ∂φ/∂x = (∂φ/∂X)/F, this is f_i = −Σ ∂φ_i/∂X σ V0: in 1D the Cauchy stress is also the first Piola stress
// (P = J σ F⁻ᵀ = σ) and the balance of momentum in the reference configuration reads ρ0 ü = ∂σ/∂X + ρ0 b.
// With the linear-elastic law σ = M (F − 1), M = λ + 2μ, that equation is linear in u for any deformation.
#include <functional>
#include <vector>

#include "engine/scene.hpp"

namespace mpm {

/// Displacement, velocity and (Cauchy = first Piola) stress at a reference position.
struct Fields1d {
  double u = 0, v = 0, sigma = 0;
};

/// P-wave (uniaxial-strain) modulus M = λ + 2μ; equals E for ν = 0.
double uniaxial_modulus(const MaterialSpec& m);
/// Stress of the engine's 1D law at stretch F (thesis eq. 2.13 or 2.14 with J = F).
double uniaxial_stress(const MaterialSpec& m, double F);
/// The stretch F > 0 with uniaxial_stress(m, F) = sigma (both laws are strictly increasing in F).
double uniaxial_stretch(const MaterialSpec& m, double sigma);

// ---------------------------------------------------------------------------------------------------------------
// Column compaction (PROBLEMS.md "column-compaction", thesis Table 5.6)

/// Column on 0 ≤ X ≤ H, fixed at X = 0, free at X = H, body force per unit mass b(t) = b_f min(t, t_f)/t_f.
struct ColumnCompaction {
  double height = 50.0;           ///< H, m
  double max_body_force = -200.0; ///< b_f, m/s²
  double ramp_time = 0.5;         ///< t_f, s
  MaterialSpec material{MaterialModel::linear_elastic, 1.0e6, 0.0, 1.0};
  int terms = 400;                ///< modal terms of the dynamic remainder (truncation ∝ terms⁻³ in u, ⁻² in v, σ)

  double body_force(double t) const;  ///< b(t)
};

/// Exact linear-elastic solution at reference position X and time t ≥ 0, any t (load constant after t_f):
/// the quasi-static part in closed form plus the modal series of the dynamic remainder (docs/COLUMN_COMPACTION.md,
/// eqs C5–C7). Exact for any strain: the reference-configuration equation is linear (see the header comment).
/// Linear elastic only (modulus M = λ + 2μ); throws std::invalid_argument for another material model.
Fields1d column_compaction_exact(const ColumnCompaction& c, double X, double t);
/// The textbook modal series u = Σ a_n β (t/ω_n² − sin(ω_n t)/ω_n³) sin(k_n X) (eq. C4), t ≤ t_f, summed
/// term by term with `terms` terms; converges slowly (σ error ~ 1/terms). For checking the closed form only.
Fields1d column_compaction_modal_series(const ColumnCompaction& c, double X, double t, int terms);

/// Static column under a constant body force b for the engine's 1D law of `m`: σ(X) = ρ0 b (H − X) (any law),
/// F = uniaxial_stretch(σ), u(X) = ∫_0^X (F − 1) dX' by Gauss–Legendre quadrature (eqs C1–C3).
struct StaticColumn {
  double u, sigma, F;
};
StaticColumn column_static(const MaterialSpec& m, double height, double body_force, double X);

// ---------------------------------------------------------------------------------------------------------------
// Bar with a dynamic traction at its free end (PROBLEMS.md "vibrating-bar-traction", thesis §4.6.2, eq. 4.93)

/// Bar on 0 ≤ X ≤ l, fixed at X = 0, traction τ(t) = −A sin(ωt) at X = l for 0 ≤ t < 4l/c (0 after), ω = πc/l.
/// Thesis values: l = 1, ρ0 = 100, E = 100 (c = 1 m/s, so its ω = π/l), A = 1 Pa; domain 1.25 m, T = 0.4 s.
struct TractionBar {
  double length = 1.0;        ///< l, m
  double density = 100.0;     ///< ρ0, kg/m³
  double modulus = 100.0;     ///< M = λ + 2μ (E for ν = 0), Pa
  double amplitude = 1.0;     ///< A, Pa

  double wave_speed() const;  ///< c = sqrt(M/ρ0)
  double traction(double t) const;  ///< τ(t), the stress prescribed at X = l
};
/// Linear-wave (small-strain) solution, thesis eq. 4.93 in d'Alembert form: σ = f(t − (l−X)/c) + f(t − (l+X)/c),
/// v = [f(t − (l−X)/c) − f(t − (l+X)/c)]/(ρ0 c), f(s) = −A sin(ωs) on [0, 2l/c). Exact for the linear-elastic
/// law at any strain; for the thesis' neo-Hookean bar only to first order in the strain A/E.
Fields1d traction_bar_exact(const TractionBar& b, double X, double t);

// ---------------------------------------------------------------------------------------------------------------
// Updated-Lagrangian FEM in 1D (the thesis' reference for Figs 5.12–5.13)

/// Linear elements, one-point quadrature, lumped mass, the engine's Euler–Cromer step (thesis eqs 2.26–2.27):
/// a^s = M_L⁻¹ f^s, v^{s+1} = v^s + Δt a^s, x^{s+1} = x^s + Δt v^{s+1}; forces at t^s. The last step is shortened
/// to land on `end`, as in the engine. Lengths per unit cross-section.
struct Ulfem1dSetup {
  double length = 1.0;                             ///< reference length, m; the bar is [0, length]
  int elements = 20;
  MaterialSpec material;
  double dt = 1e-4, end = 0.0;                     ///< s
  bool fix_left = true, fix_right = false;
  std::function<double(double t)> body_force;      ///< b(t) per unit mass, m/s²; empty: none
  std::function<double(double t)> right_traction;  ///< τ(t) at the right end, Pa (tension > 0); empty: none
  std::function<double(double X)> initial_velocity;  ///< v(X, 0); empty: at rest
};

enum class StressInterpolation {
  piecewise_constant,      ///< the element value (the FE field itself)
  linear_between_centres,  ///< linear through element centres, extrapolated linearly in the outer half-elements
};

struct Ulfem1dResult {
  std::vector<double> X, u, v;                 ///< nodes: reference position, displacement, velocity
  std::vector<double> element_X;               ///< element centres, reference configuration
  std::vector<double> element_F, element_stress;
  double time = 0;
  long steps = 0;

  double u_at(double X) const;  ///< linear between nodes
  double v_at(double X) const;  ///< linear between nodes
  double stress_at(double X, StressInterpolation how = StressInterpolation::linear_between_centres) const;
};

/// Runs the ULFEM to `end`. Throws std::invalid_argument for a bad set-up (dt above h/c in the reference
/// state, no elements, ...) and std::runtime_error naming the step and element if an element inverts (F ≤ 0)
/// or a value stops being finite.
Ulfem1dResult solve_ulfem_1d(const Ulfem1dSetup& setup);

/// Relative L2 difference sqrt(Σ (a_i − b_i)² / Σ b_i²), the measure of thesis Figs 5.12–5.14 (b: reference).
double relative_l2(const std::vector<double>& a, const std::vector<double>& b);

}  // namespace mpm
