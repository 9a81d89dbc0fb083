#pragma once
// What a run measures on its particles, whatever carries the basis (a rectangular grid: Simulation; a triangle mesh:
// MeshSimulation): errors against an exact solution, energy, the critical time step, the body forces' power, the
// state a run resumes from, and the message of an unstable particle.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "engine/deterministic_sum.hpp"
#include "engine/material.hpp"
#include "engine/particle_store.hpp"
#include "engine/problem.hpp"
#include "engine/scene.hpp"
#include "kernels/isa.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

/// The run became unstable: the message names the step, particle, position and quantity.
struct UnstableRun : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Maximum relative differences between particle and grid totals after any P2G so far.
struct Conservation {
  double mass_rel_max = 0.0;
  double momentum_rel_max = 0.0;
};

/// RMS errors over particles against the exact solution (paper eq. 43), and the parts of the relative L2 errors of
/// thesis Figs 5.12–5.14: the error norm sqrt(Σ_p |f_p − f(X_p)|²) and the exact field's norm sqrt(Σ_p |f(X_p)|²).
/// The run divides the first by the largest second one so far (run.cpp): the exact field of a vibration passes
/// through zero, and an error relative to that instant's norm is then meaningless.
struct RunErrors {
  double displacement_rms = 0.0, velocity_rms = 0.0, stress_rms = 0.0;
  double displacement_l2 = 0.0, stress_l2 = 0.0;
  double displacement_exact_l2 = 0.0, stress_exact_l2 = 0.0;
};

struct Energy {
  double kinetic = 0.0, strain = 0.0;
  double total() const { return kinetic + strain; }
};

/// The explicit stability limit of a state, dt_crit = κ h_min / max_p (c(J_p) + |v_p|), and the particle that sets
/// it. One definition for the step chosen from `time.cfl`, the start-up check of `time.dt` and the per-step check.
/// κ = 1 with a lumped mass for the accelerations; less with the consistent mass (consistent_mass_step_factor).
struct CriticalStep {
  double dt = 0.0;          ///< s
  double kappa = 1.0;       ///< the mass matrix's factor κ
  double h = 0.0;           ///< smallest cell size, m
  std::size_t particle = 0;
  double wave_speed = 0.0;  ///< tangent P-wave speed c(J) at that particle, m/s
  double speed = 0.0;       ///< |v| of that particle, m/s
  double J = 1.0;
};

/// The consistent mass shortens the explicit step: on a uniform grid the highest frequency of M⁻¹K (Fourier
/// symbols of the 1D mass and stiffness stencils, maximised over the wave number) is ω_max h/c = 2√3 for P1, √10
/// for quadratic and 3.144 for cubic B-splines, against 2 for the lumped P1 mass that h/c stands for; a tensor
/// product adds the axes' ω². So κ = 2 / (ω_max h/c) / √dim. DDMPM has P1's mass matrix and smoother gradients,
/// max-ent has not been derived: both take P1's κ, the smallest. Measured on the plate of stability/plate.json
/// (2D): the unified approach runs at cfl 0.46 and stops at 0.5 (κ = 0.447), OTM-P1 runs at 0.40 and stops at
/// 0.44 (κ = 0.408).
inline double consistent_mass_step_factor(Basis basis, int dim) {
  const double omega_h_over_c = basis == Basis::bspline2 ? std::sqrt(10.0) : basis == Basis::bspline3 ? 3.1436 : 2.0 * std::sqrt(3.0);
  return 2.0 / omega_h_over_c / std::sqrt(static_cast<double>(dim));
}

/// How a critical step was computed, for messages.
inline std::string critical_step_formula(const CriticalStep& c) {
  if (c.kappa == 1.0) return "h/(c + |v|)";
  std::ostringstream f;
  f.precision(3);
  f << c.kappa << " h/(c + |v|) (consistent mass)";
  return f.str();
}


/// Everything that determines the rest of a run: particle columns (in storage order), clock and the running
/// conservation maxima. Restoring it and stepping on gives bitwise the same result as never having stopped.
struct SimulationState {
  long step = 0;
  double time = 0.0;
  Conservation conservation;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;
};


