// The table-and-series sine of manufactured solutions (engine/periodic_sine.hpp); the plate's body force it feeds,
// checked against the exact solution it was manufactured from; and the batched sums that evaluate the force and the
// exact solution (the energy guard's power, the errors) against plain sums particle by particle.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/periodic_sine.hpp"
#include "engine/problem.hpp"
#include "engine/simulation.hpp"
#include "scene_builders.hpp"

using namespace mpm;

namespace {

/// The plate's body constants (Problem::form_body_constants) at the reference positions X0, X1.
struct PlateConstants {
  std::array<std::vector<double>, 4> columns;
  PlateConstants(const Problem<2>& problem, const std::vector<double>& X0, const std::vector<double>& X1) {
    for (auto& c : columns) c.resize(X0.size());
    problem.form_body_constants({X0.data(), X1.data()}, X0.size(),
                                {columns[0].data(), columns[1].data(), columns[2].data(), columns[3].data()});
  }
  BodyConstants<2> view() const { return {columns[0].data(), columns[1].data(), columns[2].data(), columns[3].data()}; }
};

}  // namespace

TEST_CASE("the periodic sine table agrees with libm's sin and cos to round-off", "[body-force]") {
  for (const double L : {1.0, 0.37, 25.0}) {
    const PeriodicSine trig(L);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(0.0, L);
    double worst = 0.0;
    for (int n = 0; n < 200000; ++n) {
      const double x = n < 2 ? n * L : u(rng);  // both ends, then anywhere
      const auto [s, c] = trig(x);
      const double kx = 2 * std::numbers::pi / L * x;
      worst = std::max({worst, std::abs(s - std::sin(kx)), std::abs(c - std::cos(kx))});
    }
    INFO("L = " << L << ": largest difference " << worst);
    // both round the argument k x (libm's as one product, the table's remainder k (x − x_i)) by up to half an ulp
    // of 2π each, and their results (magnitude ≤ 1) by an ulp or two
    const double ulp_2pi = std::nextafter(2 * std::numbers::pi, 7.0) - 2 * std::numbers::pi;
    CHECK(worst <= 2 * ulp_2pi + 2 * std::numeric_limits<double>::epsilon());
  }
}

TEST_CASE("the plate's body force balances its exact solution", "[body-force]") {
  // b_d = ü_d − (1/ρ₀) ∂P_dd/∂X_d (the plate's F is diagonal, P_dd = J σ_dd / F_dd), by central differences of the
  // exact solution in t and X; truncation of the differences ~1e-7 of the force
  const Scene scene = parse_scene(test::plate_scene(8, 0.05));
  const auto problem = make_problem<2>(scene);
  const double rho0 = scene.material.density;
  const auto P = [&](const std::array<double, 2>& X, double t, int d) {  // P_dd, with F from differences of u
    const double dX = 1e-6;
    double J = 1.0, F_dd = 1.0;
    for (int e = 0; e < 2; ++e) {
      std::array<double, 2> a = X, b = X;
      a[e] -= dX;
      b[e] += dX;
      const double F_ee = 1 + (problem->exact(b, t).u[e] - problem->exact(a, t).u[e]) / (2 * dX);
      J *= F_ee;
      if (e == d) F_dd = F_ee;
    }
    return J * problem->exact(X, t).sigma[d * 3] / F_dd;
  };
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> X0(500), X1(500);
  for (std::size_t p = 0; p < X0.size(); ++p) {
    X0[p] = u(rng);
    X1[p] = u(rng);
  }
  const PlateConstants constants(*problem, X0, X1);
  for (const double t : {0.003, 0.0125}) {
    const BodyForce<2> force = problem->body_force(t, constants.view());
    const auto& plate = std::get<PlateBodyForce>(force);
    double worst = 0.0, scale = 0.0;
    for (std::size_t p = 0; p < X0.size(); ++p) {
      const std::array<double, 2> X{X0[p], X1[p]};
      const auto b = plate.at<2>(p);
      for (int d = 0; d < 2; ++d) {
        const double dt = 1e-7, dX = 1e-4;
        const double udd = (problem->exact(X, t + dt).v[d] - problem->exact(X, t - dt).v[d]) / (2 * dt);
        std::array<double, 2> a = X, c = X;
        a[d] -= dX;
        c[d] += dX;
        const double div_P = (P(c, t, d) - P(a, t, d)) / (2 * dX);
        worst = std::max(worst, std::abs(b[d] - (udd - div_P / rho0)));
        scale = std::max(scale, std::abs(b[d]));
      }
    }
    INFO("t = " << t << ": largest difference " << worst << " of forces up to " << scale);
    CHECK(worst <= 1e-6 * scale);
  }
}

TEST_CASE("the plate's body force for a batch of particles equals it particle by particle", "[body-force]") {
  // the scatter and the energy balance ask for batches (at_batch), the TLS right-hand side for one particle (at)
  const Scene scene = parse_scene(test::plate_scene(8, 0.05));
  const auto problem = make_problem<2>(scene);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.01, 1.01);  // a little outside the body too
  std::vector<double> X0(200), X1(200);
  std::vector<unsigned> order(200);
  for (std::size_t p = 0; p < X0.size(); ++p) {
    X0[p] = u(rng);
    X1[p] = u(rng);
    order[p] = static_cast<unsigned>(p);
  }
  std::shuffle(order.begin(), order.end(), rng);
  const PlateConstants constants(*problem, X0, X1);
  const BodyForce<2> force = problem->body_force(0.007, constants.view());
  const auto& plate = std::get<PlateBodyForce>(force);
  for (const std::size_t count : {std::size_t{1}, std::size_t{7}, body_force_batch}) {
    std::array<double, 2> batch[body_force_batch];
    plate.at_batch<2>(order.data() + 3, count, batch);
    for (std::size_t j = 0; j < count; ++j) {
      const auto single = plate.at<2>(order[3 + j]);
      INFO("batch of " << count << ", entry " << j);
      CHECK(batch[j][0] == single[0]);
      CHECK(batch[j][1] == single[1]);
    }
  }
}

