#pragma once
// A study (DESIGN.md, "Command line" contract: `mpm study`): one scene run over the cross product of several
// varied keys, each run in-process through run_scene(). Every run becomes one row of a table — a run that fails
// (invalid, unstable, or throwing) is a row with its status and reason, never a failed study. The table is written
// as DIR/study.csv and DIR/study.h5 and printed to a stream as rows finish; plots come from tools/plot_study.py.
//
// study.h5 layout (h5py reads it directly):
//   /                 attributes: scene (the base scene as JSON text, after --set), varied_keys (string array),
//                     vary (JSON object: key -> list of the values as given), columns (string array: the table's
//                     columns in CSV order), repeat, threads
//   /table/<column>   one dataset per column, all of length rows: the varied keys and status, reason as UTF-8
//                     strings (a varied value as in the CSV: a string bare, anything else as compact JSON);
//                     steps, particles as int64 (-1: not known); everything else float64 (NaN: not known).
//                     Besides the CSV columns: cell_size (smallest length/cells over the axes, m) and
//                     exit_status (0 ok, 1 failed, 2 invalid, 3 unstable).
#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "engine/run.hpp"

namespace mpm {

/// One `--vary KEY=V1,V2,...`: the dotted key and the value texts (each parsed like a `--set` value).
struct StudyAxis {
  std::string key;
  std::vector<std::string> values;
};

/// Splits at top-level commas only: commas inside [], {} or a "string" do not split, so `[8,8],[16,16]` is two
/// values. Values are trimmed of surrounding blanks. Throws SceneError (naming `what`) for an empty value or
/// unbalanced brackets or quotes.
std::vector<std::string> split_top_level(const std::string& text, const std::string& what = "--vary");

/// Parses `KEY=V1,V2,...` into an axis. Throws SceneError for a missing key or value list.
StudyAxis parse_vary(const std::string& assignment);

/// The cross product of axes with the given sizes, as index tuples: the first axis varies slowest, the last
/// fastest (nested loops in the order of the --vary options). No axes: one empty tuple; an empty axis: none.
std::vector<std::vector<std::size_t>> cross_product(const std::vector<std::size_t>& sizes);

/// How a varied value appears in the table: a JSON string without its quotes, anything else as compact JSON,
/// text that is not JSON as it is.
std::string display_value(const std::string& value_text);

/// Checks a study before anything runs: the base scene must parse, and so must the base scene with each varied
/// value applied alone. Throws SceneError naming the key and the value.
void validate_study(const nlohmann::json& base, const std::vector<StudyAxis>& axes);

struct StudyOptions {
  int repeat = 1;             ///< runs per row; wall time is the median, the rest comes from the last run
  int threads = 0;            ///< 0: all cores
  std::string out_dir;        ///< created if missing
  std::ostream* log = nullptr;  ///< the aligned table with a progress count, as rows finish; nullptr: silent
};

/// One row of the table. Numbers that a run did not produce are NaN (steps, particles: -1).
struct StudyRow {
  std::vector<std::string> values;  ///< display_value() of each axis' value
  double wall_s = 0, particle_steps_per_s = 0;
  double displacement_rms = 0, velocity_rms = 0, stress_rms = 0;
  double displacement_rel_l2 = 0, stress_rel_l2 = 0;  ///< thesis Figs 5.12–5.14
  double mass_rel_max = 0, momentum_rel_max = 0, fallbacks = 0;
  long steps = -1, particles = -1;
  double cell_size = 0;        ///< smallest grid.length / grid.cells over the axes, m
  std::string status;          ///< "ok", "unstable", "invalid" or "failed"
  std::string reason;          ///< empty when ok
  int exit_status = exit_ok;   ///< the status run_scene() would give: 0, 1, 2, 3
};

struct StudyResult {
  std::vector<std::string> keys;  ///< the varied keys, in order
  std::vector<StudyRow> rows;     ///< in cross-product order
  std::string csv_path, h5_path;
};

/// The CSV columns: the varied keys, then wall_s ... reason (see the contract).
std::vector<std::string> study_columns(const std::vector<std::string>& keys);

/// Runs every combination (base scene + the combination's values), without per-run output files or progress,
/// and writes DIR/study.csv and DIR/study.h5. Calls validate_study() first (SceneError: nothing ran or was
/// written). Throws std::runtime_error (or OutputError) when the directory or the files cannot be written.
StudyResult run_study(const nlohmann::json& base, const std::vector<StudyAxis>& axes, const StudyOptions& options);

/// Where tools/plot_study.py is: beside the executable's source tree (../../tools from the executable's
/// directory, as in a build tree), then the tools/ directory of the source tree this file was compiled from.
/// Empty if not found.
std::string find_plot_script();

/// Runs `/usr/bin/python3 SCRIPT DIR/study.h5 --out DIR`. Returns true if the plots were made; otherwise prints a
/// note on `note` (python3 or the script missing, or the script failed, e.g. no matplotlib) and returns false.
bool plot_study(const StudyResult& result, const std::string& out_dir, std::ostream& note);

/// Everything `mpm study` does, returning its exit status: 0 the study completed (even with failed rows), 2 invalid
/// arguments or base scene (nothing run), 1 anything else. Messages go to stdout (table) and stderr (errors).
struct StudyCommand {
  std::string scene_path;
  std::vector<std::string> vary;  ///< the --vary arguments, KEY=V1,V2,...
  std::vector<std::string> sets;  ///< the --set arguments, applied to the base scene first
  int repeat = 1;
  int threads = 0;
  std::string out_dir;  ///< empty: study-<scene file stem>
  bool plot = true;
};
int study_command(const StudyCommand& command);

}  // namespace mpm
