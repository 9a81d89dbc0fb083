// Whole time step, Simulation<Dim>::step(), on the headline scene: one neo-Hookean body filling the grid with a
// uniform velocity, all sides fixed, no problem, no body force; direct mapping, lumped mass, quadratic B-splines on
// the fast path; 4 particles per cell (2D: 2x2, 1D: 4). Arguments: nominal particle count and TBB threads.
// Sizes: 2D 1e3 ... 1e7 (cells = sqrt(N/4) per axis), 1D 1e3 ... 4e6 (2^20 cells is the scene's limit).
//
//   step/<dim>d/<scheme>/n:<N>/threads:<T>     scheme: usl, musl (direct mapping), musl-tls (TLS reconstruction),
//                                              usl-generic (USL with the Cox–de Boor weights: grid.basis_path generic),
//                                              usl-ahead, musl-ahead (2D, 1e5 ... 1e7: the last G2P and the next
//                                              step's P2G in one pass over the particles,
//                                              Simulation::allow_scatter_ahead),
//                                              musl-9ppc, musl-tls-9ppc (2D, 3x3 particles per cell, the plate's
//                                              layout: TLS fits most cells from their own particles there)
//
// Counter particle_steps_per_s = particles x steps / wall time. Set-up (scene parsing, seeding, the first-touch
// of every array) is outside the timed loop. A Simulation is reused by consecutive benchmarks with the same
// dimension, size and scheme (the thread counts and repetitions of one size), since seeding 1e7 particles costs
// seconds, until it has run kFreshAfter steps. The engine reorders the particles every 16 steps, so every timed run is a whole number of 16-step
// periods starting at a reorder step, and so includes the reordering at its true frequency. At 1e7 particles a
// run is one period and the benchmark runs once (Repetitions(1)), whatever --benchmark_repetitions says.
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "bench/bench_util.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"

