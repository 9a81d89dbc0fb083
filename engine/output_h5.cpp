// HDF5 run file and XDMF sidecar (see output_h5.hpp for the layout). HDF5 C API only.
#include "engine/output_h5.hpp"

#include "engine/h5_handle.hpp"

#include <fcntl.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

namespace mpm {
namespace {

using namespace h5;

namespace fs = std::filesystem;

constexpr hsize_t kMaxChunk = hsize_t{1} << 16;  // elements per chunk of a particle column (512 KiB of doubles)
constexpr hsize_t kMetricsChunkValues = 4096;    // values per chunk of /metrics (32 KiB), also the write batch
constexpr const char* kCheckpointTmp = "/checkpoint.new";


bool exists(hid_t loc, const std::string& name, const std::string& file) {
  const htri_t e = H5Lexists(loc, name.c_str(), H5P_DEFAULT);
  if (e < 0) fail(file, "H5Lexists('" + name + "')");
  return e > 0;
}

void remove_link(hid_t loc, const std::string& name, const std::string& file) {
  if (exists(loc, name, file)) check(H5Ldelete(loc, name.c_str(), H5P_DEFAULT), file, "H5Ldelete('" + name + "')");
}

Handle create_group(hid_t loc, const std::string& name, const std::string& file) {
  return own(H5Gcreate2(loc, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, file,
             "H5Gcreate2('" + name + "')");
}

// ---- attributes ---------------------------------------------------------------------------------------------

Handle string_type(H5T_cset_t cset, const std::string& file) {
  Handle t = own(H5Tcopy(H5T_C_S1), H5Tclose, file, "H5Tcopy");
  check(H5Tset_size(t.get(), H5T_VARIABLE), file, "H5Tset_size");
  check(H5Tset_cset(t.get(), cset), file, "H5Tset_cset");
  return t;
}

// Attributes are replaced rather than updated, since a new value may have another type or shape.
void drop_attribute(hid_t obj, const std::string& name, const std::string& file) {
  const htri_t e = H5Aexists(obj, name.c_str());
  if (e < 0) fail(file, "H5Aexists('" + name + "')");
  if (e > 0) check(H5Adelete(obj, name.c_str()), file, "H5Adelete('" + name + "')");
}

// Variable-length UTF-8 strings: no size limit (the scene can be long) and h5py reads them as str.
void write_strings(hid_t obj, const std::string& name, const std::vector<std::string>& values, bool scalar,
                   const std::string& file) {
  drop_attribute(obj, name, file);
  Handle type = string_type(H5T_CSET_UTF8, file);
  const hsize_t n = values.size();
  Handle space = own(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose, file, "H5Screate");
  Handle attr = own(H5Acreate2(obj, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    file, "H5Acreate2('" + name + "')");
  std::vector<const char*> ptrs;
  for (const auto& v : values) ptrs.push_back(v.c_str());
  check(H5Awrite(attr.get(), type.get(), ptrs.data()), file, "H5Awrite('" + name + "')");
}

void write_number(hid_t obj, const std::string& name, hid_t file_type, hid_t mem_type, const void* value,
                  const std::string& file) {
  drop_attribute(obj, name, file);
  Handle space = own(H5Screate(H5S_SCALAR), H5Sclose, file, "H5Screate");
  Handle attr = own(H5Acreate2(obj, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose,
                    file, "H5Acreate2('" + name + "')");
  check(H5Awrite(attr.get(), mem_type, value), file, "H5Awrite('" + name + "')");
}
void write_double(hid_t obj, const std::string& name, double v, const std::string& file) {
  write_number(obj, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &v, file);
}
void write_int(hid_t obj, const std::string& name, long long v, const std::string& file) {
  write_number(obj, name, H5T_STD_I64LE, H5T_NATIVE_LLONG, &v, file);
}

double read_number(hid_t obj, const std::string& name, const std::string& file) {
  Handle attr = own(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, file, "H5Aopen('" + name + "')");
  Handle space = own(H5Aget_space(attr.get()), H5Sclose, file, "H5Aget_space");
  if (H5Sget_simple_extent_npoints(space.get()) != 1)
    throw OutputError("HDF5 file '" + file + "': attribute '" + name + "' is not a single number");
  double v = 0;
  check(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, &v), file, "H5Aread('" + name + "') as a number");
  return v;
}

// Reads variable-length strings (ours) and fixed-length ones (other writers, e.g. numpy bytes via h5py).
std::vector<std::string> read_strings(hid_t obj, const std::string& name, const std::string& file) {
  Handle attr = own(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, file, "H5Aopen('" + name + "')");
  Handle type = own(H5Aget_type(attr.get()), H5Tclose, file, "H5Aget_type");
  if (H5Tget_class(type.get()) != H5T_STRING)
    throw OutputError("HDF5 file '" + file + "': attribute '" + name + "' is not a string");
  Handle space = own(H5Aget_space(attr.get()), H5Sclose, file, "H5Aget_space");
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) fail(file, "H5Sget_simple_extent_npoints");
  std::vector<std::string> out;
  if (n == 0) return out;
  const H5T_cset_t cset = H5Tget_cset(type.get());
  if (H5Tis_variable_str(type.get()) > 0) {
    Handle mem = string_type(cset, file);
    std::vector<char*> ptrs(static_cast<std::size_t>(n), nullptr);
    check(H5Aread(attr.get(), mem.get(), ptrs.data()), file, "H5Aread('" + name + "')");
    for (char* p : ptrs) {
      out.emplace_back(p ? p : "");
      H5free_memory(p);
    }
  } else {
    const std::size_t size = H5Tget_size(type.get());
    Handle mem = own(H5Tcopy(H5T_C_S1), H5Tclose, file, "H5Tcopy");
    check(H5Tset_size(mem.get(), size), file, "H5Tset_size");
    check(H5Tset_cset(mem.get(), cset), file, "H5Tset_cset");
    check(H5Tset_strpad(mem.get(), H5Tget_strpad(type.get())), file, "H5Tset_strpad");
    std::vector<char> buf(size * static_cast<std::size_t>(n));
    check(H5Aread(attr.get(), mem.get(), buf.data()), file, "H5Aread('" + name + "')");
    for (hssize_t i = 0; i < n; ++i) {
      const char* p = buf.data() + i * size;
      out.emplace_back(p, std::find(p, p + size, '\0'));
    }
  }
  return out;
}

// ---- datasets and groups ------------------------------------------------------------------------------------

// Columns compress well with shuffle + deflate(1) (exponent bytes are alike), at little CPU cost. A zero-size
// dataset cannot be chunked (a chunk dimension must be >= 1 and <= a fixed size), so empty columns stay contiguous.
// `values` (n × components of `mem_type`) become a dataset of `file_type`; with `components` > 1 it is
// (n, components), row-major: a vector or tensor per particle, a triangle's nodes.
void write_array(hid_t group, const std::string& name, hid_t file_type, hid_t mem_type, const void* values,
                 hsize_t n, hsize_t components, const std::string& file) {
  const hsize_t dims[2] = {n, components};
  const int rank = components > 1 ? 2 : 1;
  Handle space = own(H5Screate_simple(rank, dims, nullptr), H5Sclose, file, "H5Screate_simple");
  Handle dcpl = own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, file, "H5Pcreate");
  if (n > 0) {
    const hsize_t chunk[2] = {std::max<hsize_t>(1, std::min(n, kMaxChunk / components)), components};
    check(H5Pset_chunk(dcpl.get(), rank, chunk), file, "H5Pset_chunk");
    check(H5Pset_shuffle(dcpl.get()), file, "H5Pset_shuffle");
    check(H5Pset_deflate(dcpl.get(), 1), file, "H5Pset_deflate");
  }
  Handle ds = own(H5Dcreate2(group, name.c_str(), file_type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                  H5Dclose, file, "H5Dcreate2('" + name + "')");
  if (n > 0)
    check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values), file, "H5Dwrite('" + name + "')");
}

void write_column(hid_t group, const ColumnView& c, const std::string& file, hsize_t components = 1) {
  write_array(group, c.name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, c.values.data(), c.values.size() / components,
              components, file);
}

std::vector<double> read_all(hid_t ds, const std::string& file, const std::string& name) {
  Handle space = own(H5Dget_space(ds), H5Sclose, file, "H5Dget_space('" + name + "')");
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) fail(file, "H5Sget_simple_extent_npoints('" + name + "')");
  std::vector<double> v(static_cast<std::size_t>(n));
  if (n > 0)
    check(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), file, "H5Dread('" + name + "')");
  return v;
}

