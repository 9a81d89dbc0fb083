// Whole time step on a triangle mesh, MeshSimulation::step(), beside Simulation<2>::step() with the same basis
// degree on the rectangular grid: one neo-Hookean body filling the unit square with a uniform velocity, all sides
// fixed, lumped mass, direct mapping, USL, 4 particles per cell or per triangle. The mesh is made at run time
// (make_jittered_mesh: nx × nx squares split in two, interior nodes moved by up to a quarter cell) and written as
// a Gmsh file for the scene, so that its size follows the particle count.
//
//   mesh/<scheme>/n:<N>/threads:<T>    scheme: grid-linear (MPM-P1 on the rectangular grid), tri-linear (MPM-P1
//                                      on triangles), grid-bspline2 (BSMPM), tri-powell-sabin (PS-MPM)
//
// Counter particle_steps_per_s = particles x steps / wall time; set-up outside the timed loop.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <variant>

#include <benchmark/benchmark.h>
#include <nlohmann/json.hpp>

#include "bench/bench_util.hpp"
#include "engine/mesh_simulation.hpp"
#include "engine/scene.hpp"
#include "engine/simulation.hpp"
#include "engine/triangle_mesh.hpp"

namespace {

constexpr int kSteps = 16;

/// A jittered mesh of the unit square with about n/4 triangles, as a Gmsh 2.2 file in the temporary directory.
std::string mesh_file(std::int64_t n) {
  const int nx = std::max(1, static_cast<int>(std::lround(std::sqrt(n / 8.0))));
  const mpm::TriangleMesh mesh = mpm::make_jittered_mesh({1.0, 1.0}, nx, nx, 0.25, 1);
  const std::string path = (std::filesystem::temp_directory_path() / ("bench_mesh_" + std::to_string(nx) + ".msh")).string();
  std::ofstream out(path);
  out.precision(17);
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << mesh.node_count() << "\n";
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    out << i + 1 << " " << mesh.nodes()[i][0] << " " << mesh.nodes()[i][1] << " 0\n";
  out << "$EndNodes\n$Elements\n" << mesh.triangle_count() << "\n";
  for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
    const auto& t = mesh.triangle(e);
    out << e + 1 << " 2 0 " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
  }
  out << "$EndElements\n";
  return path;
}

nlohmann::json scene_json(std::int64_t n, const std::string& scheme) {
  nlohmann::json grid{{"length", {1, 1}}};
  nlohmann::json particles;
  if (scheme.starts_with("tri-")) {
    grid["mesh"] = mesh_file(n);
    grid["basis"] = scheme.substr(4);
    particles = {{"per_cell", {scheme == "tri-powell-sabin" ? 6 : 4}}};  // PS: a share per split triangle
  } else {
    const int cells = mpm_bench::cells_for_2d(n);
    grid["cells"] = {cells, cells};
    grid["basis"] = scheme.substr(5);
    particles = {{"per_cell", {2, 2}}};
  }
  return {{"dimension", 2},
          {"grid", grid},
          {"particles", particles},
          {"material", {{"model", "neo-hookean"}, {"E", 1e6}, {"nu", 0.3}, {"density", 1000}}},
          {"bodies", {{{"box", {{0, 0}, {1, 1}}}, {"velocity", {0.1, 0.05}}}}},
          {"fixed", {"x-", "x+", "y-", "y+"}},
          {"algorithm", {{"update", "usl"}, {"mass", "lumped"}, {"mapping", "direct"}}},
          {"time", {{"cfl", 0.2}, {"end", 1000.0}}}};
}

using AnySimulation = std::variant<std::unique_ptr<mpm::Simulation<2>>, std::unique_ptr<mpm::MeshSimulation>>;

void BM_MeshStep(benchmark::State& state, const std::string& scheme) {
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(1)));
  try {
    const mpm::Scene scene = mpm::parse_scene(scene_json(state.range(0), scheme));
    AnySimulation sim = scene.grid.triangles ? AnySimulation(std::make_unique<mpm::MeshSimulation>(scene))
                                             : AnySimulation(std::make_unique<mpm::Simulation<2>>(scene));
    std::visit(
        [&](auto& s) {
          for (int k = 0; k < kSteps; ++k) s->step();  // warm-up: first touch, and the rectangular grid's reordering
          for (auto _ : state) s->step();
          const double np = static_cast<double>(s->particles().size());
          state.counters["particles"] = np;
          state.counters["particle_steps_per_s"] =
              benchmark::Counter(np * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
        },
        sim);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
  }
}

const bool registered = [] {
  for (const std::string scheme : {"grid-linear", "tri-linear", "grid-bspline2", "tri-powell-sabin"})
    for (std::int64_t n : {100'000, 1'000'000})
      benchmark::RegisterBenchmark(("mesh/" + scheme).c_str(), BM_MeshStep, scheme)
          ->Args({n, 1})
          ->Args({n, 2})
          ->ArgNames({"n", "threads"})
          ->Iterations(n >= 1'000'000 ? kSteps : 4 * kSteps)
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