namespace {

constexpr long kPeriod = 16;              // engine/simulation_impl.hpp: reorder_every
constexpr std::size_t kLarge = 5'000'000;  // from here: one period per run, one repetition, no warm-up
// A Simulation is replaced before it passes this many steps: the block moves at 0.1 m/s into its fixed walls, about
// half a cell per 1000 steps at cfl 0.2 whatever the size; at 1e3 particles MUSL-TLS crushed it (J <= 0) near step
// 19 600 of the reused run
constexpr long kFreshAfter = 8192;

/// Particles per cell and axis in 2D: 3 for the *-9ppc schemes, else 2.
int per_axis_2d(const std::string& scheme) { return scheme.ends_with("-9ppc") ? 3 : 2; }

/// The headline scene; `n` nominal particles, 4 per cell (9 for the *-9ppc schemes).
nlohmann::json scene_json(int dim, std::int64_t n, const std::string& scheme) {
  nlohmann::json material{{"model", "neo-hookean"}, {"E", 1e6}, {"nu", 0.3}, {"density", 1000}};
  const std::string path = scheme == "usl-generic" ? "generic" : "fast";
  nlohmann::json j;
  if (dim == 2) {
    const int per_axis = per_axis_2d(scheme);
    const int cells = mpm_bench::cells_for_2d(n, per_axis);
    j = {{"dimension", 2},
         {"grid", {{"length", {1, 1}}, {"cells", {cells, cells}}, {"basis", "bspline2"}, {"basis_path", path}}},
         {"particles", {{"per_cell", {per_axis, per_axis}}}},
         {"bodies", {{{"box", {{0, 0}, {1, 1}}}, {"velocity", {0.1, 0.05}}}}},
         {"fixed", {"x-", "x+", "y-", "y+"}}};
  } else {
    const int cells = std::max<int>(1, static_cast<int>(n / 4));
    j = {{"dimension", 1},
         {"grid", {{"length", {1}}, {"cells", {cells}}, {"basis", "bspline2"}, {"basis_path", path}}},
         {"particles", {{"per_cell", {4}}}},
         {"bodies", {{{"box", {{0}, {1}}}, {"velocity", {0.1}}}}},
         {"fixed", {"x-", "x+"}}};
  }
  j["material"] = material;
  // "musl-tls": MUSL with the TLS reconstruction (Gauss-point P2G), against the direct mapping of "musl"
  const bool tls = scheme.starts_with("musl-tls");
  const std::string update = scheme.starts_with("musl") ? "musl" : "usl";
  j["algorithm"] = {{"update", update}, {"mass", "lumped"}, {"mapping", tls ? "tls" : "direct"}};
  j["time"] = {{"cfl", 0.2}, {"end", 1000.0}};  // never reached within a benchmark
  return j;
}

/// Timed steps per run: a multiple of the reorder period, about `budget` particle-steps, at least one period.
long timed_steps(std::size_t particles) {
  constexpr double budget = 1.0e7;
  const long periods = std::max(1L, std::lround(budget / (static_cast<double>(particles) * kPeriod)));
  return std::min(periods, 256L) * kPeriod;
}

template <int Dim>
struct Cache {
  std::string key;
  std::unique_ptr<mpm::Simulation<Dim>> sim;
};

/// The cached Simulation of this size and scheme, or a fresh one if it would pass kFreshAfter within `steps` more.
template <int Dim>
mpm::Simulation<Dim>& simulation(std::int64_t n, const std::string& scheme, long steps) {
  static Cache<Dim> cache;
  const std::string key = std::to_string(n) + "/" + scheme;
  if (cache.key != key || !cache.sim || cache.sim->steps_done() + kPeriod + steps > kFreshAfter) {
    cache.sim.reset();  // free the previous one first: 1e7 particles are ~1.3 GB
    cache.sim = std::make_unique<mpm::Simulation<Dim>>(mpm::parse_scene(scene_json(Dim, n, scheme)));
    cache.sim->allow_scatter_ahead(scheme.ends_with("-ahead"));
    cache.key = key;
  }
  return *cache.sim;
}

std::size_t particles_of(int dim, std::int64_t nominal, const std::string& scheme) {
  if (dim == 2) {
    const std::size_t per_axis = per_axis_2d(scheme);
    const std::size_t c = mpm_bench::cells_for_2d(nominal, static_cast<int>(per_axis));
    return per_axis * per_axis * c * c;
  }
  return 4 * static_cast<std::size_t>(std::max<std::int64_t>(1, nominal / 4));
}

template <int Dim>
void BM_Step(benchmark::State& state, const std::string& scheme) {
  const std::int64_t nominal = state.range(0);
  const int threads = static_cast<int>(state.range(1));
  auto gc = mpm_bench::limit_threads(threads);
  try {
    const long steps = timed_steps(particles_of(Dim, nominal, scheme));
    auto& sim = simulation<Dim>(nominal, scheme, steps);
    const std::size_t np = sim.particles().size();
    // untimed: finish the current reorder period, so the timed run starts with a reordering step. A fresh
    // Simulation first runs one warm-up period (first touch of the binning arrays), except at the largest size,
    // where a period costs ~20 s and the first touch of 8 bytes per particle is negligible against 16 steps.
    if (sim.steps_done() == 0 && np < kLarge) sim.step();
    while (sim.steps_done() % kPeriod != 0) sim.step();
    if (state.max_iterations != static_cast<benchmark::IterationCount>(steps)) {
      state.SkipWithError("registered iteration count differs from timed_steps()");
      return;
    }
    for (auto _ : state) sim.step();
    state.counters["particles"] = static_cast<double>(np);
    state.counters["particle_steps_per_s"] =
        benchmark::Counter(static_cast<double>(np) * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["dt"] = sim.dt();
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

const bool registered = [] {
  // 1D stops at 4e6 particles: the scene contract allows at most 2^20 cells per axis (4 particles per cell)
  const std::vector<std::int64_t> sizes_1d{1'000, 10'000, 100'000, 1'000'000, 4'000'000};
  const std::vector<std::int64_t> sizes_2d{1'000, 10'000, 100'000, 1'000'000, 10'000'000};
  for (int dim : {1, 2})
    for (const std::string scheme :
         {"usl", "musl", "musl-tls", "usl-generic", "musl-9ppc", "musl-tls-9ppc", "usl-ahead", "musl-ahead"})
      for (std::int64_t n : dim == 1 ? sizes_1d : sizes_2d) {
        if (scheme.starts_with("musl-tls") && n > 1'000'000) continue;  // several direct steps per step
        // the whole-step cost of the generic weights beside the fast path's, and the 9-per-cell pair
        // (2D, 1e5 and 1e6)
        if ((scheme == "usl-generic" || scheme.ends_with("-9ppc")) && (dim == 1 || n < 100'000 || n > 1'000'000))
          continue;
        if (scheme.ends_with("-ahead") && (dim == 1 || n < 100'000)) continue;  // beside usl and musl
        const std::string name = "step/" + std::to_string(dim) + "d/" + scheme;
        auto fn = dim == 1 ? BM_Step<1> : BM_Step<2>;
        auto* b = benchmark::RegisterBenchmark(name.c_str(), fn, scheme)
                      ->Args({n, 1})
                      ->Args({n, 2})
                      ->ArgNames({"n", "threads"})
                      ->Iterations(timed_steps(particles_of(dim, n, scheme)))
                      ->UseRealTime()
                      ->Unit(benchmark::kMillisecond);
        // 1e7 particles: ~1 s per 2D step; one 16-step run per thread count keeps the suite within minutes
        if (particles_of(dim, n, scheme) >= kLarge) b->Repetitions(1);
      }
  return true;
}();

}  // namespace
