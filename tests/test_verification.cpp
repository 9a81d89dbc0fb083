// Verification against exact solutions: convergence orders measured from several resolutions, and
// conservation of mass and momentum between particles and grid after every P2G.
// [long]: the 2D studies that take seconds even in Release; the ASan run of tools/sanitize.sh leaves them out.
#include <array>
#include <cmath>

#include <catch2/catch.hpp>

#include "engine/run.hpp"
#include "scene_builders.hpp"

using namespace mpm;
using namespace mpm::test;

namespace {

void require_conserved(const Conservation& c) {
  CHECK(c.mass_rel_max <= 1e-13);
  CHECK(c.momentum_rel_max <= 1e-13);
}

/// Runs the bar on 10, 20 and 40 cells and checks conservation and the observed orders of u and σ.
void require_bar_orders(const std::string& basis, const std::string& mass, const std::string& mapping, double u_order,
                        double sigma_order) {
  const BarResult r[3] = {run_bar(10, basis, mass, "musl", mapping), run_bar(20, basis, mass, "musl", mapping),
                          run_bar(40, basis, mass, "musl", mapping)};
  INFO("u: " << r[0].errors.displacement_rms << " " << r[1].errors.displacement_rms << " "
             << r[2].errors.displacement_rms);
  INFO("sigma: " << r[0].errors.stress_rms << " " << r[1].errors.stress_rms << " " << r[2].errors.stress_rms);
  for (int i = 0; i < 3; ++i) require_conserved(r[i].conservation);
  for (int i = 0; i < 2; ++i) {
    CHECK(order(r[i].errors.displacement_rms, r[i + 1].errors.displacement_rms) >= u_order);
    CHECK(order(r[i].errors.stress_rms, r[i + 1].errors.stress_rms) >= sigma_order);
  }
}

}  // namespace

TEST_CASE("vibrating bar - MPM-P1 - MUSL: displacement order 2 - stress order 1 (thesis Fig 5.9a)",
          "[verification][bar]") {
  require_bar_orders("linear", "lumped", "direct", 1.8, 0.9);
}

TEST_CASE("vibrating bar - quadratic B-splines with the consistent-mass projection: orders 3 (u) and 2 (sigma)",
          "[verification][bar]") {
  require_bar_orders("bspline2", "projection", "direct", 2.7, 1.8);
}

TEST_CASE("vibrating bar - quadratic B-splines with lumped mass: the boundary defect (thesis Fig 5.10)",
          "[verification][bar]") {
  // On an open knot vector the lumped projection q_i/m_i does not reproduce linear fields in the boundary spans:
  // the stress error at the end particles does not decrease with refinement, and the overall stress order
  // collapses. This test documents the defect; the projection test above shows the cure.
  const BarResult r10 = run_bar(10, "bspline2", "lumped"), r40 = run_bar(40, "bspline2", "lumped");
  require_conserved(r10.conservation);
  require_conserved(r40.conservation);
  INFO("end-particle stress error: " << r10.end_stress_error << " -> " << r40.end_stress_error);
  CHECK(r40.end_stress_error >= 0.9 * r10.end_stress_error);
  CHECK(order(r10.errors.stress_rms, r40.errors.stress_rms, 4.0) < 1.0);
  const BarResult p40 = run_bar(40, "bspline2", "projection");
  CHECK(p40.end_stress_error < 0.1 * r40.end_stress_error);
}

TEST_CASE("vibrating bar - USL and USF converge like MUSL with P1 (displacement order 2)", "[verification][bar]") {
  for (const char* update : {"usl", "usf"}) {
    const BarResult r10 = run_bar(10, "linear", "lumped", update), r20 = run_bar(20, "linear", "lumped", update),
                    r40 = run_bar(40, "linear", "lumped", update);
    INFO(update << " u: " << r10.errors.displacement_rms << " " << r20.errors.displacement_rms << " "
                << r40.errors.displacement_rms);
    require_conserved(r40.conservation);
    CHECK(order(r10.errors.displacement_rms, r20.errors.displacement_rms) >= 1.8);
    CHECK(order(r20.errors.displacement_rms, r40.errors.displacement_rms) >= 1.8);
  }
}

