// The last gather pass of a USL or MUSL step that scatters the next step's P2G as well
// (Simulation::Step::gather_and_scatter_ahead): its results equal those of separate passes to the bit, where the
// next step keeps its bins and where the particles move far enough to be binned again between reorderings.
#include <catch2/catch.hpp>

#include "scene_builders.hpp"

using namespace mpm;
using namespace mpm::test;

namespace {

/// What a run leaves: its particle columns, its conservation maxima, and how many steps found their P2G done.
struct Outcome {
  std::vector<std::vector<double>> columns;
  double mass_rel_max, momentum_rel_max;
  long scattered_ahead;
};

template <int Dim>
Outcome run(const nlohmann::json& scene, int steps, bool ahead) {
  Simulation<Dim> sim(parse_scene(scene));
  sim.allow_scatter_ahead(ahead);
  for (int s = 0; s < steps; ++s) sim.step();
  Outcome o{{}, sim.conservation().mass_rel_max, sim.conservation().momentum_rel_max, sim.steps_scattered_ahead()};
  for (const auto& name : sim.particles().column_names()) {
    const auto c = sim.particles().column(name);
    o.columns.emplace_back(c.begin(), c.end());
  }
  return o;
}

/// Runs the scene with and without scattering ahead; the same bits; returns the steps that found their P2G done.
template <int Dim>
long same_bits_ahead_or_not(const nlohmann::json& scene, int steps) {
  const Outcome ahead = run<Dim>(scene, steps, true), apart = run<Dim>(scene, steps, false);
  CHECK(apart.scattered_ahead == 0);
  REQUIRE(ahead.columns.size() == apart.columns.size());
  for (std::size_t c = 0; c < ahead.columns.size(); ++c) CHECK(ahead.columns[c] == apart.columns[c]);
  CHECK(ahead.mass_rel_max == apart.mass_rel_max);
  CHECK(ahead.momentum_rel_max == apart.momentum_rel_max);
  return ahead.scattered_ahead;
}

}  // namespace

TEST_CASE("a gather pass that scatters the next step's P2G gives the results of separate passes to the bit",
          "[simulation][usl][musl]") {
  // 40 steps: the store is reordered at steps 0, 16 and 32, and a step scatters ahead unless the next one
  // reorders, so steps 1–39 but 16 and 32 find their P2G done
  for (const char* update : {"usl", "musl"})
    for (const char* mass : {"lumped", "projection"}) {
      INFO("plate, " << update << ", " << mass << " mass");
      CHECK(same_bits_ahead_or_not<2>(plate_scene(16, 0.05, update, mass), 40) == 37);
    }
  for (const char* update : {"usl", "musl"}) {
    INFO("bar, " << update << ", 19 steps, reordered at step 16");
    CHECK(same_bits_ahead_or_not<1>(bar_scene(40, "bspline2", "lumped", update), 19) == 17);
  }
}

TEST_CASE("a step scatters ahead only while the particles keep their bins", "[simulation][usl]") {
  // a block at 30 m/s moves 0.29 cells a step (h = 1/16, Δt = 6e-4 s): it uses up the bins' slack of one cell in
  // four steps, is binned again (not reordered) and then scatters no more ahead until the next reordering
  const nlohmann::json block = {
      {"dimension", 2},
      {"grid", {{"length", {1.0, 1.0}}, {"cells", {16, 16}}}},
      {"particles", {{"per_cell", {2, 2}}}},
      {"material", {{"model", "neo-hookean"}, {"E", 1e4}, {"nu", 0.3}, {"density", 1000.0}}},
      {"bodies", {{{"box", {{0.125, 0.25}, {0.375, 0.5}}}, {"velocity", {30.0, 0.0}}}}},
      {"algorithm", {{"update", "usl"}}},
      {"time", {{"dt", 6e-4}, {"end", 0.012}}}};
  const long ahead = same_bits_ahead_or_not<2>(block, 20);
  CHECK(ahead > 0);
  CHECK(ahead < 19);
}
