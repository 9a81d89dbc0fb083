// Runs on a triangle mesh (thesis §3.3, §6.1.2, §6.3.1): the P1 basis, the TLS fit of one triangle, and the
// plate with MPM-P1, MPM-TLS and PS-MPM against its exact solution: conservation, thread-count independence,
// convergence, and the scenes the mesh refuses.
#include <algorithm>
#include <cmath>
#include <tuple>
#include <random>
#include <string>

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include "engine/consistent_mass.hpp"
#include "engine/mesh_mass_matrix.hpp"
#include "engine/mesh_simulation.hpp"
#include "engine/triangle_tls.hpp"

using namespace mpm;
using Catch::Matchers::Contains;

namespace {

std::string mesh_file(const std::string& name) { return std::string(MPM_SOURCE_DIR) + "/tools/meshes/" + name; }

/// The vibrating plate of thesis §3.4.1 / §6.3.1 (E = 1e4 kPa, ν = 0.3, ρ = 1000, A = 0.05) on a mesh.
nlohmann::json plate_on_mesh(const std::string& mesh, const std::string& basis, const std::string& mapping,
                             const std::string& update, int per_triangle, double dt, double end,
                             const std::string& mass = "lumped") {
  return {{"dimension", 2},
          {"problem", {{"name", "vibrating-plate"}, {"amplitude", 0.05}}},
          {"grid", {{"length", {1.0, 1.0}}, {"mesh", mesh_file(mesh)}, {"basis", basis}}},
          {"particles", {{"per_cell", {per_triangle}}}},
          {"material", {{"model", "neo-hookean"}, {"E", 1e7}, {"nu", 0.3}, {"density", 1000.0}}},
          {"algorithm", {{"update", update}, {"mapping", mapping}, {"mass", mass}}},
          {"time", {{"dt", dt}, {"end", end}}}};
}

void run_to_end(MeshSimulation& sim) {
  while (!sim.finished()) sim.step();
}

std::vector<std::vector<double>> columns_after(const nlohmann::json& scene, int steps, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  MeshSimulation sim(parse_scene(scene));
  for (int s = 0; s < steps; ++s) sim.step();
  std::vector<std::vector<double>> cols;
  for (const auto& name : sim.particles().column_names()) {
    const auto c = sim.particles().column(name);
    cols.emplace_back(c.begin(), c.end());
  }
  return cols;
}

}  // namespace

TEST_CASE("P1 basis on an unstructured mesh - partition of unity and linear reproduction", "[mesh-sim]") {
  const TriangleMesh mesh = make_jittered_mesh({2.0, 1.0}, 7, 5, 0.25, 11);
  const TriangleP1 basis(mesh);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(0.0, 2.0), uy(0.0, 1.0);
  std::array<int, 3> idx;
  std::array<double, 3> w;
  std::array<Point2, 3> g;
  for (int k = 0; k < 2000; ++k) {
    const Point2 x{ux(rng), uy(rng)};
    const int e = mesh.locate(x);
    REQUIRE(e >= 0);
    REQUIRE(mesh.locate(x, k % static_cast<int>(mesh.triangle_count())) == e);  // any hint: the same answer
    basis.evaluate(e, x, idx, w, g);
    double sum = 0, gsum[2] = {0, 0};
    Point2 rx{0, 0};
    double grad_x[2][2] = {{0, 0}, {0, 0}};  // ∇(Σ φ_i x_i) per component
    for (int i = 0; i < 3; ++i) {
      sum += w[i];
      const Point2& xi = mesh.nodes()[idx[i]];
      for (int d = 0; d < 2; ++d) {
        rx[d] += w[i] * xi[d];
        gsum[d] += g[i][d];
        for (int c = 0; c < 2; ++c) grad_x[d][c] += xi[d] * g[i][c];
      }
    }
    REQUIRE(std::abs(sum - 1) <= 1e-14);
    REQUIRE(std::abs(rx[0] - x[0]) <= 1e-14);
    REQUIRE(std::abs(rx[1] - x[1]) <= 1e-14);
    for (int d = 0; d < 2; ++d) {
      REQUIRE(std::abs(gsum[d]) <= 1e-12);
      for (int c = 0; c < 2; ++c) REQUIRE(std::abs(grad_x[d][c] - (c == d ? 1.0 : 0.0)) <= 1e-12);
    }
  }
}