/// The time the velocity column stands for after `step` steps of dt ending at `time` (TimeStart): with the
/// staggered start, the midpoint of the last step, (time + dt (step - 1)) / 2, which is -dt/2 before the first.
inline double velocity_time(TimeStart start, long step, double time, double dt) {
  return start == TimeStart::staggered ? 0.5 * (time + dt * static_cast<double>(step - 1)) : time;
}

/// The staggered start (TimeStart): every particle takes the exact velocity at t = -dt/2.
template <int Dim>
void start_staggered(ParticleStore<Dim>& s, const Problem<Dim>& problem, double dt) {
  std::array<std::span<const double>, Dim> X;
  std::array<std::span<double>, Dim> v;
  for (int d = 0; d < Dim; ++d) {
    X[d] = s.column(Field::reference, d);
    v[d] = s.column(Field::velocity, d);
  }
  for (std::size_t p = 0; p < s.size(); ++p) {
    std::array<double, Dim> Xp;
    for (int d = 0; d < Dim; ++d) Xp[d] = X[d][p];
    const ExactState<Dim> ex = problem.exact(Xp, -0.5 * dt);
    for (int d = 0; d < Dim; ++d) v[d][p] = ex.v[d];
  }
}

/// Particles per call of Problem::exact_batch in particle_errors.
inline constexpr std::size_t exact_batch_size = 64;

/// RMS errors and L2 norms over the particles against the problem's exact solution at time t (paper eq. 43), the
/// velocity against it at `t_velocity` (velocity_time).
template <int Dim>
RunErrors particle_errors(const ParticleStore<Dim>& s, const Problem<Dim>& problem, double t, double t_velocity) {
  const std::size_t n = s.size();
  std::array<std::span<const double>, Dim> x, X, v;
  for (int d = 0; d < Dim; ++d) {
    x[d] = s.column(Field::position, d);
    X[d] = s.column(Field::reference, d);
    v[d] = s.column(Field::velocity, d);
  }
  std::array<std::span<const double>, sym_components<Dim>> sig;
  for (int c = 0; c < sym_components<Dim>; ++c) sig[c] = s.column(Field::stress, c);
  std::array<const double*, Dim> X_columns;
  for (int d = 0; d < Dim; ++d) X_columns[d] = X[d].data();
  // the exact solution at every particle is costly (the plate's: a log, table reads, and the sines of ωt, which a
  // batch forms once), so the particles are summed in parallel, in an order independent of the thread count
  constexpr std::size_t batch = exact_batch_size;
  const auto [eu, ev, es, nu, ns] = deterministic_batch_sums<5>(n, batch, [&](std::size_t first, std::size_t count) {
    ExactState<Dim> ex[batch], ex_v[batch];  // at t, and at t_velocity
    problem.exact_batch(t, X_columns, first, count, ex);
    if (t_velocity != t) problem.exact_batch(t_velocity, X_columns, first, count, ex_v);
    std::array<double, 5> e{};  // Σ|u − u_exact|², Σ|v − v_exact|², Σ|σ − σ_exact|², Σ|u_exact|², Σ|σ_exact|²
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t p = first + j;
      const std::array<double, Dim>& v_exact = t_velocity == t ? ex[j].v : ex_v[j].v;
      for (int d = 0; d < Dim; ++d) {
        e[0] += std::pow(x[d][p] - X[d][p] - ex[j].u[d], 2);
        e[3] += ex[j].u[d] * ex[j].u[d];
        e[1] += std::pow(v[d][p] - v_exact[d], 2);
      }
      for (int a = 0; a < Dim; ++a)
        for (int b = 0; b < Dim; ++b) {
          e[2] += std::pow(sig[sym_index<Dim>(a, b)][p] - ex[j].sigma[a * Dim + b], 2);
          e[4] += ex[j].sigma[a * Dim + b] * ex[j].sigma[a * Dim + b];
        }
    }
    return e;
  });
  return {std::sqrt(eu / n), std::sqrt(ev / n), std::sqrt(es / n), std::sqrt(eu), std::sqrt(es), std::sqrt(nu),
          std::sqrt(ns)};
}

