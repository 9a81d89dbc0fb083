// Particle ↔ grid transfers in 2D with the quadratic fast-path basis, on 2x2 particles per cell sorted into the
// engine's block order.
//
// P2G of mass, momentum and force (the USL scatter, the heaviest one), four ways; each timed iteration produces
// the finished grid from zero (clear + scatter [+ reduce]):
//   p2g/serial      CellBins::for_each_block_serial + scatter_p2g (the engine's reference order), one thread
//   p2g/coloured    CellBins::for_each_block_coloured + scatter_p2g: what the engine runs
//   p2g/atomic      baseline: tbb::parallel_for over particles, every grid add a std::atomic_ref<double> fetch_add
//   p2g/per_thread  baseline: tbb::enumerable_thread_specific grid per thread, scatter_p2g into it, then a
//                   parallel sum of the copies into the grid (which also clears the copies for the next step)
// The two baselines live here only (DESIGN.md: they justify the coloured scheme; they are not engine code).
// Every variant is checked against the serial result before timing.
//
// The reconstruction stage against direct P2G, per particle (p2g/tls): the same particles' mass, momentum and force
// through the TLS path — single-cell binning, GaussPoints::rebuild of ρ, v and σ at 2×2 Gauss points per cell,
// coloured scatter of the Gauss points (GaussPoints::scatter) — as Simulation::step_with runs it for USL. With 2×2
// particles per cell every velocity and stress fit is completed from the cell's 3×3 neighbourhood.
//
// G2P (gather_g2p) for the gathers the schemes use, MUSL's fused velocity-update + momentum-scatter pass
// (advance_velocity_scatter_momentum, coloured), the stress update alone (neo-Hookean σ(F)), and the per-step
// binning (CellBins::bin) and the every-16-steps permutation (ParticleStore::permute).
//
// The gather's schedule (schedule/g2p_usl/<partitioner>/grain:G): the USL gather under each oneTBB partitioner —
// auto (the engine's, engine/parallel_over.hpp), static, simple, affinity — and grain sizes from 256 to 16384
// particles per task, so the engine's choice is a measurement (docs/PERFORMANCE.md, "The gather's schedule").
//
// Every kernel runs in the instruction set the engine picks at run time (with_active_isa, kernels/isa.hpp; MPM_ISA
// forces one), the baselines too, so that the portable build times the code the engine runs.
#include <atomic>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "bench/bench_util.hpp"
#include "engine/gauss_points.hpp"
#include "engine/material.hpp"
#include "engine/scene.hpp"
#include "kernels/isa.hpp"
#include "kernels/transfer.hpp"