TEST_CASE("TLS on a triangle - mean-free Taylor basis, linear fields reproduced, totals kept", "[mesh-sim]") {
  // every Taylor function but the first integrates to zero under the 6-point rule (eq. 5.9 needs it)
  for (int k = 1; k < 6; ++k) {
    double integral = 0;
    for (int q = 0; q < TriangleGauss::points; ++q)
      integral += TriangleGauss::w[q] * triangle_taylor(TriangleGauss::xi[q][0], TriangleGauss::xi[q][1])[k];
    CHECK(std::abs(integral) <= 1e-15);
  }
  // the thesis' eq. 6.18 as printed (+1/18) is not mean-free
  double printed = 0;
  for (int q = 0; q < TriangleGauss::points; ++q) {
    const double s = TriangleGauss::xi[q][0] - 1.0 / 3, t = TriangleGauss::xi[q][1] - 1.0 / 3;
    printed += TriangleGauss::w[q] * (4 * s * t + 1.0 / 18);
  }
  CHECK(std::abs(printed + 1.0 / 18) <= 1e-15);

  // a linear field sampled at scattered points is fitted exactly; the constrained fields keep their totals
  const auto field = [](double s, double t, int c) { return 1.0 + c + (2.0 - c) * s - 0.5 * c * t; };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<TriangleSample> own;
  for (int p = 0; p < 7; ++p) {
    double s = u(rng), t = u(rng);
    if (s + t > 1) s = 1 - s, t = 1 - t;
    TriangleSample sample{s, t, {}};
    for (int c = 0; c < TriangleFields::count; ++c) sample.f[c] = field(s, t, c);
    own.push_back(sample);
  }
  const double area = 0.3;
  std::array<double, 3> totals;  // ∫ f = area × f(centroid) for a linear f
  for (int c = 0; c < 3; ++c) totals[c] = area * field(1.0 / 3, 1.0 / 3, c);
  for (int degree : {1, 2}) {
    FallbackCounts counts;
    const TriangleFields fit = fit_triangle(own, {}, totals, area, degree, counts);
    CHECK(counts.neighbour + counts.degree + counts.constant == 0);
    for (int c = 0; c < TriangleFields::count; ++c) {
      double integral = 0;
      for (int q = 0; q < TriangleGauss::points; ++q) {
        CHECK(fit.at[c][q] == Approx(field(TriangleGauss::xi[q][0], TriangleGauss::xi[q][1], c)).margin(1e-12));
        integral += TriangleGauss::w[q] * area * fit.at[c][q];
      }
      if (c < 3) CHECK(std::abs(integral - totals[c]) <= 1e-14);
    }
  }
  // two particles cannot determine a plane: the fit takes the neighbours', then a constant
  FallbackCounts counts;
  const std::vector<TriangleSample> two(own.begin(), own.begin() + 2);
  fit_triangle(two, own, totals, area, 1, counts);
  CHECK(counts.neighbour == 1);
  fit_triangle(two, {}, totals, area, 1, counts);
  CHECK(counts.constant == 1);
}