/// Kinetic and strain energy of the particles, summed in an order independent of the thread count.
template <int Dim>
Energy particle_energy(const ParticleStore<Dim>& s, const Material& material) {
  Energy e;
  const auto m = s.column(Field::mass);
  const auto V0 = s.column(Field::volume0);
  std::array<std::span<const double>, Dim> v;
  std::array<std::span<const double>, Dim * Dim> F_col;
  for (int d = 0; d < Dim; ++d) v[d] = s.column(Field::velocity, d);
  for (int c = 0; c < Dim * Dim; ++c) F_col[c] = s.column(Field::deformation, c);
  e.kinetic = deterministic_sum(s.size(), [&](std::size_t p) {
    double v2 = 0;
    for (int d = 0; d < Dim; ++d) v2 += v[d][p] * v[d][p];
    return 0.5 * m[p] * v2;
  });
  e.strain = std::visit(
      [&](const auto& mat) {
        return deterministic_sum(s.size(), [&](std::size_t p) {
          double F[Dim * Dim];
          for (int c = 0; c < Dim * Dim; ++c) F[c] = F_col[c][p];
          return V0[p] * mat.template energy_density<Dim>(F);
        });
      },
      material);
  return e;
}

/// The critical step κ h / max_p (c(J_p) + |v_p|) of the particles (CriticalStep) for a smallest element size h.
template <int Dim>
CriticalStep critical_step_of(const ParticleStore<Dim>& s, const Material& material, double h, double kappa) {
  const auto m = s.column(Field::mass);
  const auto V0 = s.column(Field::volume0);
  CriticalStep out;
  out.h = h;
  out.kappa = kappa;
  // the fastest signal c(J) + |v| over particles; ties go to the lowest index, so the result (and the particle a
  // message names) does not depend on the thread count
  struct Fastest {
    double signal = -1.0;
    std::size_t p = 0;
  };
  const auto faster = [](const Fastest& a, const Fastest& b) {
    return b.signal > a.signal || (b.signal == a.signal && b.p < a.p) ? b : a;
  };
  const auto signal_of = [&](const auto& mat, std::size_t p, double& c, double& v, double& J) {
    double F[Dim * Dim], v2 = 0;
    for (int k = 0; k < Dim * Dim; ++k) F[k] = s.column(Field::deformation, k)[p];
    for (int d = 0; d < Dim; ++d) v2 += std::pow(s.column(Field::velocity, d)[p], 2);
    J = Dim == 1 ? F[0] : F[0] * F[3] - F[1] * F[2];
    c = mat.wave_speed(J, m[p] / V0[p]);
    v = std::sqrt(v2);
    return c + v;
  };
  std::visit(
      [&](const auto& mat) {
        const Fastest f = tbb::parallel_reduce(
            tbb::blocked_range<std::size_t>(0, s.size(), 4096), Fastest{},
            [&](const tbb::blocked_range<std::size_t>& r, Fastest acc) {
              double c, v, J;
              for (std::size_t p = r.begin(); p < r.end(); ++p) acc = faster(acc, {signal_of(mat, p, c, v, J), p});
              return acc;
            },
            faster);
        out.particle = f.p;
        signal_of(mat, f.p, out.wave_speed, out.speed, out.J);
      },
      material);
  out.dt = out.kappa * out.h / (out.wave_speed + out.speed);
  return out;
}

/// The reference-position columns, or nulls if the store has none.
template <int Dim>
std::array<const double*, Dim> reference_columns_of(const ParticleStore<Dim>& s) {
  std::array<const double*, Dim> X{};
  if (s.has(Field::reference))
    for (int d = 0; d < Dim; ++d) X[d] = s.column(Field::reference, d).data();
  return X;
}

/// The body force's constant columns, or nulls if the store has none.
template <int Dim>
BodyConstants<Dim> body_constants_of(const ParticleStore<Dim>& s) {
  BodyConstants<Dim> c{};
  if (s.has(Field::body_constants))
    for (int k = 0; k < 2 * Dim; ++k) c[k] = s.column(Field::body_constants, k).data();
  return c;
}

/// Forms the body force's constants from the reference positions, if the store keeps them: after seeding and after
/// loading a state, which does not hold them.
template <int Dim>
void form_body_constants(ParticleStore<Dim>& s, const Problem<Dim>& problem) {
  if (!s.has(Field::body_constants)) return;
  std::array<double*, 2 * Dim> out;
  for (int k = 0; k < 2 * Dim; ++k) out[k] = s.column(Field::body_constants, k).data();
  problem.form_body_constants(reference_columns_of(s), s.size(), out);
}