hsize_t extent0(hid_t ds, const std::string& file) {
  Handle space = own(H5Dget_space(ds), H5Sclose, file, "H5Dget_space");
  hsize_t dims[2] = {0, 0};
  if (H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) fail(file, "H5Sget_simple_extent_dims");
  return dims[0];
}

// Link names of a group in name order. (H5Literate's callback type differs between HDF5 1.10 and 1.12; indexing
// by position works with both.)
std::vector<std::string> link_names(hid_t group, const std::string& file) {
  H5G_info_t info;
  check(H5Gget_info(group, &info), file, "H5Gget_info");
  std::vector<std::string> names;
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t len = H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (len < 0) fail(file, "H5Lget_name_by_idx");
    std::string name(static_cast<std::size_t>(len), '\0');
    if (H5Lget_name_by_idx(group, ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size() + 1, H5P_DEFAULT) < 0)
      fail(file, "H5Lget_name_by_idx");
    names.push_back(std::move(name));
  }
  return names;
}

std::vector<std::string> dataset_names(hid_t group, const std::string& file) {
  std::vector<std::string> out;
  for (auto& name : link_names(group, file)) {
    Handle obj = own(H5Oopen(group, name.c_str(), H5P_DEFAULT), H5Oclose, file, "H5Oopen('" + name + "')");
    if (H5Iget_type(obj.get()) == H5I_DATASET) out.push_back(std::move(name));
  }
  return out;
}

// Snapshot group names are the zero-padded step; steps past 999999 get more digits, so order by length first.
void sort_steps(std::vector<std::string>& names) {
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
    return a.size() != b.size() ? a.size() < b.size() : a < b;
  });
}

std::string snapshot_name(long step) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06ld", step);
  return buf;
}

// "x0", "x1", "x2": the node coordinates of one axis of the background grid (/xdmf/grid).
std::string axis_name(int d) {
  std::string name = "x";  // appended: `"x" + to_string(d)` trips GCC 12's false -Wrestrict
  name += std::to_string(d);
  return name;
}

void check_names(std::span<const ColumnView> columns, const std::string& file, const char* op) {
  std::set<std::string> seen;
  for (const auto& c : columns) {
    if (c.name.empty() || c.name == "." || c.name.find('/') != std::string::npos)
      throw OutputError("'" + file + "': " + op + ": invalid column name '" + c.name + "'");
    if (!seen.insert(c.name).second)
      throw OutputError("'" + file + "': " + op + ": column '" + c.name + "' given twice");
  }
}

