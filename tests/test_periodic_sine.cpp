// The table-and-series sine of manufactured body forces (engine/periodic_sine.hpp), and the plate's body force it
// feeds, checked against the exact solution it was manufactured from.
#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <random>

#include "engine/periodic_sine.hpp"
#include "engine/problem.hpp"
#include "scene_builders.hpp"

using namespace mpm;

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
  for (const double t : {0.003, 0.0125}) {
    const BodyForce<2> force = problem->body_force(t, {X0.data(), X1.data()});
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
  // the scatter asks for batches (at_batch), the energy balance and the TLS right-hand side for one particle (at)
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
  const BodyForce<2> force = problem->body_force(0.007, {X0.data(), X1.data()});
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