/// Power of the body forces on the particles, Σ_p m_p b_p(t)·v_p, W.
/// The force comes a batch of particles at a time (at_batch, in the active instruction set), as in the scatter:
/// particle by particle (at, with libm's log) the plate's power took twice the instructions (docs/PERFORMANCE.md).
template <int Dim>
double body_force_power(const ParticleStore<Dim>& s, const Problem<Dim>& problem, double t) {
  if (!problem.has_body_force()) return 0.0;
  const auto m = s.column(Field::mass);
  std::array<std::span<const double>, Dim> v;
  for (int d = 0; d < Dim; ++d) v[d] = s.column(Field::velocity, d);
  return std::visit(
      [&](const auto& force) {
        if constexpr (!std::decay_t<decltype(force)>::active) {
          return 0.0;
        } else {
          return deterministic_batch_sums<1>(s.size(), body_force_batch, [&](std::size_t first, std::size_t count) {
            unsigned index[body_force_batch];
            std::iota(index, index + count, static_cast<unsigned>(first));
            std::array<double, Dim> b[body_force_batch];
            with_active_isa([&](auto isa) { force.template at_batch<Dim, isa>(index, count, b); });
            std::array<double, 1> power{};
            for (std::size_t j = 0; j < count; ++j)
              for (int d = 0; d < Dim; ++d)
                power[0] += m[first + j] * b[j][d] * v[d][first + j];
            return power;
          })[0];
        }
      },
      problem.body_force(t, body_constants_of(s)));
}

/// A copy of every particle column with the clock and the conservation maxima.
template <int Dim>
SimulationState save_particle_state(const ParticleStore<Dim>& s, long step, double time, const Conservation& c) {
  SimulationState st;
  st.step = step;
  st.time = time;
  st.conservation = c;
  st.names = s.column_names();
  for (const auto& name : st.names) {
    const auto col = s.column(name);
    st.columns.emplace_back(col.begin(), col.end());
  }
  return st;
}

/// Copies a state's columns into the store, matched by name (a file may list them in another order), and forms the
/// body force's constants from them; throws std::invalid_argument if one is missing or has another particle count.
template <int Dim>
void load_particle_columns(ParticleStore<Dim>& s, const SimulationState& st, const Problem<Dim>& problem) {
  const auto names = s.column_names();
  std::vector<std::size_t> source(names.size());
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto it = std::find(st.names.begin(), st.names.end(), names[k]);
    if (it == st.names.end()) throw std::invalid_argument("state: column " + names[k] + " is missing");
    source[k] = it - st.names.begin();
    if (st.columns[source[k]].size() != s.size())
      throw std::invalid_argument("state: column " + names[k] + " has " + std::to_string(st.columns[source[k]].size()) +
                                  " values, this scene has " + std::to_string(s.size()) + " particles");
  }
  for (std::size_t k = 0; k < names.size(); ++k)
    std::copy(st.columns[source[k]].begin(), st.columns[source[k]].end(), s.column(names[k]).begin());
  form_body_constants(s, problem);
}

/// Throws UnstableRun naming the step, stage, particle, its position, J and velocity, and what went wrong
/// (`outside`: the particle left the `region`, "grid" or "mesh").
template <int Dim>
[[noreturn]] void raise_unstable_particle(const ParticleStore<Dim>& s, std::size_t p, long step, double t,
                                          const char* stage, bool outside, const char* region) {
  std::ostringstream msg;
  msg.precision(6);
  msg << "unstable at step " << step << " (t = " << t << " s), " << stage << ": particle " << p << " at x = (";
  for (int d = 0; d < Dim; ++d) msg << (d ? ", " : "") << s.column(Field::position, d)[p];
  double J = s.column(Field::deformation, 0)[p];
  if constexpr (Dim == 2)
    J = J * s.column(Field::deformation, 3)[p] - s.column(Field::deformation, 1)[p] * s.column(Field::deformation, 2)[p];
  msg << "), J = " << J << ", v = (";
  for (int d = 0; d < Dim; ++d) msg << (d ? ", " : "") << s.column(Field::velocity, d)[p];
  msg << ")";
  if (!std::isfinite(J)) msg << ": non-finite deformation";
  else if (!(J > 0)) msg << ": J <= 0";
  else if (outside) msg << ": left the " << region;
  else msg << ": non-finite value";
  throw UnstableRun(msg.str());
}