// ---- XDMF -------------------------------------------------------------------------------------------------------

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string shortest(double v) {  // round-trips exactly, without 17-digit noise
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// A DataItem for the first n values of an HDF5 dataset of `total` values: a plain reference when n == total,
// else a HyperSlab (start 0, stride 1, count n) over it.
std::string data_item(const std::string& ref, hsize_t n, hsize_t total, bool integer, const std::string& indent) {
  const std::string type = integer ? "NumberType=\"Int\"" : "NumberType=\"Float\"";
  const std::string hdf = "<DataItem Dimensions=\"" + std::to_string(total) + "\" " + type +
                          " Precision=\"8\" Format=\"HDF\">" + xml_escape(ref) + "</DataItem>\n";
  if (n == total) return indent + hdf;
  return indent + "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" + std::to_string(n) + "\" Type=\"HyperSlab\">\n" +
         indent + "  <DataItem Dimensions=\"3 1\" Format=\"XML\">0 1 " + std::to_string(n) + "</DataItem>\n" +
         indent + "  " + hdf + indent + "</DataItem>\n";
}

/// One snapshot's particle columns as ParaView wants them, written beside the snapshot into /xdmf/<step>/:
/// positions as one (n, 3) geometry, velocity and displacement as 3-vectors, stress and F as 3×3 tensors
/// (row-major; a 2D run's out-of-plane entries are 0, F_zz = 1, and a 1D run's F_yy = 1). ParaView 5.11's default
/// reader (Xdmf3ReaderS) crashes on a geometry of separate X and Y items and skips XDMF Function items, so these
/// are stored datasets; the snapshot keeps one dataset per component for h5py. The other columns are scalars.
class ParaViewFields {
 public:
  /// Reads the snapshot group's columns and writes the combined datasets into `out` (unless already there).
  ParaViewFields(hid_t snapshot, hid_t out, std::vector<std::string> columns, hsize_t n, const std::string& file)
      : columns_(std::move(columns)), n_(n) {
    auto column = [&](const std::string& c) {
      if (!has(c)) return std::vector<double>(n_, c == "1" ? 1.0 : 0.0);
      Handle ds = own(H5Dopen2(snapshot, c.c_str(), H5P_DEFAULT), H5Dclose, file, "H5Dopen2('" + c + "')");
      return read_all(ds.get(), file, c);
    };
    // each combined field: its components' columns, and for the displacement the reference columns to subtract
    auto combine = [&](const std::string& name, const std::vector<std::string>& parts,
                       const std::vector<std::string>& minus = {}) {
      fields_.push_back({name, parts.size()});
      if (exists(out, name, file)) return;
      std::vector<double> joined(n_ * parts.size());
      for (std::size_t k = 0; k < parts.size(); ++k) {
        const auto a = column(parts[k]);
        const auto b = k < minus.size() ? column(minus[k]) : std::vector<double>(n_, 0.0);
        for (hsize_t p = 0; p < n_; ++p) joined[p * parts.size() + k] = a[p] - b[p];
      }
      write_column(out, {name, joined}, file, parts.size());
    };
    combine("geometry", {"x0", "x1", "x2"});
    if (has("v0")) combine("velocity", {"v0", "v1", "v2"});
    if (has("X0")) combine("displacement", {"x0", "x1", "x2"}, {"X0", "X1", "X2"});
    if (has("s00")) combine("stress", {"s00", "s01", "", "s01", "s11", "", "", "", ""});
    if (has("F00")) combine("F", {"F00", "F01", "", "F10", has("F11") ? "F11" : "1", "", "", "", "1"});
  }

  /// The XDMF of the geometry and the attributes; `snapshot` and `combined` are the two groups as references,
  /// `indent` that of the elements (the data items are indented two more).
  std::string xml(const std::string& snapshot, const std::string& combined, const std::string& indent) const {
    const std::string in = indent + "  ";
    auto item = [&](const std::string& ref, std::size_t k) {
      return in + "<DataItem Dimensions=\"" + std::to_string(n_) + (k > 1 ? " " + std::to_string(k) : "") +
             "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" + xml_escape(ref) + "</DataItem>\n";
    };
    std::string out = indent + "<Geometry GeometryType=\"XYZ\">\n" + item(combined + "geometry", 3) + indent +
                      "</Geometry>\n";
    auto attribute = [&](const std::string& name, const char* type, const std::string& data) {
      out += indent + "<Attribute Name=\"" + xml_escape(name) + "\" AttributeType=\"" + type + "\" Center=\"Node\">\n" +
             data + indent + "</Attribute>\n";
    };
    for (const auto& [name, k] : fields_)
      if (name != "geometry") attribute(name, k == 3 ? "Vector" : "Tensor", item(combined + name, k));
    static const std::set<std::string> combined_columns = {"x0", "x1", "v0", "v1", "s00", "s01", "s11",
                                                           "F00", "F01", "F10", "F11"};
    for (const auto& c : columns_)
      if (!combined_columns.count(c)) attribute(c, "Scalar", item(snapshot + c, 1));
    return out;
  }

 private:
  bool has(const std::string& c) const { return std::find(columns_.begin(), columns_.end(), c) != columns_.end(); }
  std::vector<std::string> columns_;
  hsize_t n_;
  std::vector<std::pair<std::string, std::size_t>> fields_;  // name, components
};

void write_text_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw OutputError("cannot write '" + tmp + "'");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) throw OutputError("cannot rename '" + tmp + "' to '" + path + "': " + ec.message());
}

Handle open_read(const std::string& path) {
  quiet();
  return own(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, path, "H5Fopen (read)");
}

Handle file_access(const std::string& file) {
  // STRONG: H5Fclose really closes the file (and flushes it) before we rename it.
  Handle fapl = own(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, file, "H5Pcreate");
  check(H5Pset_fclose_degree(fapl.get(), H5F_CLOSE_STRONG), file, "H5Pset_fclose_degree");
  return fapl;
}

}  // namespace

// ---- H5Writer -----------------------------------------------------------------------------------------------------

struct H5Writer::State {
  std::string path, partial;
  int dimension = 0;
  Handle file, metrics;
  std::vector<std::string> metric_names;
  std::vector<double> pending;  // metrics rows not yet in the file, row-major
  hsize_t rows_in_file = 0;
  hsize_t chunk_rows = 1;
  bool closed = false;
  bool continued = false;  // append(): `path` holds the run this one continues

  // Runs a write. One that fails (full disk, file size limit) leaves the .partial file unusable: every handle is
  // closed, the file is removed, nothing is renamed into place, and the message adds what that costs. Closing
  // flushes what HDF5 still buffers, which fails again on a full disk and leaves the file half-closed in HDF5
  // (its exit handler then crashed); the file is dropped anyway, so those last writes go to /dev/null.
  template <class Write>
  void guard(Write&& write) {
    try {
      write();
    } catch (const OutputError& e) {
      closed = true;
      void* fd = nullptr;
      if (file.valid() && H5Fget_vfd_handle(file.get(), H5P_DEFAULT, &fd) >= 0 && fd) {
        const int null = ::open("/dev/null", O_WRONLY);
        if (null >= 0) {
          ::dup2(null, *static_cast<int*>(fd));
          ::close(null);
        }
      }
      metrics.reset();
      file.reset();
      std::error_code ec;
      fs::remove(partial, ec);
      throw OutputError(std::string(e.what()) + "; " +
                        (continued ? "'" + path + "' is kept as it was before this run (this run's steps are lost)"
                                   : "nothing was saved ('" + path + "' was not written)"));
    }
  }

