#include "engine/run.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <optional>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "engine/energy_balance.hpp"
#include "engine/mesh_simulation.hpp"
#include "engine/output_h5.hpp"
#include "engine/simulation.hpp"
#include "kernels/isa.hpp"

namespace mpm {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// steps between backups used to recover the last good state (StateBackup); a multiple of the engine's reorder
// period (16), so a backup falls on a step that bins afresh and the replay from it repeats the run bit for bit
constexpr long backup_every = 64;

/// Steps between samples of the energy-balance guard: about 200 per run (as the metrics), at most backup_every,
/// and a power of two so that every backup falls on a sample (the last good state is then a sample that passed).
long guard_interval(long total_steps) {
  long g = 1;
  while (2 * g <= std::min(backup_every, std::max(1L, total_steps / 200))) g *= 2;
  return g;
}

/// The per-step check of time.cfl: dt was fixed at the start from the initial state; it must stay below the
/// critical step of the current one (same definition, Simulation::critical_step).
template <class Sim>
void check_cfl(const Sim& sim) {
  const CriticalStep c = sim.critical_step();
  if (sim.dt() <= c.dt) return;
  const auto& s = sim.particles();
  char buf[720];
  int n = std::snprintf(buf, sizeof buf,
                        "CFL violated at step %ld (t = %.6g s): dt = %.6g s exceeds the critical step %s = "
                        "%.6g s by a factor %.4g (h = %.4g m); particle %zu at x = (",
                        sim.steps_done(), sim.time(), sim.dt(), critical_step_formula(c).c_str(), c.dt,
                        sim.dt() / c.dt, c.h, c.particle);
  for (int d = 0; d < Sim::dim && n < static_cast<int>(sizeof buf); ++d)
    n += std::snprintf(buf + n, sizeof buf - n, "%s%.6g", d ? ", " : "", s.column(Field::position, d)[c.particle]);
  if (n < static_cast<int>(sizeof buf))
    std::snprintf(buf + n, sizeof buf - n,
                  "): J = %.4g, wave speed c = %.6g m/s, |v| = %.6g m/s (time.cfl = %g of the initial critical step; "
                  "the material stiffened or the particle sped up: lower time.cfl)",
                  c.J, c.wave_speed, c.speed, *sim.scene().time.cfl);
  throw UnstableRun(buf);
}

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

/// Peak resident set of this process so far (getrusage: the kernel's high-water mark, in KiB on Linux).
double peak_resident_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return 1024.0 * static_cast<double>(usage.ru_maxrss);
}

/// SIGINT / SIGTERM request a clean stop (checkpoint, close the file) at the end of the current step.
std::atomic<int> stop_signal{0};
extern "C" void request_stop(int sig) { stop_signal.store(sig); }

class StopOnSignals {
 public:
  StopOnSignals() {
    stop_signal.store(0);
    old_int_ = std::signal(SIGINT, request_stop);
    old_term_ = std::signal(SIGTERM, request_stop);
  }
  ~StopOnSignals() {
    std::signal(SIGINT, old_int_);
    std::signal(SIGTERM, old_term_);
  }

 private:
  void (*old_int_)(int);
  void (*old_term_)(int);
};

template <class Store>
std::vector<ColumnView> columns_of(const Store& store) {
  std::vector<ColumnView> cols;
  for (const auto& name : store.column_names()) cols.push_back({name, store.column(name)});
  return cols;
}

/// The normalisers of the relative L2 errors: the largest norm of the exact displacement and stress over the run
/// so far (sampled with the metrics). A vibration's exact field passes through zero; dividing by its norm at that
/// instant gave 1.6e13 for the plate at t = 0.04 s.
struct ExactScale {
  double displacement = 0.0, stress = 0.0;
  void sample(const RunErrors& e) {
    displacement = std::max(displacement, e.displacement_exact_l2);
    stress = std::max(stress, e.stress_exact_l2);
  }
  static double relative(double error, double scale) { return scale > 0 ? error / scale : std::nan(""); }
};

/// Where a run continues from: a state, the energy balance so far and the worst drift so far.
struct StartPoint {
  SimulationState state;
  EnergyBalance::State balance;
  double drift_max = 0.0;
  ExactScale exact_scale;
};