TEST_CASE("vibrating plate - A = 0.05 - T = 0.0125 s - BSMPM lumped MUSL: errors decrease 8 -> 16 -> 32 cells",
          "[verification][plate][long]") {
  RunErrors e[3];
  int k = 0;
  for (int cells : {8, 16, 32}) {
    Simulation<2> sim(parse_scene(plate_scene(cells)));
    run_to_end(sim);
    require_conserved(sim.conservation());
    e[k++] = sim.errors();
  }
  for (int i = 0; i < 2; ++i) {
    INFO("cells " << (8 << i) << " -> " << (16 << i) << ": u " << e[i].displacement_rms << " -> "
                  << e[i + 1].displacement_rms << ", v " << e[i].velocity_rms << " -> " << e[i + 1].velocity_rms
                  << ", sigma " << e[i].stress_rms << " -> " << e[i + 1].stress_rms);
    CHECK(e[i + 1].displacement_rms < e[i].displacement_rms);
    CHECK(e[i + 1].velocity_rms < e[i].velocity_rms);
    CHECK(e[i + 1].stress_rms < e[i].stress_rms);
  }
}

TEST_CASE("vibrating plate - USL with projection and consistent mass conserve and beat lumped on a coarse grid",
          "[verification][plate][long]") {
  double lumped_u = 0;
  for (const char* mass : {"lumped", "projection", "consistent"}) {
    auto j = plate_scene(8, 0.05, "usl", mass);
    Simulation<2> sim(parse_scene(j));
    run_to_end(sim);
    require_conserved(sim.conservation());
    const double u = sim.errors().displacement_rms;
    INFO(mass << ": u " << u);
    if (std::string(mass) == "lumped") lumped_u = u;
    else CHECK(u < lumped_u);
  }
}

TEST_CASE("vibrating bar - BSMPM-TLS with the consistent-mass projection: orders 3 (u) and 2 (sigma) (thesis Fig 5.9c)",
          "[verification][bar][tls]") {
  require_bar_orders("bspline2", "projection", "tls", 2.7, 1.8);
}

TEST_CASE("TLS conserves mass and momentum to round-off after every P2G - 1D and 2D - uniform and random layouts",
          "[verification][tls][conservation]") {
  for (int ppc : {1, 2, 4, 9, 16}) {
    auto plate = plate_scene(8, 0.05);
    plate["algorithm"]["mapping"] = "tls";
    plate["particles"] = {{"per_cell", ppc}, {"layout", "random"}, {"seed", 7}};
    plate["time"]["end"] = 2e-3;
    Simulation<2> sim(parse_scene(plate));
    run_to_end(sim);
    INFO("2D random, " << ppc << " per cell: mass " << sim.conservation().mass_rel_max << ", momentum "
                       << sim.conservation().momentum_rel_max);
    require_conserved(sim.conservation());
  }
  for (const char* update : {"usl", "musl"}) {
    auto bar = bar_scene(10, "bspline2", "lumped", update);
    bar["algorithm"]["mapping"] = "tls";
    Simulation<1> sim(parse_scene(bar));
    run_to_end(sim);
    require_conserved(sim.conservation());
  }
}

TEST_CASE("vibrating plate at A = 0.1 - BSMPM-TLS with 4 and 6 particles per cell completes on 32 and 64 cells "
          "and converges (thesis 6.3.1 crashed)",
          "[verification][plate][tls][long]") {
  // Cells that lose particles near maximum compression made 2D TLS diverge (thesis §6.3.1); with few particles
  // per cell the velocity and stress fits are completed from the neighbouring cells (engine/gauss_points.hpp,
  // docs/RECONSTRUCTION.md). Measured u: 2×2 1.7e-3 → 5.1e-4, 3×2 1.3e-3 → 4.1e-4 (ratios 3.3 and 3.2); before,
  // both ended with J ≤ 0 or stalled (2×2: 2.0e-3 → 1.6e-3). Direct mapping: 3.2e-2 → 4.5e-2.
  for (const auto& ppc : {std::array<int, 2>{2, 2}, std::array<int, 2>{3, 2}}) {
    double u[2];
    for (int k = 0; k < 2; ++k) {
      auto j = plate_scene(32 << k, 0.1);
      j["material"] = {{"model", "neo-hookean"}, {"E", 1e7}, {"nu", 0.3}, {"density", 1000.0}};  // plate.json
      j["algorithm"]["mapping"] = "tls";
      j["particles"]["per_cell"] = ppc;
      Simulation<2> sim(parse_scene(j));
      INFO(ppc[0] << "x" << ppc[1] << " particles, " << (32 << k) << " cells");
      REQUIRE_NOTHROW(run_to_end(sim));
      require_conserved(sim.conservation());
      u[k] = sim.errors().displacement_rms;
    }
    INFO(ppc[0] << "x" << ppc[1] << ": u " << u[0] << " -> " << u[1]);
    CHECK(u[1] < u[0] / 2);  // at least first order from 32 to 64 cells
  }
}