  void open_metrics() {
    metrics = own(H5Dopen2(file.get(), "/metrics", H5P_DEFAULT), H5Dclose, partial, "H5Dopen2('/metrics')");
    metric_names = read_strings(metrics.get(), "columns", partial);
    rows_in_file = extent0(metrics.get(), partial);
    chunk_rows = std::max<hsize_t>(1, kMetricsChunkValues / std::max<std::size_t>(1, metric_names.size()));
  }

  void flush_metrics() {
    if (pending.empty()) return;
    const hsize_t ncols = metric_names.size(), rows = pending.size() / ncols;
    const hsize_t dims[2] = {rows_in_file + rows, ncols}, start[2] = {rows_in_file, 0}, count[2] = {rows, ncols};
    check(H5Dset_extent(metrics.get(), dims), partial, "H5Dset_extent('/metrics')");
    Handle fspace = own(H5Dget_space(metrics.get()), H5Sclose, partial, "H5Dget_space('/metrics')");
    check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), partial,
          "H5Sselect_hyperslab('/metrics')");
    Handle mspace = own(H5Screate_simple(2, count, nullptr), H5Sclose, partial, "H5Screate_simple");
    check(H5Dwrite(metrics.get(), H5T_NATIVE_DOUBLE, mspace.get(), fspace.get(), H5P_DEFAULT, pending.data()),
          partial, "H5Dwrite('/metrics')");
    rows_in_file += rows;
    pending.clear();
  }

  // Grows /xdmf/<name> to at least n values; returns the old size. Extendible, with a chunk independent of the
  // size, because particle counts may grow between snapshots.
  hsize_t grow_helper(hid_t group, const char* name, hid_t type, hsize_t n, Handle& ds) {
    if (exists(group, name, partial)) {
      ds = own(H5Dopen2(group, name, H5P_DEFAULT), H5Dclose, partial, std::string("H5Dopen2('/xdmf/") + name + "')");
      const hsize_t old = extent0(ds.get(), partial);
      if (old < n) check(H5Dset_extent(ds.get(), &n), partial, "H5Dset_extent");
      return old;
    }
    const hsize_t maxdim = H5S_UNLIMITED, chunk = kMaxChunk;
    Handle space = own(H5Screate_simple(1, &n, &maxdim), H5Sclose, partial, "H5Screate_simple");
    Handle dcpl = own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, partial, "H5Pcreate");
    check(H5Pset_chunk(dcpl.get(), 1, &chunk), partial, "H5Pset_chunk");
    check(H5Pset_shuffle(dcpl.get()), partial, "H5Pset_shuffle");
    check(H5Pset_deflate(dcpl.get(), 1), partial, "H5Pset_deflate");
    const long long zero = 0;  // explicit fill value: unwritten chunks read as 0 and take no space
    check(H5Pset_fill_value(dcpl.get(), H5T_NATIVE_LLONG, &zero), partial, "H5Pset_fill_value");
    ds = own(H5Dcreate2(group, name, type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT), H5Dclose, partial,
             std::string("H5Dcreate2('/xdmf/") + name + "')");
    return 0;
  }

  // Polyvertex cells need connectivity (ParaView counts cells from it), shared by all snapshots and written once:
  // /xdmf/ids = 0..n-1 in `group` (/xdmf). Returns its size.
  hsize_t write_xdmf_ids(hid_t group, hsize_t n) {
    Handle ids;
    const hsize_t ids_old = grow_helper(group, "ids", H5T_STD_I64LE, n, ids);
    std::vector<long long> block;
    for (hsize_t start = ids_old; start < n; start += kMaxChunk) {
      const hsize_t count = std::min(kMaxChunk, n - start);
      block.resize(count);
      for (hsize_t i = 0; i < count; ++i) block[i] = static_cast<long long>(start + i);
      Handle fspace = own(H5Dget_space(ids.get()), H5Sclose, partial, "H5Dget_space");
      check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, &start, nullptr, &count, nullptr), partial,
            "H5Sselect_hyperslab");
      Handle mspace = own(H5Screate_simple(1, &count, nullptr), H5Sclose, partial, "H5Screate_simple");
      check(H5Dwrite(ids.get(), H5T_NATIVE_LLONG, mspace.get(), fspace.get(), H5P_DEFAULT, block.data()), partial,
            "H5Dwrite('/xdmf/ids')");
    }
    return std::max(n, ids_old);  // a continued run may have had more particles
  }

  // The group /xdmf (the data only the sidecar reads), created when first needed.
  Handle xdmf_group() {
    return exists(file.get(), "/xdmf", partial)
               ? own(H5Gopen2(file.get(), "/xdmf", H5P_DEFAULT), H5Gclose, partial, "H5Gopen2('/xdmf')")
               : create_group(file.get(), "/xdmf", partial);
  }

  // The background grid (set_grid: node coordinates /xdmf/grid/x0, x1, x2) as a rectilinear mesh named "grid",
  // its elements indented by `indent`; empty if no grid was set. A 1D grid is a row of nodes at y = 0.
  std::string background_grid_xml(hid_t xdmf, const std::string& h5, const std::string& indent) {
    if (!exists(xdmf, "grid", partial)) return {};
    Handle grid = own(H5Gopen2(xdmf, "grid", H5P_DEFAULT), H5Gclose, partial, "H5Gopen2('/xdmf/grid')");
    std::vector<hsize_t> nodes;
    std::string items;
    for (int d = 0; d < dimension; ++d) {
      const std::string name = axis_name(d);
      Handle ds = own(H5Dopen2(grid.get(), name.c_str(), H5P_DEFAULT), H5Dclose, partial,
                      "H5Dopen2('/xdmf/grid/" + name + "')");
      nodes.push_back(extent0(ds.get(), partial));
      items += data_item(h5 + "/xdmf/grid/" + name, nodes.back(), nodes.back(), false, indent + "    ");
    }
    if (dimension == 1) items += indent + "    <DataItem Dimensions=\"1\" Format=\"XML\">0</DataItem>\n";
    // the Dimensions of a RectMesh list the slowest axis first; VXVY(VZ) lists x first
    std::string dims;
    for (int d = std::max(dimension, 2) - 1; d >= 0; --d)
      dims += std::to_string(d < dimension ? nodes[d] : 1) + (d > 0 ? " " : "");
    const bool three = dimension == 3;
    return indent + "<Grid Name=\"grid\" GridType=\"Uniform\">\n" + indent + "  <Topology TopologyType=\"" +
           (three ? "3DRectMesh" : "2DRectMesh") + "\" Dimensions=\"" + dims + "\"/>\n" + indent +
           "  <Geometry GeometryType=\"" + (three ? "VXVYVZ" : "VXVY") + "\">\n" + items + indent +
           "  </Geometry>\n" + indent + "</Grid>\n";
  }

  // The triangular mesh (set_mesh: /xdmf/mesh/geometry, (nodes, 3), and topology, (triangles, 3)) as an
  // unstructured grid named "mesh", its elements indented by `indent`; empty if no mesh was set.
  std::string background_mesh_xml(hid_t xdmf, const std::string& h5, const std::string& indent) {
    if (!exists(xdmf, "mesh", partial)) return {};
    Handle mesh = own(H5Gopen2(xdmf, "mesh", H5P_DEFAULT), H5Gclose, partial, "H5Gopen2('/xdmf/mesh')");
    // rows and bytes per value of a dataset: the sidecar describes what the file holds, whoever wrote it
    auto shape = [&](const char* name) {
      const std::string what = std::string("'/xdmf/mesh/") + name + "'";
      Handle ds = own(H5Dopen2(mesh.get(), name, H5P_DEFAULT), H5Dclose, partial, "H5Dopen2(" + what + ")");
      Handle type = own(H5Dget_type(ds.get()), H5Tclose, partial, "H5Dget_type(" + what + ")");
      const std::size_t size = H5Tget_size(type.get());
      if (size == 0) fail(partial, "H5Tget_size(" + what + ")");
      return std::pair{extent0(ds.get(), partial), size};
    };
    const auto [nodes, float_size] = shape("geometry");
    const auto [triangles, int_size] = shape("topology");
    auto item = [&](const char* name, hsize_t rows, const char* number_type, std::size_t precision) {
      return indent + "    <DataItem Dimensions=\"" + std::to_string(rows) + " 3\" NumberType=\"" + number_type +
             "\" Precision=\"" + std::to_string(precision) + "\" Format=\"HDF\">" +
             xml_escape(h5 + "/xdmf/mesh/" + name) + "</DataItem>\n";
    };
    return indent + "<Grid Name=\"mesh\" GridType=\"Uniform\">\n" + indent +
           "  <Topology TopologyType=\"Triangle\" NumberOfElements=\"" + std::to_string(triangles) + "\">\n" +
           item("topology", triangles, "Int", int_size) + indent + "  </Topology>\n" + indent +
           "  <Geometry GeometryType=\"XYZ\">\n" + item("geometry", nodes, "Float", float_size) + indent +
           "  </Geometry>\n" + indent + "</Grid>\n";
  }

  // The sidecar is built from what the file holds (not from what this writer wrote), so it also covers
  // snapshots of an earlier run continued with append().
  std::string build_xdmf() {
    struct Grid {
      std::string name;
      double time = 0;
      hsize_t n = 0;
      std::vector<std::string> columns;
    };
    std::vector<Grid> grids;
    hsize_t max_n = 0;
    Handle snaps = own(H5Gopen2(file.get(), "/snapshots", H5P_DEFAULT), H5Gclose, partial, "H5Gopen2('/snapshots')");
    auto names = link_names(snaps.get(), partial);
    sort_steps(names);
    for (auto& name : names) {
      Handle g = own(H5Gopen2(snaps.get(), name.c_str(), H5P_DEFAULT), H5Gclose, partial, "H5Gopen2('" + name + "')");
      Grid grid{name, read_number(g.get(), "time", partial), 0, dataset_names(g.get(), partial)};
      if (!grid.columns.empty()) {
        Handle ds = own(H5Dopen2(g.get(), grid.columns.front().c_str(), H5P_DEFAULT), H5Dclose, partial, "H5Dopen2");
        grid.n = extent0(ds.get(), partial);
      }
      max_n = std::max(max_n, grid.n);
      grids.push_back(std::move(grid));
    }
    Handle xdmf = xdmf_group();
    const hsize_t ids_size = max_n > 0 ? write_xdmf_ids(xdmf.get(), max_n) : 0;

    // Relative reference by the final name, so the pair of files can be moved together.
    const std::string h5 = fs::path(path).filename().string() + ":";
    // ParaView's default reader shows one top-level grid only: with a background grid or mesh, each time step is a
    // spatial collection of the particles and the background. (set_grid and set_mesh each remove the other.)
    const std::string mesh =
        background_grid_xml(xdmf.get(), h5, "        ") + background_mesh_xml(xdmf.get(), h5, "        ");
    std::ostringstream x;
    x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n"
      << "    <Grid Name=\"run\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (const auto& g : grids) {
      if (g.n == 0) {  // Xdmf3 (ParaView's reader) fails on empty grids, so an empty snapshot is only noted
        x << "      <!-- snapshot " << g.name << " at t = " << shortest(g.time) << " has no particles -->\n";
        continue;
      }
      const std::string time = "<Time Value=\"" + shortest(g.time) + "\"/>\n";
      std::string in = "        ";  // the particles' elements
      if (mesh.empty()) {
        x << "      <Grid Name=\"" << g.name << "\" GridType=\"Uniform\">\n        " << time;
      } else {
        x << "      <Grid Name=\"" << g.name << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n        "
          << time << "        <Grid Name=\"particles\" GridType=\"Uniform\">\n";
        in += "  ";
      }
      x << in << "<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << g.n << "\" NodesPerElement=\"1\">\n"
        << data_item(h5 + "/xdmf/ids", g.n, ids_size, true, in + "  ") << in << "</Topology>\n";
      Handle snapshot = own(H5Gopen2(snaps.get(), g.name.c_str(), H5P_DEFAULT), H5Gclose, partial, "H5Gopen2");
      const std::string combined_path = "/xdmf/" + g.name;
      Handle combined = exists(xdmf.get(), g.name, partial)
                            ? own(H5Gopen2(xdmf.get(), g.name.c_str(), H5P_DEFAULT), H5Gclose, partial, "H5Gopen2")
                            : create_group(xdmf.get(), g.name, partial);
      const ParaViewFields fields(snapshot.get(), combined.get(), g.columns, g.n, partial);
      x << fields.xml(h5 + "/snapshots/" + g.name + "/", h5 + combined_path + "/", in);
      if (!mesh.empty()) x << "        </Grid>\n" << mesh;
      x << "      </Grid>\n";
    }
    x << "    </Grid>\n  </Domain>\n</Xdmf>\n";
    return x.str();
  }
};