namespace {

using mpm_bench::Grid2D;
using mpm_bench::ParticleSet2D;

constexpr mpm::ScatterFields kAll{true, true, true};
constexpr mpm::NoBodyForce kNoBody{};
constexpr std::size_t kParticleGrain = 2048;  // as the engine's gathers
constexpr std::size_t kGridGrain = 4096;      // as the engine's grid loops

/// One particle set alive at a time (the largest is ~0.5 GB); reused by consecutive benchmarks of one size.
ParticleSet2D& particle_set(std::int64_t nominal) {
  static std::unique_ptr<ParticleSet2D> cached;
  const int cells = mpm_bench::cells_for_2d(nominal);
  if (!cached || cached->cells != cells) {
    cached.reset();
    cached = std::make_unique<ParticleSet2D>(cells);
  }
  return *cached;
}

// ---------------------------------------------------------------------------------------------------------------
// Baseline 1: atomic adds. The loop body is scatter_p2g's (kernels/transfer.hpp) with every += made atomic.
template <mpm::ScatterFields Fields, int Dim, int S, class Axis>
void scatter_p2g_atomic(const mpm::TensorBasis<Dim, Axis>& basis, const mpm::ParticleView<Dim>& p,
                        const mpm::GridView<Dim>& g, const unsigned* order, std::size_t begin, std::size_t end) {
  const auto add = [](double& target, double value) {
    std::atomic_ref<double>(target).fetch_add(value, std::memory_order_relaxed);
  };
  for (std::size_t k = begin; k < end; ++k) {
    const std::size_t ip = order[k];
    double xp[Dim];
    for (int d = 0; d < Dim; ++d) xp[d] = p.x[d][ip];
    const auto st = mpm::stencil_at<Dim, S>(basis, xp);
    const double mp = p.m[ip];
    double mv[Dim] = {};
    if constexpr (Fields.momentum)
      for (int d = 0; d < Dim; ++d) mv[d] = mp * p.v[d][ip];
    double Vsig[Dim][Dim] = {};
    if constexpr (Fields.force) {
      const double V = mpm::det(p, ip) * p.V0[ip];
      for (int a = 0; a < Dim; ++a)
        for (int b = 0; b < Dim; ++b) Vsig[a][b] = V * p.s[mpm::sym_index<Dim>(a, b)][ip];
    }
    mpm::for_each_node(st, g.stride1, [&](int i, double w, const std::array<double, Dim>& dw) {
      if constexpr (Fields.mass) add(g.m[i], w * mp);
      if constexpr (Fields.momentum)
        for (int d = 0; d < Dim; ++d) add(g.q[d][i], w * mv[d]);
      if constexpr (Fields.force)
        for (int d = 0; d < Dim; ++d) {
          double fi = 0.0;
          for (int l = 0; l < Dim; ++l) fi -= dw[l] * Vsig[l][d];
          add(g.f[d][i], fi);
        }
    });
  }
}

// Baseline 2: per-thread grids of the arrays the scatter writes.
struct LocalGrid {
  std::vector<double> m, q0, q1, f0, f1;
  explicit LocalGrid(int dofs) : m(dofs, 0.0), q0(dofs, 0.0), q1(dofs, 0.0), f0(dofs, 0.0), f1(dofs, 0.0) {}
  mpm::GridView<2> view(int stride1) {
    mpm::GridView<2> g;
    g.stride1 = stride1;
    g.dofs = static_cast<int>(m.size());
    g.m = m.data();
    g.q = {q0.data(), q1.data()};
    g.f = {f0.data(), f1.data()};
    return g;
  }
  std::array<std::vector<double>*, 5> arrays() { return {&m, &q0, &q1, &f0, &f1}; }
};

void clear_parallel(Grid2D& g) {
  auto targets = g.scatter_targets();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.dofs, kGridGrain), [&](const auto& r) {
    for (auto* a : targets) std::fill(a->begin() + r.begin(), a->begin() + r.end(), 0.0);
  });
}

void p2g_serial(ParticleSet2D& ps, Grid2D& g) {
  for (auto* a : g.scatter_targets()) std::fill(a->begin(), a->end(), 0.0);
  const auto pv = ps.store.view();
  const auto gv = g.view();
  const unsigned* order = ps.bins.order().data();
  ps.bins.for_each_block_serial([&](std::size_t b, std::size_t e) {
    mpm::with_active_isa([&](auto isa) { mpm::scatter_p2g<kAll, 2, 3, isa>(ps.basis, pv, gv, order, b, e, kNoBody); });
  });
}

void p2g_coloured(ParticleSet2D& ps, Grid2D& g) {
  clear_parallel(g);
  const auto pv = ps.store.view();
  const auto gv = g.view();
  const unsigned* order = ps.bins.order().data();
  ps.bins.for_each_block_coloured([&](std::size_t b, std::size_t e) {
    mpm::with_active_isa([&](auto isa) { mpm::scatter_p2g<kAll, 2, 3, isa>(ps.basis, pv, gv, order, b, e, kNoBody); });
  });
}

void p2g_atomic(ParticleSet2D& ps, Grid2D& g) {
  clear_parallel(g);
  const auto pv = ps.store.view();
  const auto gv = g.view();
  const unsigned* order = ps.bins.order().data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ps.n, kParticleGrain), [&](const auto& r) {
    mpm::with_active_isa([&](auto) { scatter_p2g_atomic<kAll, 2, 3>(ps.basis, pv, gv, order, r.begin(), r.end()); });
  });
}

void p2g_per_thread(ParticleSet2D& ps, Grid2D& g, tbb::enumerable_thread_specific<LocalGrid>& locals) {
  const auto pv = ps.store.view();
  const unsigned* order = ps.bins.order().data();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ps.n, kParticleGrain), [&](const auto& r) {
    const auto lv = locals.local().view(g.stride1);
    mpm::with_active_isa(
        [&](auto isa) { mpm::scatter_p2g<kAll, 2, 3, isa>(ps.basis, pv, lv, order, r.begin(), r.end(), kNoBody); });
  });
  std::vector<LocalGrid*> copies;
  for (auto& l : locals) copies.push_back(&l);
  auto targets = g.scatter_targets();
  // sum the copies into the grid and zero them for the next step, one cache-sized chunk at a time
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.dofs, kGridGrain), [&](const auto& r) {
    for (int k = 0; k < 5; ++k) {
      double* out = targets[k]->data();
      for (std::size_t c = 0; c < copies.size(); ++c) {
        double* in = copies[c]->arrays()[k]->data();
        if (c == 0)
          for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] = in[i];
        else
          for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] += in[i];
        std::fill(in + r.begin(), in + r.end(), 0.0);
      }
      if (copies.empty()) std::fill(out + r.begin(), out + r.end(), 0.0);
    }
  });
}