TEST_CASE("column compaction (thesis 5.4.2) - direct BSMPM errors against the exact solution decrease 12 -> 25 -> 50 cells",
          "[verification][column]") {
  RunErrors e[3];
  int k = 0;
  for (int cells : {12, 25, 50}) {
    const nlohmann::json j = {{"dimension", 1},
                              {"problem", {{"name", "column-compaction"}}},
                              {"grid", {{"length", {50.0}}, {"cells", {cells}}}},
                              {"particles", {{"per_cell", {4}}}}};
    Simulation<1> sim(parse_scene(j));
    run_to_end(sim);
    require_conserved(sim.conservation());
    e[k++] = sim.errors();
  }
  for (int i = 0; i < 2; ++i) {
    INFO("u " << e[i].displacement_rms << " -> " << e[i + 1].displacement_rms << ", sigma " << e[i].stress_rms
              << " -> " << e[i + 1].stress_rms);
    CHECK(order(e[i].displacement_rms, e[i + 1].displacement_rms) >= 1.8);
    CHECK(e[i + 1].stress_rms < 0.5 * e[i].stress_rms);
  }
}

namespace {

/// Runs a 1D scene to its end: the errors against the exact solution, and the conservation maxima.
RunErrors errors_at_end(const nlohmann::json& scene, Conservation* conservation) {
  Simulation<1> sim(parse_scene(scene));
  run_to_end(sim);
  *conservation = sim.conservation();
  return sim.errors();
}

/// The column of thesis §5.4.2 (Table 5.6 material and load) on `cells` cells of the 50 m grid it fills.
RunErrors run_column(int cells, const std::string& mapping, int per_cell, Conservation* conservation) {
  const nlohmann::json j = {{"dimension", 1},
                            {"problem", {{"name", "column-compaction"}}},
                            {"grid", {{"length", {50.0}}, {"cells", {cells}}}},
                            {"particles", {{"per_cell", {per_cell}}}},
                            {"algorithm", {{"mapping", mapping}}}};
  return errors_at_end(j, conservation);
}

}  // namespace

TEST_CASE("column compaction (thesis 5.4.2, Table 5.7) - BSMPM-TLS with the thesis' 20 particles per cell: "
          "conservative at every resolution - stress error order >= 1.5 over 10 -> 80 cells",
          "[verification][column][tls][long]") {
  // Measured (MUSL, dt = 1e-4 s): sigma RMS 40.7 -> 12.1 -> 4.42 -> 1.46 Pa (orders 1.75, 1.45, 1.60; least-squares
  // 1.59), u 1.23e-3 -> 3.05e-4 -> 8.59e-5 -> 2.17e-5 m; direct BSMPM 35.7 -> 12.1 -> 3.96 -> 1.75 Pa. dt / 4
  // changes the 40- and 80-cell errors by < 1 %: this is the spatial error. With 4 particles per cell MUSL-TLS
  // stops on the energy guard at 40 and 80 cells (exit 3) where USL-TLS converges (50 -> 25 -> 12 -> 2.9 Pa):
  // docs/RECONSTRUCTION.md.
  const int cells[] = {10, 20, 40, 80};
  double log_h[4], log_e[4];
  for (int k = 0; k < 4; ++k) {
    Conservation c;
    const RunErrors e = run_column(cells[k], "tls", 20, &c);
    require_conserved(c);
    INFO(cells[k] << " cells: u " << e.displacement_rms << ", sigma " << e.stress_rms);
    CHECK(std::isfinite(e.stress_rms));
    log_h[k] = std::log(1.0 / cells[k]);
    log_e[k] = std::log(e.stress_rms);
  }
  // least-squares slope of log(error) against log(h) over the four resolutions
  const double mh = (log_h[0] + log_h[1] + log_h[2] + log_h[3]) / 4, me = (log_e[0] + log_e[1] + log_e[2] + log_e[3]) / 4;
  double num = 0.0, den = 0.0;
  for (int k = 0; k < 4; ++k) {
    num += (log_h[k] - mh) * (log_e[k] - me);
    den += (log_h[k] - mh) * (log_h[k] - mh);
  }
  INFO("fitted stress order " << num / den);
  CHECK(num / den >= 1.5);
}

