#pragma once
// Run output (DESIGN.md, "Output"): one HDF5 file per run holding the scene, a metrics table, particle snapshots
// and a restartable checkpoint, plus an XDMF sidecar so ParaView opens the snapshots directly.
//
// File layout:
//   /                  attributes: scene (JSON text), dimension, and whatever set_attribute() adds
//   /metrics           float64 (rows, ncols), extendible; attribute "columns" = the column names
//   /snapshots/NNNNNN  one group per snapshot (zero-padded step); attributes step, time; one float64 column each
//   /checkpoint        the latest restartable state; attributes step, time and named scalars; one column each
//   /xdmf              data for the sidecar only: ids (vertex connectivity), <step>/{geometry, velocity,
//                      displacement, stress, F} (the columns combined for ParaView) and the background: either
//                      grid/x0, x1 (, x2), the node coordinates of a rectangular grid (set_grid), or
//                      mesh/geometry (float64, nodes × 3) and mesh/topology (int32, triangles × 3), a triangular
//                      mesh (set_mesh)
//
// Crash safety comes from the name, not from HDF5: the file is written as `<path>.partial` and renamed to
// `<path>` only when it is complete, so `<path>` is never a half-written file. The HDF5 C API stays out of this
// header, so including it does not drag hdf5.h into the engine.
#include <array>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

namespace mpm {

/// Anything that went wrong writing or reading a run file; the message names the file and the HDF5 operation.
struct OutputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One named particle column for a snapshot (a view; the writer copies nothing it does not write).
struct ColumnView {
  std::string name;
  std::span<const double> values;
};

/// Writes a run's HDF5 file under `<path>.partial` and renames it to `<path>` on close(), plus the XDMF sidecar
/// xdmf_path(path). Not thread-safe: the engine writes from one thread.
class H5Writer {
 public:
  /// Creates `<path>.partial` (truncating a leftover one) with the root attributes "scene" and "dimension".
  H5Writer(std::string path, const std::string& scene_json, int dimension);
  /// Continues an existing run file (resume): copies `<path>` to `<path>.partial` and opens that for writing, so
  /// `<path>` stays intact until close(). If only `<path>.partial` exists (a killed run), it is renamed to `<path>`
  /// first and continued the same way, so it is kept if the continued run fails.
  static H5Writer append(std::string path);

  H5Writer(H5Writer&&) noexcept;
  H5Writer& operator=(H5Writer&&) noexcept;  // finishes the writer being replaced, like the destructor
  H5Writer(const H5Writer&) = delete;
  H5Writer& operator=(const H5Writer&) = delete;
  /// If close() was not called: flush + close + rename anyway (a failed run keeps its data); never throws.
  /// A write that failed (OutputError from any method that writes, e.g. on a full disk) has already closed the
  /// writer and removed `<path>.partial`: its message names the file and says what was lost.
  ~H5Writer();

  /// Column names of the metrics table, e.g. {"t","mass","momentum_x",...}; call once before add_metrics.
  /// (After append() the names are already known; calling it again with the same names is allowed.)
  void set_metric_names(std::vector<std::string> names);
  /// Appends one row (size == names.size()). Rows are buffered and written a chunk at a time and on flush.
  void add_metrics(std::span<const double> row);

  /// Writes group /snapshots/NNNNNN (zero-padded step, replacing one of the same step) with attributes step and
  /// time and one chunked, shuffled, deflated float64 dataset per column. All columns have the particle count.
  /// Columns x0, x1 (, x2) are the positions the XDMF sidecar uses as geometry; the others become XDMF attributes.
  void write_snapshot(long step, double time, std::span<const ColumnView> columns);
  /// Node coordinates of the background grid, one vector per axis (as many axes as the run's dimension), written
  /// to /xdmf/grid; the sidecar then shows the grid beside the particles in every time step. Replaces an earlier
  /// grid (a continued run sets it again) or mesh (set_mesh): a run has one background.
  void set_grid(std::span<const std::vector<double>> nodes);
  /// A triangular background mesh (2D runs): node coordinates and counter-clockwise triangles (0-based node
  /// indices), written to /xdmf/mesh; the sidecar then shows the mesh beside the particles in every time step, as
  /// set_grid does for the rectangular grid. Replaces an earlier mesh (a continued run sets it again) or grid.
  /// No nodes, no triangles or a node index out of range: OutputError naming the file (and the triangle).
  void set_mesh(std::span<const std::array<double, 2>> nodes, std::span<const std::array<int, 3>> triangles);
  /// Writes/overwrites group /checkpoint with attributes step, time, the given columns (any lengths) and the named
  /// scalar attributes; then flushes the file (H5Fflush) so the .partial file is valid after each call.
  void write_checkpoint(long step, double time, std::span<const ColumnView> columns,
                        std::span<const std::pair<std::string, double>> scalars);
  /// Sets (or replaces) a string attribute on the root group, e.g. a summary JSON or a status.
  void set_attribute(const std::string& name, const std::string& value);
  /// For resume after append(): drops the snapshots with a step after `step` and the metrics rows whose "t"
  /// column is after `time` (if there is a "t" column), so the continued run does not record them twice.
  void discard_after(long step, double time);
  /// Writes buffered metrics rows and flushes the file to disk.
  void flush();
  /// Flush, close, rename .partial -> final, write the .xdmf (also atomically: tmp + rename). Idempotent.
  void close();
  /// The final file name.
  const std::string& path() const;

 private:
  struct State;
  explicit H5Writer(std::unique_ptr<State> state);
  State& live(const char* op);  // the state of an open writer, or OutputError
  void finish_quietly() noexcept;
  std::unique_ptr<State> s_;
};

/// For a program's main(), before anything touches HDF5: no HDF5 clean-up at exit. After a write failed on a full
/// disk HDF5 may hold a file it could not close, and its exit handler crashes on it (SIGSEGV); the run file is
/// removed by then (H5Writer), so there is nothing left for that handler to flush.
void skip_hdf5_exit_handler();

/// The XDMF sidecar of a run file: `<path minus .h5>.xdmf` (or `<path>.xdmf` if it does not end in .h5).
std::string xdmf_path(const std::string& h5_path);

// Reading back (tests and resume). All throw OutputError naming the file and what failed.

/// Parses the "scene" root attribute.
nlohmann::json read_scene_attribute(const std::string& path);
/// A whole dataset as doubles, e.g. "/snapshots/000010/x0" or "/metrics" (row-major flattened).
std::vector<double> read_dataset(const std::string& path, const std::string& dataset);
/// Group names under /snapshots, in step order (empty if there are none).
std::vector<std::string> list_snapshots(const std::string& path);
/// Names of the datasets in a group, e.g. "/checkpoint", sorted by name.
std::vector<std::string> list_datasets(const std::string& path, const std::string& group);
/// A numeric attribute of an object ("/" for the root), converted to double (e.g. "/checkpoint", "step").
double read_number_attribute(const std::string& path, const std::string& object, const std::string& name);
/// A string attribute, or each element of a string-array attribute (e.g. "/metrics", "columns").
std::vector<std::string> read_string_attribute(const std::string& path, const std::string& object,
                                               const std::string& name);

}  // namespace mpm