H5Writer::H5Writer(std::unique_ptr<State> state) : s_(std::move(state)) {}

H5Writer::State& H5Writer::live(const char* op) {
  if (!s_) throw OutputError(std::string("H5Writer::") + op + " on a moved-from writer");
  if (s_->closed) throw OutputError("'" + s_->path + "': " + op + " after close()");
  quiet();
  return *s_;
}

H5Writer::H5Writer(std::string path, const std::string& scene_json, int dimension) : s_(std::make_unique<State>()) {
  quiet();
  State& s = *s_;
  s.path = std::move(path);
  s.partial = s.path + ".partial";
  if (dimension < 1 || dimension > 3)
    throw OutputError("'" + s.path + "': dimension must be 1, 2 or 3, got " + std::to_string(dimension));
  s.dimension = dimension;
  Handle fapl = file_access(s.partial);
  s.file = own(H5Fcreate(s.partial.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose, s.partial,
               "H5Fcreate (the run file for '" + s.path + "')");
  s.guard([&] {
    write_strings(s.file.get(), "scene", {scene_json}, true, s.partial);
    write_int(s.file.get(), "dimension", dimension, s.partial);
    create_group(s.file.get(), "/snapshots", s.partial);
  });
}

H5Writer H5Writer::append(std::string path) {
  quiet();
  auto s = std::make_unique<State>();
  s->path = std::move(path);
  s->partial = s->path + ".partial";
  std::error_code ec;
  if (!fs::exists(s->path, ec) && fs::exists(s->partial, ec)) {
    // a killed run: its .partial file (valid up to its last checkpoint) becomes the file kept if this run fails
    fs::rename(s->partial, s->path, ec);
    if (ec) throw OutputError("cannot rename '" + s->partial + "' to '" + s->path + "': " + ec.message());
  }
  if (!fs::exists(s->path, ec))
    throw OutputError("cannot continue '" + s->path + "': neither it nor its .partial file exists");
  // Work on a copy: the complete file stays in place until close() replaces it.
  fs::copy_file(s->path, s->partial, fs::copy_options::overwrite_existing, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(s->partial, ec);
    throw OutputError("cannot copy '" + s->path + "' to '" + s->partial + "': " + why + "; '" + s->path +
                      "' is kept as it was");
  }
  s->continued = true;
  Handle fapl = file_access(s->partial);
  s->file = own(H5Fopen(s->partial.c_str(), H5F_ACC_RDWR, fapl.get()), H5Fclose, s->partial, "H5Fopen (append)");
  State& state = *s;
  state.guard([&] {
    state.dimension = static_cast<int>(read_number(state.file.get(), "dimension", state.partial));
    if (exists(state.file.get(), "/metrics", state.partial)) state.open_metrics();
    if (!exists(state.file.get(), "/snapshots", state.partial))
      create_group(state.file.get(), "/snapshots", state.partial);
    remove_link(state.file.get(), kCheckpointTmp, state.partial);  // left over if the earlier run died mid-checkpoint
  });
  return H5Writer(std::move(s));
}

H5Writer::H5Writer(H5Writer&& o) noexcept = default;

H5Writer& H5Writer::operator=(H5Writer&& o) noexcept {
  if (this != &o) {
    finish_quietly();
    s_ = std::move(o.s_);
  }
  return *this;
}

H5Writer::~H5Writer() { finish_quietly(); }

void H5Writer::finish_quietly() noexcept {
  try {
    close();
  } catch (...) {  // a destructor must not throw; the .partial file keeps what was written
  }
}

void H5Writer::set_metric_names(std::vector<std::string> names) {
  State& s = live("set_metric_names");
  if (s.metrics.valid()) {
    if (names == s.metric_names) return;
    throw OutputError("'" + s.path + "': set_metric_names: the metrics table already has other columns");
  }
  if (names.empty()) throw OutputError("'" + s.path + "': set_metric_names: no column names");
  s.guard([&] {
    const hsize_t ncols = names.size();
    s.chunk_rows = std::max<hsize_t>(1, kMetricsChunkValues / ncols);
    const hsize_t dims[2] = {0, ncols}, maxdims[2] = {H5S_UNLIMITED, ncols}, chunk[2] = {s.chunk_rows, ncols};
    Handle space = own(H5Screate_simple(2, dims, maxdims), H5Sclose, s.partial, "H5Screate_simple");
    Handle dcpl = own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, s.partial, "H5Pcreate");
    check(H5Pset_chunk(dcpl.get(), 2, chunk), s.partial, "H5Pset_chunk");
    check(H5Pset_deflate(dcpl.get(), 1), s.partial, "H5Pset_deflate");  // a part-filled chunk then costs little
    s.metrics = own(H5Dcreate2(s.file.get(), "/metrics", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, dcpl.get(),
                               H5P_DEFAULT),
                    H5Dclose, s.partial, "H5Dcreate2('/metrics')");
    write_strings(s.metrics.get(), "columns", names, false, s.partial);
    s.metric_names = std::move(names);
    s.rows_in_file = 0;
  });
}