/// Written from the particle columns themselves: a copy of the state would add the store's size to the peak memory.
template <class Sim>
void write_checkpoint(H5Writer& out, const Sim& sim, const EnergyBalance& balance, double drift_max,
                      const ExactScale& scale) {
  const Conservation& c = sim.conservation();
  const EnergyBalance::State& b = balance.state();
  const std::pair<std::string, double> scalars[] = {{"mass_rel_max", c.mass_rel_max},
                                                    {"momentum_rel_max", c.momentum_rel_max},
                                                    {"energy0", b.energy0},
                                                    {"drift_rel_max", drift_max},
                                                    {"external_work", b.work},
                                                    {"external_power", b.power},
                                                    {"energy_sample_time", b.time},
                                                    {"energy_scale", b.scale},
                                                    {"energy_excess_max", b.excess_max},
                                                    {"energy_excess_min", b.excess_min},
                                                    {"displacement_exact_l2_max", scale.displacement},
                                                    {"stress_exact_l2_max", scale.stress}};
  out.write_checkpoint(sim.steps_done(), sim.time(), columns_of(sim.particles()), scalars);
}

/// The state a failed run is replayed from (every backup_every steps), kept in an unlinked temporary file
/// (TMPDIR or /tmp; gone when the run ends) instead of in memory: a second copy of the particle store in memory
/// was 120 of the 297 bytes per particle of a 2D direct run at 1e6 particles. The kernel's page cache holds the
/// file while memory is free and writes it out when it is not. Cost: one sequential write of the store per
/// backup, read back only after a failure.
class StateBackup {
 public:
  StateBackup() : file_(std::tmpfile()) {
    if (!file_) fail("create");
  }
  ~StateBackup() { std::fclose(file_); }
  StateBackup(const StateBackup&) = delete;
  StateBackup& operator=(const StateBackup&) = delete;

  template <class Sim>
  void save(const Sim& sim) {
    state_.step = sim.steps_done();
    state_.time = sim.time();
    state_.conservation = sim.conservation();
    state_.names = sim.particles().column_names();
    sizes_.clear();
    std::rewind(file_);
    for (const auto& name : state_.names) {
      const auto col = sim.particles().column(name);
      if (std::fwrite(col.data(), sizeof(double), col.size(), file_) != col.size()) fail("write");
      sizes_.push_back(col.size());
    }
    if (std::fflush(file_) != 0) fail("write");
  }
  /// The saved state, read back from the file.
  SimulationState load() {
    SimulationState st = state_;
    std::rewind(file_);
    for (const std::size_t n : sizes_) {
      st.columns.emplace_back(n);
      if (std::fread(st.columns.back().data(), sizeof(double), n, file_) != n) fail("read");
    }
    return st;
  }
  long step() const { return state_.step; }

 private:
  [[noreturn]] static void fail(const char* what) {
    throw std::runtime_error(std::string("cannot ") + what + " the last-good-state backup (a temporary file in " +
                             "TMPDIR or /tmp): " + std::strerror(errno));
  }
  std::FILE* file_;
  SimulationState state_;  ///< step, time, conservation and column names; the columns are in the file
  std::vector<std::size_t> sizes_;
};

StartPoint read_checkpoint(const std::string& file) {
  StartPoint sp;
  sp.state.step = static_cast<long>(read_number_attribute(file, "/checkpoint", "step"));
  sp.state.time = read_number_attribute(file, "/checkpoint", "time");
  sp.state.conservation = {read_number_attribute(file, "/checkpoint", "mass_rel_max"),
                           read_number_attribute(file, "/checkpoint", "momentum_rel_max")};
  const auto scalar = [&](const char* name) { return read_number_attribute(file, "/checkpoint", name); };
  sp.drift_max = scalar("drift_rel_max");
  sp.balance = {scalar("energy0"),      scalar("external_work"),     scalar("external_power"),
                scalar("energy_sample_time"), scalar("energy_scale"), scalar("energy_excess_max"),
                scalar("energy_excess_min")};
  // absent from checkpoints of older runs: the maximum then restarts from the resumed state
  const auto optional = [&](const char* name) {
    try {
      return scalar(name);
    } catch (const OutputError&) {
      return 0.0;
    }
  };
  sp.exact_scale = {optional("displacement_exact_l2_max"), optional("stress_exact_l2_max")};
  sp.state.names = list_datasets(file, "/checkpoint");
  for (const auto& name : sp.state.names) sp.state.columns.push_back(read_dataset(file, "/checkpoint/" + name));
  return sp;
}