TEST_CASE("plate of thesis 6.3.1 on 1056 triangles - MPM-P1, MPM-TLS and PS-MPM conserve mass and momentum",
          "[mesh-sim]") {
  struct Method {
    const char *basis, *mapping, *mass;
  };
  for (const Method& m : {Method{"linear", "direct", "lumped"}, Method{"linear", "tls", "lumped"},
                          Method{"powell-sabin", "direct", "lumped"}, Method{"powell-sabin", "direct", "projection"}})
    for (const char* update : {"usl", "musl"}) {
      INFO(m.basis << " " << m.mapping << " " << m.mass << " " << update);
      MeshSimulation sim(
          parse_scene(plate_on_mesh("plate_1058.msh", m.basis, m.mapping, update, 24, 1.25e-4, 0.015, m.mass)));
      run_to_end(sim);
      CHECK(sim.conservation().mass_rel_max <= 1e-12);
      CHECK(sim.conservation().momentum_rel_max <= 1e-12);
      CHECK(sim.time() == 0.015);
    }
}

TEST_CASE("runs on a triangle mesh - 1 thread bitwise equal to 2 threads", "[mesh-sim][parallel]") {
  for (const auto& [basis, mapping, mass] : {std::tuple{"linear", "direct", "lumped"}, {"linear", "tls", "lumped"},
                                             {"powell-sabin", "direct", "projection"}}) {
    INFO(basis << " " << mapping << " " << mass);
    const auto scene = plate_on_mesh("plate_h1.msh", basis, mapping, "musl", 24, 1e-4, 2e-3, mass);
    CHECK(columns_after(scene, 20, 1) == columns_after(scene, 20, 2));
  }
}

TEST_CASE("Powell-Sabin velocities - the consistent mass reproduces a linear field, the lumped mass does not",
          "[mesh-sim]") {
  // particles at the 4 sub-centroids of each of the 6 split triangles, carrying v = x; q_a = Σ m_p φ_a v_p
  const TriangleMesh mesh = read_gmsh(mesh_file("plate_h2.msh"), {1.0, 1.0});
  const PowellSabinBasis basis(mesh);
  struct Particle {
    int e;
    Point2 x;
    double m;
  };
  std::vector<Particle> particles;
  for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
    for (const auto& [a, b, c] : basis.split(e))
      for (const auto& [s, t] : {std::pair{1.0 / 6, 1.0 / 6}, {2.0 / 3, 1.0 / 6}, {1.0 / 6, 2.0 / 3}, {1.0 / 3, 1.0 / 3}})
        particles.push_back({static_cast<int>(e),
                             {a[0] + s * (b[0] - a[0]) + t * (c[0] - a[0]), a[1] + s * (b[1] - a[1]) + t * (c[1] - a[1])},
                             1.0});
  const std::size_t n = basis.function_count();
  std::array<std::vector<double>, 2> q{std::vector<double>(n), std::vector<double>(n)}, v = q;
  std::vector<double> lumped(n);
  MeshMassMatrix M(mesh, basis);
  std::array<int, 9> idx;
  std::array<double, 9> w;
  std::array<Point2, 9> g;
  for (const auto& p : particles) {
    basis.evaluate(p.e, p.x, idx, w, g);
    M.add(p.e, w, p.m);
    for (int k = 0; k < 9; ++k) {
      lumped[idx[k]] += w[k] * p.m;
      for (int d = 0; d < 2; ++d) q[d][idx[k]] += w[k] * p.m * p.x[d];
    }
  }
  ConsistentMassSolver<2> solver(static_cast<int>(n));
  solver.solve_with([&](const auto& in, auto& out) { M.multiply(in, out); }, lumped,
                    [](int, std::size_t) { return true; }, v, q);
  double consistent = 0, lumped_error = 0;  // worst |∂v_d/∂x_d − 1| at interior particles
  for (const auto& p : particles) {
    if (std::min({p.x[0], 1 - p.x[0], p.x[1], 1 - p.x[1]}) < 0.2) continue;
    basis.evaluate(p.e, p.x, idx, w, g);
    for (int d = 0; d < 2; ++d) {
      double dv = 0, dv_lumped = 0;
      for (int k = 0; k < 9; ++k) {
        dv += v[d][idx[k]] * g[k][d];
        dv_lumped += q[d][idx[k]] / lumped[idx[k]] * g[k][d];
      }
      consistent = std::max(consistent, std::abs(dv - 1));
      lumped_error = std::max(lumped_error, std::abs(dv_lumped - 1));
    }
  }
  CHECK(consistent <= 1e-9);
  CHECK(lumped_error >= 0.1);  // measured 0.28 (README: PS-MPM needs the consistent mass)
}