namespace {

/// The bar of thesis §4.6.2 with the linear-elastic law, for which the wave solution (eq. 4.93) is exact at any
/// strain; `cells` cells on the 1.25 m grid (the bar fills 4/5 of them), 4 particles per cell, T = 0.4 s.
RunErrors run_traction_bar(int cells, const std::string& mapping, Conservation* conservation) {
  const nlohmann::json j = {{"dimension", 1},
                            {"problem", {{"name", "vibrating-bar-traction"}}},
                            {"grid", {{"length", {1.25}}, {"cells", {cells}}}},
                            {"particles", {{"per_cell", {4}}}},
                            {"material", {{"model", "linear-elastic"}}},
                            {"algorithm", {{"mapping", mapping}}}};
  return errors_at_end(j, conservation);
}

}  // namespace

TEST_CASE("bar with a traction at its free end (thesis 4.6.2, Fig 4.9) - BSMPM direct and TLS: errors decrease at a "
          "measured order, 20 -> 40 -> 80 cells",
          "[verification][traction][long]") {
  // Measured: u orders 1.66, 1.68 (direct) and 1.63, 1.53 (TLS); sigma 1.01, 1.44 and 1.04, 1.19. The stress has
  // a kink at the wave front (eq. 4.93), which bounds the orders (thesis: "slightly lower than expected").
  for (const char* mapping : {"direct", "tls"}) {
    RunErrors e[3];
    int k = 0;
    for (int cells : {20, 40, 80}) {
      Conservation c;
      e[k++] = run_traction_bar(cells, mapping, &c);
      require_conserved(c);
    }
    for (int i = 0; i < 2; ++i) {
      INFO(mapping << ": u " << e[i].displacement_rms << " -> " << e[i + 1].displacement_rms << ", v "
                   << e[i].velocity_rms << " -> " << e[i + 1].velocity_rms << ", sigma " << e[i].stress_rms
                   << " -> " << e[i + 1].stress_rms);
      CHECK(order(e[i].displacement_rms, e[i + 1].displacement_rms) >= 1.5);
      CHECK(order(e[i].stress_rms, e[i + 1].stress_rms) >= 0.9);
    }
  }
}

TEST_CASE("The relative L2 errors divide by the largest exact norm of the run, not the current one", "[verification]") {
  // At t = 0.04 s the plate's exact displacement and stress are zero (ω t = 4π): divided by their norm at that
  // instant the errors were 1.6e13; divided by the largest norm over the run they are the plain relative error.
  auto scene = plate_scene(8);
  scene["time"] = {{"dt", 1e-4}, {"end", 0.04}};
  RunOptions opt;
  opt.quiet = true;
  const RunResult r = run_scene(parse_scene(scene), opt);
  REQUIRE(r.status == exit_ok);
  const auto& e = r.summary["errors"];
  INFO(e.dump());
  // 8 × 8 cells: errors of 15–21 % of the largest norm (the old normalisation: ~1e13)
  CHECK(e["displacement_rel_l2"].get<double>() < 0.3);
  CHECK(e["stress_rel_l2"].get<double>() < 0.3);
  CHECK(e["displacement_rel_l2"].get<double>() > 0.0);
}
