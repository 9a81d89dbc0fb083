#pragma once
// A whole run of a scene: time stepping with observation, HDF5 output, progress and the summary of the
// command-line contract (DESIGN.md). This is what `mpm run` calls, and what a library user can call too.
#include <string>

#include <nlohmann/json.hpp>

#include "engine/scene.hpp"

namespace mpm {

struct RunOptions {
  int threads = 0;            ///< 0: all cores
  std::string out;            ///< HDF5 output path; overrides output.file
  bool quiet = false;         ///< no progress line
};

/// Exit statuses of the command-line contract.
enum ExitStatus { exit_ok = 0, exit_failure = 1, exit_invalid = 2, exit_unstable = 3 };

struct RunResult {
  ExitStatus status = exit_ok;
  nlohmann::json summary;  ///< the `--summary` object
  std::string message;     ///< one line for the user when the run did not end normally
};

/// Runs a validated scene to its end time. Never throws for an unstable run: that is status 3 with the last
/// state saved; a scene it cannot run (e.g. dt above the critical step) is status 2 before any work.
RunResult run_scene(const Scene& scene, const RunOptions& options);

/// Continues the run recorded in `path` (its .partial file if the run was killed) from its last checkpoint, into
/// the same file, with the scene stored there. Status 2 if the file has no usable checkpoint. The result is
/// bitwise the run that was never interrupted.
RunResult resume_run(const std::string& path, const RunOptions& options);

}  // namespace mpm