/// The time step of a scene: time.dt, checked against the critical step of the initial state, or time.cfl of it
/// (the same definition the per-step check of time.cfl uses, so a run at cfl < 1 does not fail its first check by
/// construction). Throws SceneError for a time.dt above the critical step.
inline double time_step_for(const Scene& scene, const CriticalStep& critical) {
  if (scene.time.cfl) return *scene.time.cfl * critical.dt;
  const double dt = *scene.time.dt;
  if (dt > critical.dt) {
    std::ostringstream msg;
    msg << "scene: time.dt = " << dt << ": expected at most the critical step " << critical_step_formula(critical)
        << " = " << critical.dt << " s of the initial state (cell size " << critical.h << " m; particle "
        << critical.particle << ": wave speed " << critical.wave_speed << " m/s, |v| = " << critical.speed
        << " m/s); use a smaller time.dt or time.cfl";
    throw SceneError(msg.str());
  }
  return dt;
}

/// Steps to time.end: end / dt, rounded when within round-off of an integer, else the last step is shorter.
inline long count_steps(const Scene& scene, double dt) {
  const double n = scene.time.end / dt;
  const long rounded = std::lround(n);
  return std::abs(n - rounded) < 1e-9 * std::max(1.0, n) ? std::max(1L, rounded) : static_cast<long>(std::ceil(n));
}

/// The particle columns a run needs: the state; the reference position where an exact solution, a body force's
/// constants or a basis that moves with the body read it; the body force's constants.
template <int Dim>
FieldSet needed_fields(const Problem<Dim>& problem, Update update) {
  FieldSet f;
  f.add(Field::position).add(Field::velocity).add(Field::deformation).add(Field::stress);
  f.add(Field::mass).add(Field::volume0);
  if (problem.has_exact() || problem.body_force_has_constants() || basis_moves_with_body(update))
    f.add(Field::reference);
  if (problem.body_force_has_constants()) f.add(Field::body_constants);
  return f;
}

/// One constitutive law per run (resolved once per step): bodies may differ in density only. Throws SceneError.
template <int Dim>
void check_body_materials(const Scene& scene, const std::vector<typename Problem<Dim>::Body>& bodies) {
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const MaterialSpec& m = bodies[b].material;
    if (m.model != scene.material.model || m.E != scene.material.E || m.nu != scene.material.nu)
      throw SceneError("scene: bodies." + std::to_string(b) +
                       ".material: expected the scene's model, E and nu (bodies may differ in density only)");
  }
}

/// Particles of every body: positions, reference volume, mass, velocity.
template <int Dim>
struct Seeds {
  std::vector<std::array<double, Dim>> x;
  std::vector<double> V0, m;
  std::vector<std::array<double, Dim>> v;
};

/// The particle store of the seeds, with the columns the problem and update need (needed_fields), at rest in the
/// reference state (F = I, σ = 0 for both laws). Throws SceneError if there are none.
template <int Dim>
ParticleStore<Dim> store_from_seeds(const Seeds<Dim>& seeds, const Problem<Dim>& problem, Update update) {
  const std::size_t n = seeds.x.size();
  if (n == 0) throw SceneError("scene: bodies: no particle falls inside any body");
  ParticleStore<Dim> store(n, needed_fields(problem, update));
  auto pv = store.view();
  for (std::size_t p = 0; p < n; ++p) {
    for (int d = 0; d < Dim; ++d) {
      pv.x[d][p] = seeds.x[p][d];
      pv.v[d][p] = seeds.v[p][d];
      if (pv.X[d]) store.column(Field::reference, d)[p] = seeds.x[p][d];
    }
    for (int a = 0; a < Dim; ++a) pv.F[a * Dim + a][p] = 1.0;
    store.column(Field::mass)[p] = seeds.m[p];
    store.column(Field::volume0)[p] = seeds.V0[p];
  }
  form_body_constants(store, problem);
  return store;
}

}  // namespace mpm