void H5Writer::add_metrics(std::span<const double> row) {
  State& s = live("add_metrics");
  if (!s.metrics.valid()) throw OutputError("'" + s.path + "': add_metrics before set_metric_names");
  if (row.size() != s.metric_names.size())
    throw OutputError("'" + s.path + "': add_metrics: row has " + std::to_string(row.size()) +
                      " values, the table has " + std::to_string(s.metric_names.size()) + " columns");
  s.pending.insert(s.pending.end(), row.begin(), row.end());
  if (s.pending.size() / s.metric_names.size() >= s.chunk_rows) s.guard([&] { s.flush_metrics(); });
}

void H5Writer::write_snapshot(long step, double time, std::span<const ColumnView> columns) {
  State& s = live("write_snapshot");
  if (step < 0) throw OutputError("'" + s.path + "': write_snapshot: negative step " + std::to_string(step));
  check_names(columns, s.path, "write_snapshot");
  for (const auto& c : columns)
    if (c.values.size() != columns.front().values.size())
      throw OutputError("'" + s.path + "': write_snapshot: column '" + c.name + "' has " +
                        std::to_string(c.values.size()) + " values, '" + columns.front().name + "' has " +
                        std::to_string(columns.front().values.size()));
  s.guard([&] {
    const std::string name = "/snapshots/" + snapshot_name(step);
    remove_link(s.file.get(), name, s.partial);  // the same step again (e.g. after resume) replaces it
    Handle g = create_group(s.file.get(), name, s.partial);
    write_int(g.get(), "step", step, s.partial);
    write_double(g.get(), "time", time, s.partial);
    for (const auto& c : columns) write_column(g.get(), c, s.partial);
  });
}