TEST_CASE("plate on triangles - MPM-TLS's and PS-MPM's stress converge where MPM-P1's does not (246 -> 946 "
          "triangles)",
          "[mesh-sim][long]") {
  const auto order = [](const std::string& basis, const std::string& mapping) {
    double stress[2];
    for (int h = 0; h < 2; ++h) {  // tools/meshes/plate_h1, h2: the element size halves (tools/make_meshes.sh)
      const std::string mesh = "plate_h" + std::to_string(h + 1) + ".msh";
      MeshSimulation sim(parse_scene(plate_on_mesh(mesh, basis, mapping, "usl", 24, 2.5e-5, 0.02)));
      run_to_end(sim);
      stress[h] = sim.errors().stress_rms;
    }
    return std::log2(stress[0] / stress[1]);
  };
  // measured 1.64, 0.97 and -0.15 (docs/RESULTS.md section 9)
  CHECK(order("linear", "tls") >= 1.0);
  CHECK(order("powell-sabin", "direct") >= 0.5);
  CHECK(order("linear", "direct") <= 0.5);
}

TEST_CASE("a particle that leaves the mesh stops the run naming it", "[mesh-sim]") {
  nlohmann::json scene = plate_on_mesh("plate_h1.msh", "linear", "direct", "usl", 6, 1e-4, 0.05);
  scene.erase("problem");
  scene["bodies"] = {{{"box", {{0.2, 0.2}, {0.8, 0.8}}}, {"velocity", {40.0, 0.0}}}};
  scene["fixed"] = nlohmann::json::array();
  MeshSimulation sim(parse_scene(scene));
  CHECK_THROWS_WITH(run_to_end(sim), Contains("locate: particle") && Contains("left the mesh"));
}

TEST_CASE("scenes a triangle mesh refuses - exit 2 naming the key", "[mesh-sim]") {
  const auto base = plate_on_mesh("plate_h1.msh", "linear", "direct", "musl", 6, 1e-4, 2e-3);
  const auto refused = [&](auto edit, const std::string& words) {
    nlohmann::json s = base;
    edit(s);
    CHECK_THROWS_WITH(parse_scene(s), Contains(words));
  };
  refused([](auto& s) { s["grid"]["cells"] = {8, 8}; }, "grid.cells");
  refused([](auto& s) { s["grid"]["basis"] = "bspline2"; }, "grid.basis");
  refused([](auto& s) { s["dimension"] = 1; s["grid"]["length"] = {1.0}; s["problem"] = {{"name", "vibrating-bar"}}; }, "grid.mesh");
  refused([](auto& s) { s["particles"]["per_cell"] = {5}; }, "particles.per_cell");
  refused([](auto& s) { s["algorithm"]["update"] = "usf"; }, "algorithm.update");
  refused([](auto& s) { s["algorithm"]["mass"] = "consistent"; s["algorithm"]["mapping"] = "tls"; }, "algorithm.mass");
  refused([](auto& s) { s["algorithm"]["mapping"] = "mls"; }, "algorithm.mapping");
  refused([](auto& s) { s["grid"]["basis"] = "powell-sabin"; s["algorithm"]["mapping"] = "tls"; }, "algorithm.mapping");
  refused([](auto& s) { s["grid"]["mesh"] = "/nonexistent/plate.msh"; }, "/nonexistent/plate.msh");
  nlohmann::json grid_ps = base;
  grid_ps["grid"] = {{"length", {1.0, 1.0}}, {"cells", {8, 8}}, {"basis", "powell-sabin"}};
  CHECK_THROWS_WITH(parse_scene(grid_ps), Contains("grid.mesh"));
}