/// Opens the run file once the scene is known to be runnable (so an invalid scene writes nothing).
using OpenOutput = std::function<std::optional<H5Writer>()>;

/// One run, phase by phase: set up (the simulation, the run file, the guards; or the state to resume), step to
/// the end (guards, metrics, snapshots, checkpoints, signals), recover the last good state when the run became
/// unstable, and summarise.
template <class Sim>
class Run {
 public:
  Run(const Scene& scene, const RunOptions& options, int threads, const OpenOutput& open_output,
      const std::optional<StartPoint>& start)
      : scene_(scene), threads_(threads), sim_(scene),  // SceneError escapes: status 2
        out_(open_output()), balance_(scene.time.energy_tolerance, sim_.energy().total(), sim_.external_power(),
                                      sim_.time()),
        progress_(!options.quiet) {
    if (out_) describe_output();
    if (start) {
      sim_.load_state(start->state);
      balance_ = EnergyBalance(scene.time.energy_tolerance, start->balance);
      drift_max_ = start->drift_max;
      exact_scale_ = start->exact_scale;
      if (out_) out_->discard_after(sim_.steps_done(), sim_.time());
    }
    energy0_ = balance_.state().energy0;
    total_ = sim_.steps_total();
    metrics_every_ = std::max(1L, total_ / 200);
    guard_every_ = guard_interval(total_);
    snapshot_every_ = scene.output.every > 0 ? scene.output.every : total_;
    if (!start) {
      record_metrics(sim_.energy());
      snapshot();
    }
    last_balanced_ = sim_.steps_done();
    backup_.save(sim_);
  }

  /// Steps to the end, or to a signal (then a checkpoint is written); throws UnstableRun.
  void step_to_end() {
    bool checkpoint_due = false;
    while (!sim_.finished()) {
      if (sim_.steps_done() % backup_every == 0) backup_.save(sim_);
      const auto t0 = Clock::now();
      sim_.step();
      stepping_s_ += seconds_since(t0);
      ++steps_timed_;
      const long s = sim_.steps_done();
      if (scene_.time.cfl) check_cfl(sim_);
      check_and_record(s);
      if (s % snapshot_every_ == 0 || sim_.finished()) snapshot();
      // checkpoints (periodic, or on a signal) wait for the next step that bins the particles afresh, at most
      // reorder-period − 1 steps: a run resumed from any other step would bin them differently and end up
      // different in the last bits (Simulation::next_step_bins)
      checkpoint_due = checkpoint_due || (out_ && scene_.output.checkpoint_every > 0 && s % scene_.output.checkpoint_every == 0);
      if (checkpoint_due && sim_.next_step_bins() && !sim_.finished()) {
        write_checkpoint(*out_, sim_, balance_, drift_max_, exact_scale_);
        checkpoint_due = false;
      }
      progress_.update(s, total_, sim_.time());
      if (const int sig = stop_signal.load(); sig != 0 && !sim_.finished() && sim_.next_step_bins()) {
        stop_by_signal(sig);
        return;
      }
    }
  }

  /// Replays from the last backup up to the last good step: the run is deterministic, so this is the last good
  /// state exactly; it is saved as a snapshot (and checkpoint) beside the earlier ones. A step that threw is not
  /// counted, so the last good state is the one before it; when the energy balance failed, it is the last sample
  /// that held (backups fall on samples, so it is never before the backup).
  void recover_last_good_state(const UnstableRun& e) {
    result_.status = exit_unstable;
    result_.message = e.what();
    const long last_good = energy_failed_ ? std::max(last_balanced_, backup_.step()) : sim_.steps_done();
    sim_.load_state(backup_.load());
    while (sim_.steps_done() < last_good) sim_.step();
    snapshot();
    if (out_) {
      write_checkpoint(*out_, sim_, balance_, drift_max_, exact_scale_);
      out_->set_attribute("status", "unstable: " + result_.message);
    }
    result_.message += "; last good state (step " + std::to_string(sim_.steps_done()) + ") saved";
  }