void H5Writer::set_grid(std::span<const std::vector<double>> nodes) {
  State& s = live("set_grid");
  if (nodes.size() != static_cast<std::size_t>(s.dimension))
    throw OutputError("'" + s.path + "': set_grid: " + std::to_string(nodes.size()) + " axes for a " +
                      std::to_string(s.dimension) + "D run");
  for (const auto& axis : nodes)
    if (axis.empty()) throw OutputError("'" + s.path + "': set_grid: an axis without nodes");
  s.guard([&] {
    Handle xdmf = s.xdmf_group();
    remove_link(xdmf.get(), "grid", s.partial);  // a continued run sets it again
    remove_link(xdmf.get(), "mesh", s.partial);  // one background per run: the later replaces the earlier
    Handle g = create_group(xdmf.get(), "grid", s.partial);
    for (std::size_t d = 0; d < nodes.size(); ++d)
      write_column(g.get(), {axis_name(static_cast<int>(d)), nodes[d]}, s.partial);
  });
}

void H5Writer::set_mesh(std::span<const std::array<double, 2>> nodes, std::span<const std::array<int, 3>> triangles) {
  State& s = live("set_mesh");
  // checked before anything is written: a bad mesh is the caller's error and must not cost the run file (guard)
  if (s.dimension != 2)
    throw OutputError("'" + s.path + "': set_mesh: a triangular mesh for a " + std::to_string(s.dimension) +
                      "D run");
  if (nodes.empty()) throw OutputError("'" + s.path + "': set_mesh: a mesh without nodes");
  if (triangles.empty()) throw OutputError("'" + s.path + "': set_mesh: a mesh without triangles");
  for (std::size_t e = 0; e < triangles.size(); ++e)
    for (const int k : triangles[e])
      if (k < 0 || static_cast<std::size_t>(k) >= nodes.size())
        throw OutputError("'" + s.path + "': set_mesh: triangle " + std::to_string(e) + " has node index " +
                          std::to_string(k) + ", the mesh has " + std::to_string(nodes.size()) + " nodes (0-based)");
  s.guard([&] {
    Handle xdmf = s.xdmf_group();
    remove_link(xdmf.get(), "mesh", s.partial);  // a continued run sets it again
    remove_link(xdmf.get(), "grid", s.partial);  // one background per run: the later replaces the earlier
    Handle g = create_group(xdmf.get(), "mesh", s.partial);
    // z = 0: an XYZ geometry like the particles' (ParaViewFields), the form ParaView's XDMF3 reader is known to take
    std::vector<double> xyz(3 * nodes.size(), 0.0);
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      xyz[3 * i] = nodes[i][0];
      xyz[3 * i + 1] = nodes[i][1];
    }
    write_array(g.get(), "geometry", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, xyz.data(), nodes.size(), 3, s.partial);
    static_assert(sizeof(std::array<int, 3>) == 3 * sizeof(int));  // the triangles are rows of a (T, 3) array
    write_array(g.get(), "topology", H5T_STD_I32LE, H5T_NATIVE_INT, triangles.data(), triangles.size(), 3,
                s.partial);
  });
}

void H5Writer::write_checkpoint(long step, double time, std::span<const ColumnView> columns,
                                std::span<const std::pair<std::string, double>> scalars) {
  State& s = live("write_checkpoint");
  check_names(columns, s.path, "write_checkpoint");
  std::set<std::string> seen{"step", "time"};
  for (const auto& [name, value] : scalars)
    if (name.empty() || !seen.insert(name).second)
      throw OutputError("'" + s.path + "': write_checkpoint: scalar name '" + name +
                        "' is empty, reserved or repeated");
  s.guard([&] {
    s.flush_metrics();  // the metrics belong to the state being saved
    // Build the new checkpoint beside the old one and swap it in by links, so the old one is never half-replaced.
    remove_link(s.file.get(), kCheckpointTmp, s.partial);
    {
      Handle g = create_group(s.file.get(), kCheckpointTmp, s.partial);
      write_int(g.get(), "step", step, s.partial);
      write_double(g.get(), "time", time, s.partial);
      for (const auto& [name, value] : scalars) write_double(g.get(), name, value, s.partial);
      for (const auto& c : columns) write_column(g.get(), c, s.partial);
    }
    remove_link(s.file.get(), "/checkpoint", s.partial);
    check(H5Lmove(s.file.get(), kCheckpointTmp, s.file.get(), "/checkpoint", H5P_DEFAULT, H5P_DEFAULT), s.partial,
          "H5Lmove('/checkpoint')");
    check(H5Fflush(s.file.get(), H5F_SCOPE_GLOBAL), s.partial, "H5Fflush");
  });
}