enum class P2G { serial, coloured, atomic, per_thread };

void BM_P2G(benchmark::State& state, P2G variant) {
  const std::int64_t nominal = state.range(0);
  const int threads = static_cast<int>(state.range(1));
  auto& ps = particle_set(nominal);
  auto gc = mpm_bench::limit_threads(threads);
  Grid2D reference(ps.functions()), g(ps.functions());
  p2g_serial(ps, reference);
  tbb::enumerable_thread_specific<LocalGrid> locals([&] { return LocalGrid(g.dofs); });
  auto run = [&] {
    switch (variant) {
      case P2G::serial: p2g_serial(ps, g); break;
      case P2G::coloured: p2g_coloured(ps, g); break;
      case P2G::atomic: p2g_atomic(ps, g); break;
      case P2G::per_thread: p2g_per_thread(ps, g, locals); break;
    }
  };
  run();  // warm-up: first touch, per-thread copies allocated
  double worst = 0.0;
  for (int k = 0; k < 5; ++k) worst = std::max(worst, mpm_bench::max_rel_diff(*g.scatter_targets()[k], *reference.scatter_targets()[k]));
  if (worst > 1e-12) {
    state.SkipWithError("P2G result differs from the serial scatter");
    return;
  }
  for (auto _ : state) {
    run();
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * ps.n));
  state.counters["particles"] = static_cast<double>(ps.n);
  state.counters["rel_diff_vs_serial"] = worst;
}

// ---------------------------------------------------------------------------------------------------------------
/// Runs `run` once untimed (first touch of what it writes), then times it; reports particles per second.
template <class Run>
void time_per_particle(benchmark::State& state, Run&& run, std::size_t particles) {
  run();
  for (auto _ : state) {
    run();
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * particles));
  state.counters["particles"] = static_cast<double>(particles);
}

/// The TLS P2G of mass, momentum and force, from the particles to a finished grid (p2g/tls; compare p2g/coloured).
void BM_P2G_TLS(benchmark::State& state) {
  auto& ps = particle_set(state.range(0));
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  const nlohmann::json scene_json = {
      {"dimension", 2},
      {"grid", {{"length", {1, 1}}, {"cells", {ps.cells, ps.cells}}, {"basis", "bspline2"}}},
      {"particles", {{"per_cell", {2, 2}}}},
      {"bodies", {{{"box", {{0, 0}, {1, 1}}}}}},
      {"material", {{"model", "neo-hookean"}, {"E", 1e6}, {"nu", 0.3}, {"density", 1000}}},
      {"algorithm", {{"update", "usl"}, {"mass", "lumped"}, {"mapping", "tls"}}},
      {"time", {{"dt", 1e-6}, {"end", 1e-6}}}};
  mpm::GaussPoints<2> gauss(mpm::parse_scene(scene_json), ps.bins.block_width());
  auto cells = mpm::CellBins<2>::single_cells_in_order_of(ps.bins);
  Grid2D g(ps.functions());
  const auto pv = ps.store.view();
  const auto gv = g.view();
  const std::array<const double*, 2> x{pv.x[0], pv.x[1]};
  auto run = [&] {
    cells.bin(x, ps.n);
    benchmark::DoNotOptimize(gauss.rebuild(pv, cells, ps.bins, mpm::NoBodyForce{}, true, true));
    clear_parallel(g);
    gauss.scatter<kAll, false, 3>(ps.basis, gv);
  };
  time_per_particle(state, run, ps.n);
  state.counters["fallbacks_per_rebuild"] =
      static_cast<double>(gauss.fallbacks().total()) / static_cast<double>(state.iterations() + 1);
}

// ---------------------------------------------------------------------------------------------------------------
enum class G2P { usl, velocity, position_deformation, fused_velocity_momentum };

template <mpm::GatherFields Fields>
void gather(ParticleSet2D& ps, Grid2D& g, double dt, const mpm::NeoHookean& law, mpm::ParticleGuard& guard) {
  const auto pv = ps.store.view();
  const auto gv = g.view();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ps.n, kParticleGrain), [&](const auto& r) {
    mpm::with_active_isa([&](auto isa) {
      const auto stress = [&](const double* F, double* s) { law.stress<2, isa>(F, s); };
      mpm::gather_g2p<Fields, 2, 3, isa>(ps.basis, pv, gv, r.begin(), r.end(), dt, stress, guard);
    });
  });
}

