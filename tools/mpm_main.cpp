// The `mpm` command line (DESIGN.md, "Command line" contract): run, validate.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "engine/output_h5.hpp"
#include "engine/run.hpp"
#include "engine/scene.hpp"
#include "engine/study.hpp"
#include "kernels/isa.hpp"

namespace {

/// Loads the scene file and applies the --set overrides in order.
mpm::Scene load_with_overrides(const std::string& path, const std::vector<std::string>& sets) {
  nlohmann::json j = mpm::read_json_file(path);
  for (const auto& s : sets) mpm::apply_override(j, s);
  return mpm::parse_scene(j);
}

/// A file we can create, checked before the run (as output.file is) so that a long run does not fail at its end:
/// not a directory, and its directory exists and is writable.
void require_writable(const std::string& path, const std::string& option) {
  if (path.empty()) return;
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw mpm::SceneError(option + " = " + path + ": expected a file name, not a directory");
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  if (access(dir.c_str(), W_OK | X_OK) != 0)
    throw mpm::SceneError(option + " = " + path + ": expected a file in an existing, writable directory: " +
                          dir.string() + ": " + std::strerror(errno));
}

void write_json_atomically(const std::string& path, const nlohmann::json& j) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << '\n';
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

void print_report(const nlohmann::json& s) {
  std::printf("%s: %ld steps, %ld particles, %d threads (%s), %.3f s stepping, %.3g particle-steps/s\n",
              s["status"].get<std::string>().c_str(), s["steps"].get<long>(), s["particles"].get<long>(),
              s["threads"].get<int>(), s["isa"].get<std::string>().c_str(), s["wall_s"].get<double>(),
              s["particle_steps_per_s"].get<double>());
  if (s.contains("errors"))
    std::printf("errors (RMS): displacement %.6e  velocity %.6e  stress %.6e\n",
                s["errors"]["displacement_rms"].get<double>(), s["errors"]["velocity_rms"].get<double>(),
                s["errors"]["stress_rms"].get<double>());
  std::printf("conservation (max relative, particles vs grid): mass %.3e  momentum %.3e\n",
              s["conservation"]["mass_rel_max"].get<double>(), s["conservation"]["momentum_rel_max"].get<double>());
  std::printf("peak memory: %.1f MB, %.0f bytes per particle\n", s["peak_rss_bytes"].get<double>() / 1e6,
              s["peak_rss_bytes_per_particle"].get<double>());
  if (s.contains("output")) std::printf("output: %s\n", s["output"].get<std::string>().c_str());
}

}  // namespace

int main(int argc, char** argv) {
  mpm::skip_hdf5_exit_handler();
  CLI::App app{"mpm: B-spline material point method with conservative least-squares reconstruction"};
  app.require_subcommand(1);

  std::string scene_path, out, summary, resume;
  std::vector<std::string> sets;
  int threads = 0;
  bool quiet = false;

  auto* run = app.add_subcommand("run", "run a scene to its end time");
  run->add_option("scene", scene_path, "scene file (JSON)");
  run->add_option("--set", sets, "override one scene key: KEY=VALUE (dotted path, JSON value)");
  run->add_option("--threads", threads, "worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  run->add_option("--out", out, "HDF5 output file (overrides output.file)");
  run->add_option("--summary", summary, "write the run summary as JSON to this file");
  run->add_option("--resume", resume, "continue from the last checkpoint in this HDF5 file");
  run->add_flag("--quiet", quiet, "no progress line");

  auto* validate = app.add_subcommand("validate", "check a scene file, exit 0 if valid, 2 if not");
  validate->add_option("scene", scene_path, "scene file (JSON)")->required();
  validate->add_option("--set", sets, "override one scene key: KEY=VALUE");

  mpm::StudyCommand study_args;
  auto* study = app.add_subcommand("study", "run a scene over the cross product of varied keys: table + plots");
  study->add_option("scene", study_args.scene_path, "scene file (JSON)")->required();
  study->add_option("--vary", study_args.vary, "vary one key: KEY=V1,V2,... (split at top-level commas)")
      ->required()->allow_extra_args(false);
  study->add_option("--set", study_args.sets, "override one scene key: KEY=VALUE")->allow_extra_args(false);
  study->add_option("--repeat", study_args.repeat, "runs per row; wall time is their median")->check(CLI::Range(1, 1000));
  study->add_option("--threads", study_args.threads, "worker threads (default: all cores)")->check(CLI::Range(1, 1024));
  study->add_option("--out", study_args.out_dir, "output directory (default: study-<scene name>)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return mpm::exit_invalid;
  }

  if (const char* isa = std::getenv("MPM_ISA")) {  // the kernels' instruction set (kernels/isa.hpp)
    try {
      mpm::set_active_isa(mpm::isa_for(isa));
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "mpm: %s\n", e.what());
      return mpm::exit_invalid;
    }
  }
  if (study->parsed()) return mpm::study_command(study_args);

  try {
    if (validate->parsed()) {
      const mpm::Scene scene = load_with_overrides(scene_path, sets);
      std::printf("%s: valid %dD scene\n", scene_path.c_str(), scene.dimension);
      return mpm::exit_ok;
    }
    if (resume.empty() == scene_path.empty()) {
      std::fprintf(stderr, "mpm run: give either a scene file or --resume FILE.h5\n");
      return mpm::exit_invalid;
    }
    require_writable(summary, "--summary");
    require_writable(out, "--out");
    mpm::RunResult r;
    if (!resume.empty()) {
      r = mpm::resume_run(resume, {threads, "", quiet});
    } else {
      const mpm::Scene scene = load_with_overrides(scene_path, sets);
      r = mpm::run_scene(scene, {threads, out, quiet});
    }
    if (r.status == mpm::exit_invalid) {
      std::fprintf(stderr, "%s\n", r.message.c_str());
      return r.status;
    }
    if (!summary.empty()) write_json_atomically(summary, r.summary);
    if (!quiet) print_report(r.summary);
    if (r.status != mpm::exit_ok) std::fprintf(stderr, "mpm: %s\n", r.message.c_str());
    return r.status;
  } catch (const mpm::SceneError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return mpm::exit_invalid;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpm: %s\n", e.what());
    return mpm::exit_failure;
  }
}