  /// The summary (README: --summary), also stored in the run file, which is closed.
  RunResult finish() {
    auto& j = result_.summary;
    j["status"] = result_.status == exit_ok ? "ok" : result_.status == exit_unstable ? "unstable" : "interrupted";
    if (!result_.message.empty()) j["reason"] = result_.message;
    j["steps"] = sim_.steps_done();
    j["t"] = sim_.time();
    j["dt"] = sim_.dt();
    j["particles"] = sim_.particles().size();
    j["threads"] = threads_;
    j["isa"] = isa_name(active_isa());
    j["wall_s"] = stepping_s_;
    j["particle_steps_per_s"] =
        stepping_s_ > 0 ? static_cast<double>(sim_.particles().size()) * steps_timed_ / stepping_s_ : 0.0;
    if (sim_.has_exact() && result_.status == exit_ok) {
      const RunErrors err = sim_.errors();
      j["errors"] = {{"displacement_rms", err.displacement_rms},
                     {"velocity_rms", err.velocity_rms},
                     {"stress_rms", err.stress_rms},
                     {"displacement_rel_l2", ExactScale::relative(err.displacement_l2, exact_scale_.displacement)},
                     {"stress_rel_l2", ExactScale::relative(err.stress_l2, exact_scale_.stress)}};
    }
    j["conservation"] = {{"mass_rel_max", sim_.conservation().mass_rel_max},
                         {"momentum_rel_max", sim_.conservation().momentum_rel_max}};
    const EnergyBalance::State& eb = balance_.state();
    j["energy"] = {{"initial", energy0_},           {"drift_rel_max", drift_max_},
                   {"external_work", eb.work},      {"balance_gain_max", eb.excess_max},
                   {"balance_loss_max", -eb.excess_min}, {"tolerance", scene_.time.energy_tolerance}};
    const FallbackCounts fb = sim_.fallbacks();
    j["fallbacks"] = {{"neighbour", fb.neighbour}, {"degree", fb.degree}, {"constant", fb.constant}, {"empty", fb.empty}};
    j["pipeline"] = sim_.pipeline();
    j["columns"] = sim_.particles().column_names();
    j["bytes_per_particle"] = sim_.particles().bytes_per_particle();
    const double rss = peak_resident_bytes();
    j["peak_rss_bytes"] = rss;
    j["peak_rss_bytes_per_particle"] = rss / static_cast<double>(sim_.particles().size());
    if (out_) {
      out_->set_attribute("summary", j.dump());
      out_->close();
      j["output"] = out_->path();
    }
    return result_;
  }

 private:
  /// The metrics' columns and the background: the knots of the uniform grid on [0, length], or the triangle mesh.
  void describe_output() {
    std::vector<std::string> names{"step", "t", "kinetic_energy", "strain_energy", "total_energy",
                                   "mass_rel_max", "momentum_rel_max"};
    if (sim_.has_exact())
      for (const char* e : {"displacement_rms", "velocity_rms", "stress_rms"}) names.push_back(e);
    out_->set_metric_names(names);
    if constexpr (std::is_same_v<Sim, MeshSimulation>) {
      out_->set_mesh(sim_.mesh().nodes(), sim_.mesh().triangles());
    } else {
      std::vector<std::vector<double>> nodes(Sim::dim);
      for (int d = 0; d < Sim::dim; ++d)
        for (int i = 0; i <= scene_.grid.cells[d]; ++i)
          nodes[d].push_back(scene_.grid.length[d] * i / scene_.grid.cells[d]);
      out_->set_grid(nodes);
    }
  }

  /// The energy guard and the metrics, each at its own interval (and at the end).
  void check_and_record(long s) {
    const bool guard_now = s % guard_every_ == 0 || sim_.finished();
    const bool metrics_now = s % metrics_every_ == 0 || sim_.finished();
    if (!guard_now && !metrics_now) return;
    const Energy e = sim_.energy();
    if (guard_now) {
      if (auto why = balance_.sample(s, sim_.time(), e.total(), sim_.external_power())) {
        energy_failed_ = true;
        throw UnstableRun(*why);
      }
      last_balanced_ = s;
    }
    if (metrics_now) record_metrics(e);
  }

  void record_metrics(const Energy& e) {
    if (energy0_ > 0) drift_max_ = std::max(drift_max_, std::abs(e.total() - energy0_) / energy0_);
    const std::optional<RunErrors> err = sim_.has_exact() ? std::optional(sim_.errors()) : std::nullopt;
    if (err) exact_scale_.sample(*err);
    if (!out_) return;
    std::vector<double> row{static_cast<double>(sim_.steps_done()), sim_.time(), e.kinetic, e.strain, e.total(),
                            sim_.conservation().mass_rel_max, sim_.conservation().momentum_rel_max};
    if (err) row.insert(row.end(), {err->displacement_rms, err->velocity_rms, err->stress_rms});
    out_->add_metrics(row);
  }