enum class Partitioner { auto_, static_, simple, affinity };

/// The USL gather as one parallel_for over particle ranges of `grain` under the given partitioner.
void gather_usl_scheduled(ParticleSet2D& ps, Grid2D& g, double dt, const mpm::NeoHookean& law,
                          mpm::ParticleGuard& guard, Partitioner part, std::size_t grain,
                          tbb::affinity_partitioner& affinity) {
  const auto pv = ps.store.view();
  const auto gv = g.view();
  const tbb::blocked_range<std::size_t> range(0, ps.n, grain);
  const auto body = [&](const tbb::blocked_range<std::size_t>& r) {
    mpm::with_active_isa([&](auto isa) {
      const auto stress = [&](const double* F, double* s) { law.stress<2, isa>(F, s); };
      mpm::gather_g2p<mpm::GatherFields{true, true, true}, 2, 3, isa>(ps.basis, pv, gv, r.begin(), r.end(), dt, stress,
                                                                       guard);
    });
  };
  switch (part) {
    case Partitioner::auto_: tbb::parallel_for(range, body, tbb::auto_partitioner{}); break;
    case Partitioner::static_: tbb::parallel_for(range, body, tbb::static_partitioner{}); break;
    case Partitioner::simple: tbb::parallel_for(range, body, tbb::simple_partitioner{}); break;
    case Partitioner::affinity: tbb::parallel_for(range, body, affinity); break;
  }
}

mpm::NeoHookean neo_hookean() {
  mpm::MaterialSpec spec;
  spec.model = mpm::MaterialModel::neo_hookean;
  spec.E = 1e6;
  spec.nu = 0.3;
  return mpm::NeoHookean{mpm::Lame::from(spec)};
}

/// A grid of random velocities and accelerations for the gathers.
Grid2D random_grid(const ParticleSet2D& ps) {
  Grid2D g(ps.functions());
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int d = 0; d < 2; ++d)
    for (int i = 0; i < g.dofs; ++i) {
      g.v[d][i] = u(rng);
      g.a[d][i] = u(rng);
    }
  return g;
}

constexpr double kGatherDt = 1e-9;  // particles and F barely change over a gather benchmark

void BM_G2P(benchmark::State& state, G2P variant) {
  const std::int64_t nominal = state.range(0);
  auto& ps = particle_set(nominal);
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  Grid2D g = random_grid(ps);
  const auto law = neo_hookean();
  mpm::ParticleGuard guard;
  guard.hi = {1.0, 1.0, 0.0};
  const double dt = kGatherDt;
  auto run = [&] {
    switch (variant) {
      case G2P::usl: gather<mpm::GatherFields{true, true, true}>(ps, g, dt, law, guard); break;
      case G2P::velocity: gather<mpm::GatherFields{true, false, false}>(ps, g, dt, law, guard); break;
      case G2P::position_deformation: gather<mpm::GatherFields{false, true, true}>(ps, g, dt, law, guard); break;
      case G2P::fused_velocity_momentum: {  // as Simulation::step_with runs it for MUSL: clear q, coloured pass
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.dofs, kGridGrain), [&](const auto& r) {
          for (int d = 0; d < 2; ++d) std::fill(g.q[d].begin() + r.begin(), g.q[d].begin() + r.end(), 0.0);
        });
        const auto pv = ps.store.view();
        const auto gv = g.view();
        const unsigned* order = ps.bins.order().data();
        ps.bins.for_each_block_coloured([&](std::size_t b, std::size_t e) {
          mpm::with_active_isa([&](auto isa) {
            benchmark::DoNotOptimize(
                mpm::advance_velocity_scatter_momentum<2, 3, isa>(ps.basis, pv, gv, order, b, e, dt));
          });
        });
        break;
      }
    }
  };
  time_per_particle(state, run, ps.n);
  if (guard.first_bad.load() != mpm::ParticleGuard::none) state.SkipWithError("a particle was flagged invalid");
}

void BM_GatherSchedule(benchmark::State& state, Partitioner part) {
  auto& ps = particle_set(state.range(0));
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  const auto grain = static_cast<std::size_t>(state.range(2));
  Grid2D g = random_grid(ps);
  const auto law = neo_hookean();
  mpm::ParticleGuard guard;
  guard.hi = {1.0, 1.0, 0.0};
  tbb::affinity_partitioner affinity;  // kept across iterations: it replays the last split
  time_per_particle(state, [&] { gather_usl_scheduled(ps, g, kGatherDt, law, guard, part, grain, affinity); }, ps.n);
  if (guard.first_bad.load() != mpm::ParticleGuard::none) state.SkipWithError("a particle was flagged invalid");
}