TEST_CASE("the body forces' power of a plate run equals its sum particle by particle", "[body-force]") {
  // Simulation::external_power takes the force in batches (at_batch, the active instruction set's log); here the
  // plain sum of m_p b_p·v_p with the force of one particle at a time (at, libm's log)
  const Scene scene = parse_scene(test::plate_scene(8, 0.05));
  Simulation<2> sim(scene);
  for (int n = 0; n < 5; ++n) sim.step();  // the velocities of the run, not only the exact initial ones
  const auto& s = sim.particles();
  const auto problem = make_problem<2>(scene);
  const BodyForce<2> force = problem->body_force(sim.time(), body_constants_of(s));
  const auto& plate = std::get<PlateBodyForce>(force);
  long double sum = 0, scale = 0;
  for (std::size_t p = 0; p < s.size(); ++p) {
    const auto b = plate.at<2>(p);
    for (int d = 0; d < 2; ++d) {
      const long double term = s.column(Field::mass)[p] * b[d] * s.column(Field::velocity, d)[p];
      sum += term;
      scale += std::abs(term);
    }
  }
  INFO("power " << sim.external_power() << " W, particle by particle " << static_cast<double>(sum) << " W");
  REQUIRE(scale > 0);
  CHECK(std::abs(sim.external_power() - static_cast<double>(sum)) <= 1e-13 * static_cast<double>(scale));
}

TEST_CASE("a plate run's errors equal their sums particle by particle", "[body-force]") {
  // particle_errors takes the exact solution in batches (Problem::exact_batch, the plate's sines of ωt formed once
  // per batch); here the plain sums with the exact solution at one particle at a time. The staggered start compares
  // the velocities at another time than the rest (velocity_time), which a batch evaluates separately.
  for (const char* start : {"collocated", "staggered"}) {
    nlohmann::json j = test::plate_scene(8, 0.05);
    j["time"]["start"] = start;
    const Scene scene = parse_scene(j);
    Simulation<2> sim(scene);
    for (int n = 0; n < 5; ++n) sim.step();
    const auto& s = sim.particles();
    const auto problem = make_problem<2>(scene);
    const double t = sim.time(), t_v = velocity_time(scene.time.start, sim.steps_done(), t, sim.dt());
    long double eu = 0, ev = 0, es = 0;
    for (std::size_t p = 0; p < s.size(); ++p) {
      const std::array<double, 2> X{s.column(Field::reference, 0)[p], s.column(Field::reference, 1)[p]};
      const ExactState<2> ex = problem->exact(X, t), ex_v = problem->exact(X, t_v);
      for (int d = 0; d < 2; ++d) {
        eu += std::pow(s.column(Field::position, d)[p] - X[d] - ex.u[d], 2);
        ev += std::pow(s.column(Field::velocity, d)[p] - ex_v.v[d], 2);
      }
      for (int a = 0; a < 2; ++a)
        for (int b = 0; b < 2; ++b)
          es += std::pow(s.column(Field::stress, sym_index<2>(a, b))[p] - ex.sigma[a * 2 + b], 2);
    }
    const RunErrors e = sim.errors();
    const auto rms = [&](long double sum) { return static_cast<double>(std::sqrt(sum / s.size())); };
    INFO(start << ": u RMS " << e.displacement_rms << " against " << rms(eu) << ", v RMS " << e.velocity_rms
               << " against " << rms(ev) << ", σ RMS " << e.stress_rms << " against " << rms(es));
    CHECK(e.displacement_rms == Approx(rms(eu)).epsilon(1e-13));
    CHECK(e.velocity_rms == Approx(rms(ev)).epsilon(1e-13));
    CHECK(e.stress_rms == Approx(rms(es)).epsilon(1e-13));
  }
}

TEST_CASE("the plate's body constants follow their particles through a reordering and a loaded state",
          "[body-force]") {
  // the constants are columns of the store (Field::body_constants), permuted with the rest, and formed afresh from X
  // when a state is loaded: a state (outputs, checkpoints) does not hold them
  const Scene scene = parse_scene(test::plate_scene(8, 0.05));
  const double k = 2 * std::numbers::pi / scene.grid.length[0];
  const auto wrong_constants = [&](const ParticleStore<2>& s) {
    const BodyConstants<2> c = body_constants_of(s);
    std::size_t wrong = 0;
    for (std::size_t p = 0; p < s.size(); ++p)
      for (int d = 0; d < 2; ++d) {
        const double kX = k * s.column(Field::reference, d)[p];
        wrong += c[2 * d][p] != std::sin(kX) || c[2 * d + 1][p] != std::cos(kX);
      }
    return wrong;
  };
  Simulation<2> sim(scene);
  sim.step();  // the first step permutes the particles into block order
  CHECK(wrong_constants(sim.particles()) == 0);
  const auto names = sim.particles().column_names();
  CHECK(std::find(names.begin(), names.end(), "body0") == names.end());
  Simulation<2> resumed(scene);  // its particles in the seeds' order
  resumed.load_state(sim.save_state());
  CHECK(wrong_constants(resumed.particles()) == 0);
}
