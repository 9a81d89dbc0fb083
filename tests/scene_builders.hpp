#pragma once
// Scenes of the verification problems, built in code so each test states the settings it depends on.
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include <nlohmann/json.hpp>

#include "engine/scene.hpp"
#include "engine/simulation.hpp"

namespace mpm::test {

/// Vibrating bar, small deformation without grid crossing (thesis Table 5.2).
inline nlohmann::json bar_scene(int cells, const std::string& basis, const std::string& mass,
                                const std::string& update = "musl") {
  return {{"dimension", 1},
          {"problem", {{"name", "vibrating-bar"}, {"v0", 0.28}}},
          {"grid", {{"length", {1.0}}, {"cells", {cells}}, {"basis", basis}}},
          {"particles", {{"per_cell", {12}}}},
          {"material", {{"model", "linear-elastic"}, {"E", 7e6}, {"nu", 0.0}, {"density", 2000.0}}},
          {"algorithm", {{"update", update}, {"mass", mass}}},
          {"time", {{"dt", 1e-7}, {"end", 1.9e-6}}}};
}

/// Vibrating plate, manufactured solution; T = 0.0125 s, where every exact field is non-zero.
inline nlohmann::json plate_scene(int cells, double amplitude = 0.05, const std::string& update = "musl",
                                  const std::string& mass = "lumped") {
  return {{"dimension", 2},
          {"problem", {{"name", "vibrating-plate"}, {"amplitude", amplitude}}},
          {"grid", {{"length", {1.0, 1.0}}, {"cells", {cells, cells}}, {"basis", "bspline2"}}},
          {"particles", {{"per_cell", {3, 3}}}},
          {"algorithm", {{"update", update}, {"mass", mass}}},
          {"time", {{"dt", 1e-5}, {"end", 0.0125}}}};
}

template <int Dim>
void run_to_end(Simulation<Dim>& sim) {
  while (!sim.finished()) sim.step();
}

/// Every particle column after `steps` steps on at most `threads` threads (for the thread-count tests).
template <int Dim>
std::vector<std::vector<double>> state_after(const nlohmann::json& scene, int steps, int threads) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  Simulation<Dim> sim(parse_scene(scene));
  for (int s = 0; s < steps && !sim.finished(); ++s) sim.step();
  std::vector<std::vector<double>> cols;
  for (const auto& name : sim.particles().column_names()) {
    const auto c = sim.particles().column(name);
    cols.emplace_back(c.begin(), c.end());
  }
  return cols;
}

/// The largest difference between two runs' particle columns (state_after, in the order of `names`), relative to
/// the magnitude of the column's field (F01 against the largest entry of F, not of F01 alone: where the exact shear
/// is zero, a shear column holds round-off only, and relative to itself any two runs differ by O(1)).
inline double largest_field_difference(const std::vector<std::vector<double>>& a,
                                       const std::vector<std::vector<double>>& b,
                                       const std::vector<std::string>& names) {
  const auto field_of = [&](std::size_t c) { return names[c].substr(0, names[c].find_first_of("0123456789")); };
  std::map<std::string, double> scale;  // per field: the largest magnitude of its columns
  for (std::size_t c = 0; c < a.size(); ++c) {
    double& s = scale[field_of(c)];
    for (double x : a[c]) s = std::max(s, std::abs(x));
  }
  double worst = 0.0;
  for (std::size_t c = 0; c < a.size(); ++c) {
    const double s = std::max(scale[field_of(c)], 1e-300);
    for (std::size_t p = 0; p < a[c].size(); ++p) worst = std::max(worst, std::abs(a[c][p] - b[c][p]) / s);
  }
  return worst;
}

/// The particle column names of a scene's runs, in the order of state_after.
template <int Dim>
std::vector<std::string> column_names_of(const nlohmann::json& scene) {
  return Simulation<Dim>(parse_scene(scene)).particles().column_names();
}

/// What a verification test reads from a bar run.
struct BarResult {
  RunErrors errors;
  Conservation conservation;
  double end_stress_error;  ///< largest stress error of the two end particles
};

/// Runs the bar of thesis Table 5.2 (bar_scene) to the end with the given mapping.
inline BarResult run_bar(int cells, const std::string& basis, const std::string& mass,
                         const std::string& update = "musl", const std::string& mapping = "direct") {
  auto scene = bar_scene(cells, basis, mass, update);
  scene["algorithm"]["mapping"] = mapping;
  Simulation<1> sim(parse_scene(scene));
  run_to_end(sim);
  const auto& s = sim.particles();
  const auto X = s.column(Field::reference), sigma = s.column(Field::stress);
  const auto exact_source = make_problem<1>(sim.scene());
  double end_error = 0.0;
  for (std::size_t p : {std::size_t(0), s.size() - 1})
    end_error = std::max(end_error, std::abs(sigma[p] - exact_source->exact({X[p]}, sim.time()).sigma[0]));
  return {sim.errors(), sim.conservation(), end_error};
}

/// The fixed-ends bar of thesis §4.6.1: E = 4 kPa, ρ = 1, v0 = 0.6, T = 1e-3 s, dt = 1e-5, 12 particles per cell.
inline nlohmann::json otm_bar(int cells, const std::string& basis, const std::string& mapping = "direct") {
  return {{"dimension", 1},
          {"problem", {{"name", "vibrating-bar"}, {"v0", 0.6}}},
          {"grid", {{"length", {1.0}}, {"cells", {cells}}, {"basis", basis}}},
          {"particles", {{"per_cell", {12}}}},
          {"material", {{"model", "linear-elastic"}, {"E", 4e3}, {"nu", 0.0}, {"density", 1.0}}},
          {"algorithm", {{"update", "musl"}, {"mapping", mapping}}},
          {"time", {{"dt", 1e-5}, {"end", 1e-3}}}};
}

/// The plate of thesis §4.6.3 (tools/scenes/plate-unified.json): A = 0.005, 32×32 cells, 4×4 particles per cell,
/// dt = 1e-4, T = 3.5e-3 s.
inline nlohmann::json plate_4_6_3(const std::string& basis) {
  return {{"dimension", 2},
          {"problem", {{"name", "vibrating-plate"}, {"amplitude", 0.005}}},
          {"grid", {{"length", {1.0, 1.0}}, {"cells", {32, 32}}, {"basis", basis}}},
          {"particles", {{"per_cell", {4, 4}}}},
          {"material", {{"model", "neo-hookean"}, {"E", 1e7}, {"nu", 0.3}, {"density", 1000.0}}},
          {"time", {{"dt", 1e-4}, {"end", 3.5e-3}}}};
}

/// What a run leaves for a verification test.
struct Outcome {
  RunErrors errors;
  Conservation conservation;
};

/// Runs a scene to its end.
template <int Dim>
Outcome finished(const nlohmann::json& scene) {
  Simulation<Dim> sim(parse_scene(scene));
  run_to_end(sim);
  return {sim.errors(), sim.conservation()};
}

/// Observed order of convergence between two resolutions (cell size halved: ratio 2).
inline double order(double coarse_error, double fine_error, double ratio = 2.0) {
  return std::log(coarse_error / fine_error) / std::log(ratio);
}

}  // namespace mpm::test