  void snapshot() {
    if (out_) out_->write_snapshot(sim_.steps_done(), sim_.time(), columns_of(sim_.particles()));
  }

  void stop_by_signal(int sig) {
    result_.status = exit_failure;
    result_.message = "stopped by signal " + std::to_string(sig) + " at step " + std::to_string(sim_.steps_done());
    if (!out_) return;
    write_checkpoint(*out_, sim_, balance_, drift_max_, exact_scale_);
    result_.message += "; checkpoint written to " + out_->path() + " (continue with: mpm run --resume " +
                       out_->path() + ")";
  }

  const Scene& scene_;
  const int threads_;
  RunResult result_;
  Sim sim_;
  std::optional<H5Writer> out_;
  EnergyBalance balance_;
  double drift_max_ = 0.0, energy0_ = 0.0;
  ExactScale exact_scale_;
  long total_ = 0, metrics_every_ = 1, guard_every_ = 1, snapshot_every_ = 1;
  long last_balanced_ = 0;  ///< the last step whose energy balance was checked and held
  bool energy_failed_ = false;
  StateBackup backup_;
  Progress progress_;
  StopOnSignals signals_;
  double stepping_s_ = 0.0;
  long steps_timed_ = 0;
};

template <class Sim>
RunResult run_with(const Scene& scene, const RunOptions& options, int threads, const OpenOutput& open_output,
                   const std::optional<StartPoint>& start) {
  Run<Sim> run(scene, options, threads, open_output, start);
  try {
    run.step_to_end();
  } catch (const UnstableRun& e) {
    run.recover_last_good_state(e);
  }
  return run.finish();
}

/// The simulation a scene runs: on its triangle mesh, or on the rectangular grid of its dimension.
RunResult run_scene_from(const Scene& scene, const RunOptions& options, int threads, const OpenOutput& open_output,
                         const std::optional<StartPoint>& start) {
  if (scene.grid.triangles) return run_with<MeshSimulation>(scene, options, threads, open_output, start);
  return scene.dimension == 1 ? run_with<Simulation<1>>(scene, options, threads, open_output, start)
                              : run_with<Simulation<2>>(scene, options, threads, open_output, start);
}

RunResult invalid(const std::string& message) {
  RunResult r;
  r.status = exit_invalid;
  r.message = message;
  r.summary = {{"status", "invalid"}, {"reason", message}};
  return r;
}

template <class F>
RunResult with_threads(const RunOptions& options, F&& run) {
  const int threads = options.threads > 0 ? options.threads : tbb::info::default_concurrency();
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  try {
    return run(threads);
  } catch (const SceneError& e) {
    return invalid(e.what());
  }
}

}  // namespace

RunResult run_scene(const Scene& scene, const RunOptions& options) {
  return with_threads(options, [&](int threads) {
    const std::string path = options.out.empty() ? scene.output.file : options.out;
    const OpenOutput open = [&]() -> std::optional<H5Writer> {
      if (path.empty()) return std::nullopt;
      return H5Writer(path, scene.source.dump(), scene.dimension);
    };
    return run_scene_from(scene, options, threads, open, std::nullopt);
  });
}

RunResult resume_run(const std::string& path, const RunOptions& options) {
  return with_threads(options, [&](int threads) {
    const bool killed = !std::filesystem::exists(path) && std::filesystem::exists(path + ".partial");
    const std::string file = killed ? path + ".partial" : path;
    if (!std::filesystem::exists(file)) return invalid("--resume " + path + ": no such run file");
    StartPoint start;
    Scene scene;
    try {
      scene = parse_scene(read_scene_attribute(file));
      start = read_checkpoint(file);
    } catch (const OutputError& e) {
      return invalid("--resume " + path + ": no usable checkpoint (" + std::string(e.what()) + ")");
    }
    const OpenOutput open = [&]() -> std::optional<H5Writer> { return H5Writer::append(path); };
    return run_scene_from(scene, options, threads, open, start);
  });
}

}  // namespace mpm