void H5Writer::set_attribute(const std::string& name, const std::string& value) {
  State& s = live("set_attribute");
  s.guard([&] { write_strings(s.file.get(), name, {value}, true, s.partial); });
}

void H5Writer::discard_after(long step, double time) {
  State& s = live("discard_after");
  s.guard([&] {
    s.flush_metrics();
    Handle snaps =
        own(H5Gopen2(s.file.get(), "/snapshots", H5P_DEFAULT), H5Gclose, s.partial, "H5Gopen2('/snapshots')");
    // the snapshots after `step`, and their ParaView datasets (/xdmf/<step>, ParaViewFields)
    auto drop_after = [&](hid_t group) {
      for (const auto& name : link_names(group, s.partial)) {
        long long n = -1;
        const auto [end, ec] = std::from_chars(name.data(), name.data() + name.size(), n);
        if (ec == std::errc() && end == name.data() + name.size() && n > step)
          check(H5Ldelete(group, name.c_str(), H5P_DEFAULT), s.partial, "H5Ldelete('" + name + "')");
      }
    };
    drop_after(snaps.get());
    if (exists(s.file.get(), "/xdmf", s.partial)) {
      Handle xdmf = own(H5Gopen2(s.file.get(), "/xdmf", H5P_DEFAULT), H5Gclose, s.partial, "H5Gopen2('/xdmf')");
      drop_after(xdmf.get());
    }
    const auto t = std::find(s.metric_names.begin(), s.metric_names.end(), "t");
    if (!s.metrics.valid() || t == s.metric_names.end()) return;
    const std::size_t ncols = s.metric_names.size(), col = static_cast<std::size_t>(t - s.metric_names.begin());
    const auto values = read_all(s.metrics.get(), s.partial, "/metrics");
    hsize_t keep = 0;
    while (keep < s.rows_in_file && !(values[keep * ncols + col] > time)) ++keep;
    if (keep < s.rows_in_file) {
      const hsize_t dims[2] = {keep, ncols};
      check(H5Dset_extent(s.metrics.get(), dims), s.partial, "H5Dset_extent('/metrics')");
      s.rows_in_file = keep;
    }
  });
}

void H5Writer::flush() {
  State& s = live("flush");
  s.guard([&] {
    s.flush_metrics();
    check(H5Fflush(s.file.get(), H5F_SCOPE_GLOBAL), s.partial, "H5Fflush");
  });
}

void H5Writer::close() {
  if (!s_ || s_->closed) return;
  quiet();
  State& s = *s_;
  s.closed = true;  // whatever happens below, do not try again from the destructor
  std::string xdmf;
  s.guard([&] {
    s.flush_metrics();
    xdmf = s.build_xdmf();
    s.metrics.reset();
    // flushed while the file is still open, so that a failure here finds it open (State::guard)
    check(H5Fflush(s.file.get(), H5F_SCOPE_GLOBAL), s.partial, "H5Fflush");
    s.file.close(s.partial);  // its result matters: this is the final flush
  });
  std::error_code ec;
  fs::rename(s.partial, s.path, ec);
  if (ec) throw OutputError("cannot rename '" + s.partial + "' to '" + s.path + "': " + ec.message());
  write_text_atomically(xdmf_path(s.path), xdmf);
}

const std::string& H5Writer::path() const {
  static const std::string none;
  return s_ ? s_->path : none;
}

// ---- free functions -------------------------------------------------------------------------------------------

void skip_hdf5_exit_handler() { H5dont_atexit(); }

std::string xdmf_path(const std::string& h5_path) {
  const std::string ext = ".h5";
  const bool h5 = h5_path.size() > ext.size() && h5_path.compare(h5_path.size() - ext.size(), ext.size(), ext) == 0;
  return (h5 ? h5_path.substr(0, h5_path.size() - ext.size()) : h5_path) + ".xdmf";
}

nlohmann::json read_scene_attribute(const std::string& path) {
  const auto text = read_string_attribute(path, "/", "scene");
  if (text.size() != 1) throw OutputError("HDF5 file '" + path + "': attribute 'scene' is not a single string");
  try {
    return nlohmann::json::parse(text.front());
  } catch (const nlohmann::json::exception& e) {
    throw OutputError("HDF5 file '" + path + "': attribute 'scene' is not valid JSON: " + e.what());
  }
}

std::vector<double> read_dataset(const std::string& path, const std::string& dataset) {
  Handle file = open_read(path);
  Handle ds = own(H5Dopen2(file.get(), dataset.c_str(), H5P_DEFAULT), H5Dclose, path, "H5Dopen2('" + dataset + "')");
  return read_all(ds.get(), path, dataset);
}

std::vector<std::string> list_snapshots(const std::string& path) {
  Handle file = open_read(path);
  if (!exists(file.get(), "/snapshots", path)) return {};
  Handle g = own(H5Gopen2(file.get(), "/snapshots", H5P_DEFAULT), H5Gclose, path, "H5Gopen2('/snapshots')");
  auto names = link_names(g.get(), path);
  sort_steps(names);
  return names;
}

std::vector<std::string> list_datasets(const std::string& path, const std::string& group) {
  Handle file = open_read(path);
  Handle g = own(H5Gopen2(file.get(), group.c_str(), H5P_DEFAULT), H5Gclose, path, "H5Gopen2('" + group + "')");
  return dataset_names(g.get(), path);
}

double read_number_attribute(const std::string& path, const std::string& object, const std::string& name) {
  Handle file = open_read(path);
  Handle obj = own(H5Oopen(file.get(), object.c_str(), H5P_DEFAULT), H5Oclose, path, "H5Oopen('" + object + "')");
  return read_number(obj.get(), name, path);
}

std::vector<std::string> read_string_attribute(const std::string& path, const std::string& object,
                                               const std::string& name) {
  Handle file = open_read(path);
  Handle obj = own(H5Oopen(file.get(), object.c_str(), H5P_DEFAULT), H5Oclose, path, "H5Oopen('" + object + "')");
  return read_strings(obj.get(), name, path);
}

}  // namespace mpm