void BM_Stress(benchmark::State& state) {
  auto& ps = particle_set(state.range(0));
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  const auto law = neo_hookean();
  const auto pv = ps.store.view();
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ps.n, kParticleGrain), [&](const auto& r) {
      mpm::with_active_isa([&](auto isa) {
        for (std::size_t p = r.begin(); p < r.end(); ++p) {
          const double F[4] = {pv.F[0][p], pv.F[1][p], pv.F[2][p], pv.F[3][p]};
          double s[3];
          law.stress<2, isa>(F, s);
          for (int c = 0; c < 3; ++c) pv.s[c][p] = s[c];
        }
      });
    });
  };
  time_per_particle(state, run, ps.n);
}

void BM_Bin(benchmark::State& state) {
  auto& ps = particle_set(state.range(0));
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  std::array<const double*, 2> x{ps.store.column(mpm::Field::position, 0).data(),
                                 ps.store.column(mpm::Field::position, 1).data()};
  ps.bins.bin(x, ps.n);
  for (auto _ : state) {
    ps.bins.bin(x, ps.n);
    benchmark::ClobberMemory();
  }
  ps.bins.adopt_order();  // particles are still in block order: the order is the identity
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * ps.n));
  state.counters["particles"] = static_cast<double>(ps.n);
}

/// The reordering the engine does every 16 steps, with the order it sees then: nearly the identity.
void BM_Permute(benchmark::State& state) {
  auto& ps = particle_set(state.range(0));
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  ps.bins.adopt_order();
  const auto order = ps.bins.order();
  ps.store.permute(order);
  for (auto _ : state) {
    ps.store.permute(order);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * ps.n));
  state.counters["particles"] = static_cast<double>(ps.n);
  state.counters["columns"] = static_cast<double>(ps.store.bytes_per_particle() / sizeof(double));
}

const bool registered = [] {
  using benchmark::RegisterBenchmark;
  const std::vector<std::int64_t> sizes{100'000, 1'000'000, 4'000'000};
  auto args = [](benchmark::internal::Benchmark* b, std::int64_t n, std::vector<int> threads) {
    for (int t : threads) b->Args({n, t});
    b->ArgNames({"n", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);
  };
  for (auto n : sizes) {
    args(RegisterBenchmark("p2g/serial", BM_P2G, P2G::serial), n, {1});
    args(RegisterBenchmark("p2g/coloured", BM_P2G, P2G::coloured), n, {1, 2});
    args(RegisterBenchmark("p2g/atomic", BM_P2G, P2G::atomic), n, {1, 2});
    args(RegisterBenchmark("p2g/per_thread", BM_P2G, P2G::per_thread), n, {1, 2});
    if (n <= 1'000'000) args(RegisterBenchmark("p2g/tls", BM_P2G_TLS), n, {1, 2});
  }
  const std::int64_t n = 1'000'000;
  args(RegisterBenchmark("g2p/usl", BM_G2P, G2P::usl), n, {1, 2});
  args(RegisterBenchmark("g2p/velocity", BM_G2P, G2P::velocity), n, {1, 2});
  args(RegisterBenchmark("g2p/position_deformation", BM_G2P, G2P::position_deformation), n, {1, 2});
  args(RegisterBenchmark("fused/musl_velocity_momentum", BM_G2P, G2P::fused_velocity_momentum), n, {1, 2});
  args(RegisterBenchmark("stress/neo_hookean", BM_Stress), n, {1, 2});
  args(RegisterBenchmark("bin", BM_Bin), n, {1, 2});
  args(RegisterBenchmark("permute", BM_Permute), n, {1, 2});
  const std::pair<const char*, Partitioner> partitioners[] = {{"auto", Partitioner::auto_},
                                                              {"static", Partitioner::static_},
                                                              {"simple", Partitioner::simple},
                                                              {"affinity", Partitioner::affinity}};
  for (const std::int64_t np : {100'000, 1'000'000})
    for (const auto& [label, part] : partitioners) {
      auto* b = RegisterBenchmark((std::string("schedule/g2p_usl/") + label).c_str(), BM_GatherSchedule, part);
      for (const std::int64_t grain : {256, 2048, 16384}) b->Args({np, 2, grain});
      b->ArgNames({"n", "threads", "grain"})->UseRealTime()->Unit(benchmark::kMillisecond);
    }
  return true;
}();

}  // namespace
