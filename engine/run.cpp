#include "engine/run.hpp"

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <thread>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "engine/output_h5.hpp"
#include "engine/simulation.hpp"

namespace mpm {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// One-line progress on stderr, redrawn in place; only on a terminal, and only once a run has taken a while.
class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled && isatty(STDERR_FILENO)), start_(Clock::now()) {}
  void update(long step, long total, double t) {
    if (!enabled_) return;
    const double elapsed = seconds_since(start_);
    if (elapsed < 2.0 || elapsed - last_ < 0.5) return;
    last_ = elapsed;
    const double frac = static_cast<double>(step) / total;
    std::fprintf(stderr, "\r  step %ld/%ld  t = %.4g s  %5.1f%%  elapsed %.0f s  eta %.0f s   ", step, total, t,
                 100 * frac, elapsed, frac > 0 ? elapsed * (1 - frac) / frac : 0.0);
    shown_ = true;
  }
  ~Progress() {
    if (shown_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  bool shown_ = false;
  Clock::time_point start_;
  double last_ = 0.0;
};

template <int Dim>
std::vector<ColumnView> columns_of(const ParticleStore<Dim>& store) {
  std::vector<ColumnView> cols;
  for (const auto& name : store.column_names()) cols.push_back({name, store.column(name)});
  return cols;
}

template <int Dim>
RunResult run_dim(const Scene& scene, const RunOptions& options, int threads) {
  RunResult result;
  Simulation<Dim> sim(scene);  // SceneError escapes: status 2, nothing written yet

  const std::string out_path = options.out.empty() ? scene.output.file : options.out;
  std::optional<H5Writer> out;
  std::vector<std::string> metric_names{"step", "t", "kinetic_energy", "strain_energy", "total_energy",
                                        "mass_rel_max", "momentum_rel_max"};
  if (sim.has_exact())
    for (const char* e : {"displacement_rms", "velocity_rms", "stress_rms"}) metric_names.push_back(e);
  if (!out_path.empty()) {
    out.emplace(out_path, scene.source.dump(), Dim);
    out->set_metric_names(metric_names);
  }
  const long total = sim.steps_total();
  const long metrics_every = std::max(1L, total / 200);
  const long snapshot_every = scene.output.every > 0 ? scene.output.every : total;

  auto record_metrics = [&] {
    if (!out) return;
    const Energy e = sim.energy();
    std::vector<double> row{static_cast<double>(sim.steps_done()), sim.time(), e.kinetic, e.strain, e.total(),
                            sim.conservation().mass_rel_max, sim.conservation().momentum_rel_max};
    if (sim.has_exact()) {
      const RunErrors err = sim.errors();
      row.insert(row.end(), {err.displacement_rms, err.velocity_rms, err.stress_rms});
    }
    out->add_metrics(row);
  };
  auto snapshot = [&] {
    if (out) out->write_snapshot(sim.steps_done(), sim.time(), columns_of(sim.particles()));
  };

  const Energy e0 = sim.energy();
  double drift_max = 0.0;
  record_metrics();
  snapshot();
  Progress progress(!options.quiet);
  double stepping_s = 0.0;
  try {
    while (!sim.finished()) {
      const auto t0 = Clock::now();
      sim.step();
      stepping_s += seconds_since(t0);
      const long s = sim.steps_done();
      if (s % metrics_every == 0 || sim.finished()) {
        record_metrics();
        if (e0.total() > 0) drift_max = std::max(drift_max, std::abs(sim.energy().total() - e0.total()) / e0.total());
      }
      if (s % snapshot_every == 0 || sim.finished()) snapshot();
      progress.update(s, total, sim.time());
    }
  } catch (const UnstableRun& e) {
    result.status = exit_unstable;
    result.message = e.what();
    // the state that failed is kept for inspection beside the last good snapshot
    snapshot();
  }

  auto& j = result.summary;
  j["status"] = result.status == exit_ok ? "ok" : "unstable";
  if (!result.message.empty()) j["reason"] = result.message;
  j["steps"] = sim.steps_done();
  j["t"] = sim.time();
  j["dt"] = sim.dt();
  j["particles"] = sim.particles().size();
  j["threads"] = threads;
  j["wall_s"] = stepping_s;
  j["particle_steps_per_s"] =
      stepping_s > 0 ? static_cast<double>(sim.particles().size()) * sim.steps_done() / stepping_s : 0.0;
  if (sim.has_exact() && result.status == exit_ok) {
    const RunErrors err = sim.errors();
    j["errors"] = {{"displacement_rms", err.displacement_rms},
                   {"velocity_rms", err.velocity_rms},
                   {"stress_rms", err.stress_rms}};
  }
  j["conservation"] = {{"mass_rel_max", sim.conservation().mass_rel_max},
                       {"momentum_rel_max", sim.conservation().momentum_rel_max}};
  j["energy"] = {{"initial", e0.total()}, {"drift_rel_max", drift_max}};
  j["fallbacks"] = {{"neighbour", 0}, {"degree", 0}, {"constant", 0}};
  j["pipeline"] = sim.pipeline();
  j["columns"] = sim.particles().column_names();
  j["bytes_per_particle"] = sim.particles().bytes_per_particle();
  if (out) {
    out->set_attribute("summary", j.dump());
    out->close();
    j["output"] = out->path();
  }
  return result;
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  try {
    return scene.dimension == 1 ? run_dim<1>(scene, options, threads) : run_dim<2>(scene, options, threads);
  } catch (const SceneError& e) {
    RunResult r;
    r.status = exit_invalid;
    r.message = e.what();
    r.summary = {{"status", "invalid"}, {"reason", r.message}};
    return r;
  }
}

}  // namespace mpm
