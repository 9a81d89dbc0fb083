// `mpm study`: the cross product of varied scene keys, one in-process run per row (see study.hpp).
#include "engine/study.hpp"

#include <hdf5.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "engine/h5_handle.hpp"
#include "engine/output_h5.hpp"
#include "engine/scene.hpp"

namespace mpm {

namespace {

using namespace h5;

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr const char* kPython = "/usr/bin/python3";

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::string one_line(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}

/// The raw scene with `--set`-style overrides applied; an override error names the option it came from.
void apply(json& scene, const std::string& key, const std::string& value, const std::string& what) {
  try {
    apply_override(scene, key + "=" + value);
  } catch (const SceneError& e) {
    // apply_override speaks of --set; say which --vary value it was
    std::string msg = e.what();
    const std::string prefix = "--set " + key + "=" + value + ": ";
    if (msg.rfind(prefix, 0) == 0) msg = msg.substr(prefix.size());
    throw SceneError(what + ": " + msg);
  }
}

std::string vary_what(const std::string& key, const std::string& value) {
  return "--vary " + key + ": value " + value;
}

/// The run scene: per-run output files are never written by a study.
void drop_output_file(json& scene) {
  if (scene.is_object() && scene.contains("output") && scene["output"].is_object()) scene["output"].erase("file");
}

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double number_at(const json& j, const char* group, const char* key) {
  if (!j.contains(group) || !j[group].is_object()) return kNaN;
  const json& g = j[group];
  return g.contains(key) && g[key].is_number() ? g[key].get<double>() : kNaN;
}

const char* status_name(int exit_status) {
  switch (exit_status) {
    case exit_ok: return "ok";
    case exit_invalid: return "invalid";
    case exit_unstable: return "unstable";
    default: return "failed";
  }
}

StudyRow blank_row() {
  StudyRow r;
  r.wall_s = r.particle_steps_per_s = kNaN;
  r.displacement_rms = r.velocity_rms = r.stress_rms = kNaN;
  r.displacement_rel_l2 = r.stress_rel_l2 = kNaN;
  r.mass_rel_max = r.momentum_rel_max = r.fallbacks = kNaN;
  r.cell_size = kNaN;
  return r;
}

/// One row: parse the combined scene, run it `repeat` times (stopping at the first run that does not end ok).
StudyRow run_row(const json& scene_json, int repeat, int threads) {
  StudyRow row = blank_row();
  Scene scene;
  try {
    scene = parse_scene(scene_json);
  } catch (const SceneError& e) {
    row.exit_status = exit_invalid;
    row.status = status_name(exit_invalid);
    row.reason = one_line(e.what());
    return row;
  }
  scene.output.file.clear();
  scene.output.checkpoint_every = 0;
  row.cell_size = std::numeric_limits<double>::infinity();
  for (int d = 0; d < scene.dimension; ++d)
    row.cell_size = std::min(row.cell_size, scene.grid.length[d] / scene.grid.cells[d]);

  RunOptions options;
  options.threads = threads;
  options.quiet = true;
  std::vector<double> walls;
  RunResult last;
  bool have = false;
  for (int i = 0; i < std::max(1, repeat); ++i) {
    try {
      last = run_scene(scene, options);
      have = true;
    } catch (const std::exception& e) {
      row.exit_status = exit_failure;
      row.status = status_name(exit_failure);
      row.reason = one_line(e.what());
      have = false;
      break;
    } catch (...) {
      row.exit_status = exit_failure;
      row.status = status_name(exit_failure);
      row.reason = "unknown exception";
      have = false;
      break;
    }
    const json& s = last.summary;
    if (s.contains("wall_s") && s["wall_s"].is_number()) walls.push_back(s["wall_s"].get<double>());
    if (last.status != exit_ok) break;
  }
  if (!have) return row;

  const json& s = last.summary;
  row.exit_status = last.status;
  row.status = s.contains("status") && s["status"].is_string() ? s["status"].get<std::string>()
                                                               : status_name(last.status);
  row.reason = one_line(!last.message.empty() ? last.message : s.value("reason", std::string()));
  if (s.contains("steps") && s["steps"].is_number()) row.steps = s["steps"].get<long>();
  if (s.contains("particles") && s["particles"].is_number()) row.particles = s["particles"].get<long>();
  row.wall_s = median(walls);
  if (row.steps >= 0 && row.particles >= 0 && row.wall_s > 0)
    row.particle_steps_per_s = static_cast<double>(row.particles) * static_cast<double>(row.steps) / row.wall_s;
  else if (s.contains("particle_steps_per_s") && s["particle_steps_per_s"].is_number())
    row.particle_steps_per_s = s["particle_steps_per_s"].get<double>();
  row.displacement_rms = number_at(s, "errors", "displacement_rms");
  row.velocity_rms = number_at(s, "errors", "velocity_rms");
  row.stress_rms = number_at(s, "errors", "stress_rms");
  row.displacement_rel_l2 = number_at(s, "errors", "displacement_rel_l2");
  row.stress_rel_l2 = number_at(s, "errors", "stress_rel_l2");
  row.mass_rel_max = number_at(s, "conservation", "mass_rel_max");
  row.momentum_rel_max = number_at(s, "conservation", "momentum_rel_max");
  if (s.contains("fallbacks") && s["fallbacks"].is_object()) {
    double sum = 0;
    for (const auto& [name, v] : s["fallbacks"].items())
      if (v.is_number()) sum += v.get<double>();
    row.fallbacks = sum;
  }
  return row;
}

// ---- CSV ----------------------------------------------------------------------------------------------------

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos && trim(s) == s) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

std::string csv_number(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "" : (v > 0 ? "inf" : "-inf");
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

std::string csv_count(long v) { return v < 0 ? "" : std::to_string(v); }

std::string csv_line(const std::vector<std::string>& fields) {
  std::string line;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) line += ',';
    line += csv_field(fields[i]);
  }
  return line + "\n";
}

std::vector<std::string> csv_row(const StudyRow& r) {
  std::vector<std::string> f = r.values;
  for (double v : {r.wall_s, r.particle_steps_per_s, r.displacement_rms, r.velocity_rms, r.stress_rms,
                   r.displacement_rel_l2, r.stress_rel_l2, r.mass_rel_max, r.momentum_rel_max, r.fallbacks})
    f.push_back(csv_number(v));
  f.push_back(csv_count(r.steps));
  f.push_back(csv_count(r.particles));
  f.push_back(r.status);
  f.push_back(r.reason);
  return f;
}

// ---- the printed table --------------------------------------------------------------------------------------

struct Table {
  std::vector<std::string> keys;
  std::vector<std::size_t> key_width;
  std::size_t count_width = 0;

  static constexpr int num_width = 9;

  Table(const std::vector<StudyAxis>& axes, std::size_t total) {
    for (const auto& a : axes) {
      keys.push_back(a.key);
      std::size_t w = a.key.size();
      for (const auto& v : a.values) w = std::max(w, display_value(v).size());
      key_width.push_back(w);
    }
    count_width = 3 + 2 * std::to_string(total).size();
  }

  static std::string pad(const std::string& s, std::size_t w, bool right = false) {
    if (s.size() >= w) return s;
    return right ? std::string(w - s.size(), ' ') + s : s + std::string(w - s.size(), ' ');
  }
  static std::string num(double v, const char* fmt) {
    if (std::isnan(v)) return pad("-", num_width, true);
    char buf[40];
    std::snprintf(buf, sizeof buf, fmt, v);
    return pad(buf, num_width, true);
  }
  static std::string count(long v, std::size_t w) { return pad(v < 0 ? "-" : std::to_string(v), w, true); }

  std::string header() const {
    std::string s = pad("", count_width);
    for (std::size_t i = 0; i < keys.size(); ++i) s.append("  ").append(pad(keys[i], key_width[i]));
    s.append("  ").append(pad("status", 8));
    for (const char* h : {"wall_s", "psteps/s", "disp_rms", "vel_rms", "stress_rms", "mass_rel", "mom_rel"})
      s.append(" ").append(pad(h, num_width, true));
    s.append(" ").append(pad("fallbk", 6, true)).append(" ").append(pad("steps", 7, true));
    s.append(" ").append(pad("particles", 9, true)).append("  reason");
    return s;
  }

  std::string line(const StudyRow& r, std::size_t i, std::size_t total) const {
    std::string s = pad("[" + std::to_string(i) + "/" + std::to_string(total) + "]", count_width);
    for (std::size_t k = 0; k < keys.size(); ++k) s.append("  ").append(pad(r.values[k], key_width[k]));
    s.append("  ").append(pad(r.status, 8));
    s.append(" ").append(num(r.wall_s, "%.3g"));
    s.append(" ").append(num(r.particle_steps_per_s, "%.3g"));
    for (double v : {r.displacement_rms, r.velocity_rms, r.stress_rms, r.mass_rel_max, r.momentum_rel_max})
      s.append(" ").append(num(v, "%.3e"));
    const std::string fallbacks = std::isnan(r.fallbacks) ? "-" : std::to_string(static_cast<long>(r.fallbacks));
    s.append(" ").append(pad(fallbacks, 6, true));
    s.append(" ").append(count(r.steps, 7)).append(" ").append(count(r.particles, 9));
    if (!r.reason.empty()) s.append("  ").append(r.reason);
    return s;
  }
};

// ---- HDF5 ---------------------------------------------------------------------------------------------------

Handle vlen_utf8(const std::string& file) {
  Handle t = own(H5Tcopy(H5T_C_S1), H5Tclose, file, "H5Tcopy");
  check(H5Tset_size(t.get(), H5T_VARIABLE), file, "H5Tset_size");
  check(H5Tset_cset(t.get(), H5T_CSET_UTF8), file, "H5Tset_cset");
  return t;
}

void h5_strings_attr(hid_t obj, const std::string& name, const std::vector<std::string>& values, bool scalar,
                     const std::string& file) {
  Handle type = vlen_utf8(file);
  const hsize_t n = values.size();
  Handle space = own(scalar ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &n, nullptr), H5Sclose, file, "H5Screate");
  Handle attr = own(H5Acreate2(obj, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, file,
            "H5Acreate2('" + name + "')");
  std::vector<const char*> ptrs;
  for (const auto& v : values) ptrs.push_back(v.c_str());
  if (!ptrs.empty()) check(H5Awrite(attr.get(), type.get(), ptrs.data()), file, "H5Awrite('" + name + "')");
}

void h5_int_attr(hid_t obj, const std::string& name, long long v, const std::string& file) {
  Handle space = own(H5Screate(H5S_SCALAR), H5Sclose, file, "H5Screate");
  Handle attr = own(H5Acreate2(obj, name.c_str(), H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, file,
            "H5Acreate2('" + name + "')");
  check(H5Awrite(attr.get(), H5T_NATIVE_LLONG, &v), file, "H5Awrite('" + name + "')");
}

void h5_dataset(hid_t group, const std::string& name, hid_t file_type, hid_t mem_type, const void* data,
                hsize_t n, const std::string& file) {
  Handle space = own(H5Screate_simple(1, &n, nullptr), H5Sclose, file, "H5Screate_simple");
  Handle ds = own(H5Dcreate2(group, name.c_str(), file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
          H5Dclose, file, "H5Dcreate2('" + name + "')");
  if (n > 0)
    check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), file, "H5Dwrite('" + name + "')");
}

void h5_strings(hid_t group, const std::string& name, const std::vector<std::string>& values,
                const std::string& file) {
  Handle type = vlen_utf8(file);
  std::vector<const char*> ptrs;
  for (const auto& v : values) ptrs.push_back(v.c_str());
  h5_dataset(group, name, type.get(), type.get(), ptrs.data(), values.size(), file);
}

void h5_doubles(hid_t group, const std::string& name, const std::vector<double>& values, const std::string& file) {
  h5_dataset(group, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, values.data(), values.size(), file);
}

void h5_longs(hid_t group, const std::string& name, const std::vector<long long>& values, const std::string& file) {
  h5_dataset(group, name, H5T_STD_I64LE, H5T_NATIVE_LLONG, values.data(), values.size(), file);
}

void write_h5(const std::string& path, const json& scene, const std::vector<StudyAxis>& axes,
              const std::vector<StudyRow>& rows, const StudyOptions& options) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  const std::string tmp = path + ".partial";
  {
    Handle f = own(H5Fcreate(tmp.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, tmp, "H5Fcreate");
    std::vector<std::string> keys;
    nlohmann::ordered_json vary = nlohmann::ordered_json::object();  // in --vary order
    for (const auto& a : axes) {
      keys.push_back(a.key);
      nlohmann::ordered_json values = nlohmann::ordered_json::array();
      for (const auto& v : a.values) {
        json parsed = json::parse(v, nullptr, false);
        values.push_back(parsed.is_discarded() ? nlohmann::ordered_json(v) : nlohmann::ordered_json(parsed));
      }
      vary[a.key] = values;
    }
    h5_strings_attr(f.get(), "scene", {scene.dump()}, true, tmp);
    h5_strings_attr(f.get(), "varied_keys", keys, false, tmp);
    h5_strings_attr(f.get(), "vary", {vary.dump()}, true, tmp);
    h5_strings_attr(f.get(), "columns", study_columns(keys), false, tmp);
    h5_int_attr(f.get(), "repeat", options.repeat, tmp);
    h5_int_attr(f.get(), "threads", options.threads, tmp);

    Handle g = own(H5Gcreate2(f.get(), "table", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, tmp, "H5Gcreate2('table')");
    for (std::size_t k = 0; k < keys.size(); ++k) {
      std::vector<std::string> col;
      for (const auto& r : rows) col.push_back(r.values[k]);
      h5_strings(g.get(), keys[k], col, tmp);
    }
    auto doubles = [&](const char* name, double StudyRow::*field) {
      std::vector<double> col;
      for (const auto& r : rows) col.push_back(r.*field);
      h5_doubles(g.get(), name, col, tmp);
    };
    doubles("wall_s", &StudyRow::wall_s);
    doubles("particle_steps_per_s", &StudyRow::particle_steps_per_s);
    doubles("displacement_rms", &StudyRow::displacement_rms);
    doubles("velocity_rms", &StudyRow::velocity_rms);
    doubles("stress_rms", &StudyRow::stress_rms);
    doubles("displacement_rel_l2", &StudyRow::displacement_rel_l2);
    doubles("stress_rel_l2", &StudyRow::stress_rel_l2);
    doubles("mass_rel_max", &StudyRow::mass_rel_max);
    doubles("momentum_rel_max", &StudyRow::momentum_rel_max);
    doubles("fallbacks", &StudyRow::fallbacks);
    std::vector<long long> steps, particles, exit_status;
    std::vector<std::string> status, reason;
    for (const auto& r : rows) {
      steps.push_back(r.steps);
      particles.push_back(r.particles);
      exit_status.push_back(r.exit_status);
      status.push_back(r.status);
      reason.push_back(r.reason);
    }
    h5_longs(g.get(), "steps", steps, tmp);
    h5_longs(g.get(), "particles", particles, tmp);
    h5_strings(g.get(), "status", status, tmp);
    h5_strings(g.get(), "reason", reason, tmp);
    doubles("cell_size", &StudyRow::cell_size);
    h5_longs(g.get(), "exit_status", exit_status, tmp);
    g.close(tmp);
    f.close(tmp);
  }
  fs::rename(tmp, path);
}

}  // namespace

// ---- public -------------------------------------------------------------------------------------------------

std::vector<std::string> split_top_level(const std::string& text, const std::string& what) {
  std::vector<std::string> out;
  std::string stack;  // the closing brackets we wait for
  bool in_string = false, escaped = false;
  std::size_t start = 0;
  auto push = [&](std::size_t end) {
    std::string v = trim(text.substr(start, end - start));
    if (v.empty())
      throw SceneError(what + ": empty value at position " + std::to_string(start) + " of '" + text +
                       "'; expected V1,V2,... (commas inside [], {} or quotes do not separate values)");
    out.push_back(std::move(v));
    start = end + 1;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped) escaped = false;
      else if (c == '\\') escaped = true;
      else if (c == '"') in_string = false;
      continue;
    }
    switch (c) {
      case '"': in_string = true; break;
      case '[': stack.push_back(']'); break;
      case '{': stack.push_back('}'); break;
      case ']':
      case '}':
        if (stack.empty() || stack.back() != c)
          throw SceneError(what + ": unbalanced '" + std::string(1, c) + "' at position " + std::to_string(i) +
                           " of '" + text + "'");
        stack.pop_back();
        break;
      case ',':
        if (stack.empty()) push(i);
        break;
      default: break;
    }
  }
  if (in_string) throw SceneError(what + ": unterminated string in '" + text + "'");
  if (!stack.empty())
    throw SceneError(what + ": missing '" + std::string(1, stack.back()) + "' in '" + text + "'");
  push(text.size());
  return out;
}

StudyAxis parse_vary(const std::string& assignment) {
  const auto eq = assignment.find('=');
  StudyAxis axis;
  if (eq != std::string::npos) axis.key = trim(assignment.substr(0, eq));
  if (eq == std::string::npos || axis.key.empty() || trim(assignment.substr(eq + 1)).empty())
    throw SceneError("--vary " + assignment + ": expected KEY=V1,V2,... such as grid.cells=[8,8],[16,16]");
  axis.values = split_top_level(assignment.substr(eq + 1), "--vary " + axis.key);
  return axis;
}

std::vector<std::vector<std::size_t>> cross_product(const std::vector<std::size_t>& sizes) {
  std::vector<std::vector<std::size_t>> out;
  std::size_t total = 1;
  for (std::size_t s : sizes) total *= s;
  out.reserve(total);
  std::vector<std::size_t> idx(sizes.size(), 0);
  for (std::size_t n = 0; n < total; ++n) {
    out.push_back(idx);
    // odometer: the last axis turns fastest
    for (std::size_t k = sizes.size(); k-- > 0;) {
      if (++idx[k] < sizes[k]) break;
      idx[k] = 0;
    }
  }
  return out;
}

std::string display_value(const std::string& value_text) {
  const json v = json::parse(value_text, nullptr, false);
  if (v.is_discarded()) return value_text;
  return v.is_string() ? v.get<std::string>() : v.dump();
}

void validate_study(const nlohmann::json& base, const std::vector<StudyAxis>& axes) {
  parse_scene(base);
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const auto& a = axes[i];
    if (a.values.empty()) throw SceneError("--vary " + a.key + ": expected at least one value");
    for (std::size_t j = 0; j < i; ++j)
      if (axes[j].key == a.key) throw SceneError("--vary " + a.key + ": the key is varied twice");
    for (const auto& v : a.values) {
      json j = base;
      const std::string what = vary_what(a.key, v);
      apply(j, a.key, v, what);
      try {
        parse_scene(j);
      } catch (const SceneError& e) {
        throw SceneError(what + ": " + e.what());
      }
    }
  }
}

std::vector<std::string> study_columns(const std::vector<std::string>& keys) {
  std::vector<std::string> c = keys;
  for (const char* name : {"wall_s", "particle_steps_per_s", "displacement_rms", "velocity_rms", "stress_rms",
                           "displacement_rel_l2", "stress_rel_l2", "mass_rel_max", "momentum_rel_max", "fallbacks", "steps", "particles", "status", "reason"})
    c.push_back(name);
  return c;
}

StudyResult run_study(const nlohmann::json& base_in, const std::vector<StudyAxis>& axes,
                      const StudyOptions& options) {
  json base = base_in;
  drop_output_file(base);
  validate_study(base, axes);

  StudyResult result;
  for (const auto& a : axes) result.keys.push_back(a.key);
  const fs::path dir = options.out_dir.empty() ? fs::path(".") : fs::path(options.out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("cannot create the study directory " + dir.string() +
                             (ec ? ": " + ec.message() : std::string()));
  result.csv_path = (dir / "study.csv").string();
  result.h5_path = (dir / "study.h5").string();

  // The CSV grows row by row under a temporary name, so an interrupted study keeps the rows it finished.
  const std::string csv_tmp = result.csv_path + ".partial";
  std::ofstream csv(csv_tmp, std::ios::trunc);
  if (!csv) throw std::runtime_error("cannot write " + csv_tmp);
  csv << csv_line(study_columns(result.keys)) << std::flush;

  std::vector<std::size_t> sizes;
  for (const auto& a : axes) sizes.push_back(a.values.size());
  const auto combos = cross_product(sizes);
  const Table table(axes, combos.size());
  if (options.log) *options.log << table.header() << std::endl;

  for (std::size_t n = 0; n < combos.size(); ++n) {
    json scene = base;
    std::vector<std::string> values;
    for (std::size_t k = 0; k < axes.size(); ++k) {
      const std::string& v = axes[k].values[combos[n][k]];
      apply(scene, axes[k].key, v, vary_what(axes[k].key, v));  // checked by validate_study
      values.push_back(display_value(v));
    }
    StudyRow row = run_row(scene, options.repeat, options.threads);
    row.values = std::move(values);
    csv << csv_line(csv_row(row)) << std::flush;
    if (!csv) throw std::runtime_error("cannot write " + csv_tmp);
    if (options.log) *options.log << table.line(row, n + 1, combos.size()) << std::endl;
    result.rows.push_back(std::move(row));
  }
  csv.close();
  if (!csv) throw std::runtime_error("cannot write " + csv_tmp);
  fs::rename(csv_tmp, result.csv_path);
  write_h5(result.h5_path, base, axes, result.rows, options);
  return result;
}

std::string find_plot_script() {
  std::vector<fs::path> candidates;
  if (const char* env = std::getenv("MPM_PLOT_STUDY")) candidates.emplace_back(env);
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path() / ".." / ".." / "tools" / "plot_study.py");
  const fs::path source(__FILE__);  // CMake compiles with absolute source paths
  if (source.is_absolute()) candidates.push_back(source.parent_path().parent_path() / "tools" / "plot_study.py");
  for (const auto& c : candidates)
    if (fs::is_regular_file(c, ec)) return fs::weakly_canonical(c, ec).string();
  return {};
}

bool plot_study(const StudyResult& result, const std::string& out_dir, std::ostream& note) {
  const std::string script = find_plot_script();
  if (script.empty()) {
    note << "note: no plots: tools/plot_study.py not found beside the executable or its source tree; the study "
            "itself is complete\n";
    return false;
  }
  if (access(kPython, X_OK) != 0) {
    note << "note: no plots: " << kPython << " is not available; the study itself is complete (plot later with: "
         << "python3 " << script << " " << result.h5_path << " --out " << out_dir << ")\n";
    return false;
  }
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  const std::string dir = out_dir.empty() ? "." : out_dir;
  std::vector<std::string> args{kPython, script, result.h5_path, "--out", dir};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid < 0) {
    note << "note: no plots: cannot start " << kPython << "; the study itself is complete\n";
    return false;
  }
  if (pid == 0) {
    execv(kPython, argv.data());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      note << "note: no plots: lost track of the plotting process; the study itself is complete\n";
      return false;
    }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return true;
  note << "note: no plots (" << script << " "
       << (WIFEXITED(status) ? "exited with status " + std::to_string(WEXITSTATUS(status)) : std::string("was killed"))
       << "; is matplotlib installed?); the study itself is complete\n";
  return false;
}

int study_command(const StudyCommand& command) {
  try {
    if (command.scene_path.empty()) throw SceneError("mpm study: a scene file is required");
    if (command.vary.empty()) throw SceneError("mpm study: expected at least one --vary KEY=V1,V2,...");
    if (command.repeat < 1) throw SceneError("--repeat " + std::to_string(command.repeat) + ": expected at least 1");
    json base = read_json_file(command.scene_path);
    for (const auto& s : command.sets) apply_override(base, s);
    drop_output_file(base);
    std::vector<StudyAxis> axes;
    for (const auto& v : command.vary) axes.push_back(parse_vary(v));
    validate_study(base, axes);

    const std::string out_dir =
        command.out_dir.empty() ? "study-" + fs::path(command.scene_path).stem().string() : command.out_dir;
    {
      std::error_code ec;
      fs::create_directories(out_dir, ec);
      if (ec || !fs::is_directory(out_dir) || access(out_dir.c_str(), W_OK) != 0)
        throw SceneError("--out " + out_dir + ": expected a directory that can be created and written" +
                         (ec ? " (" + ec.message() + ")" : std::string()));
    }

    std::size_t total = 1;
    std::string axes_text;
    for (const auto& a : axes) {
      total *= a.values.size();
      axes_text += (axes_text.empty() ? "" : " x ") + a.key + " (" + std::to_string(a.values.size()) + ")";
    }
    std::cout << "study: " << total << " run" << (total == 1 ? "" : "s") << " of " << command.scene_path << " over "
              << axes_text;
    if (command.repeat > 1) std::cout << ", median wall time of " << command.repeat << " repeats";
    std::cout << "; output in " << out_dir << "\n";

    StudyOptions options;
    options.repeat = command.repeat;
    options.threads = command.threads;
    options.out_dir = out_dir;
    options.log = &std::cout;
    const StudyResult result = run_study(base, axes, options);

    std::size_t ok = 0;
    for (const auto& r : result.rows) ok += r.status == "ok";
    std::cout << "study: " << ok << " of " << result.rows.size() << " runs ok; wrote " << result.csv_path << ", "
              << result.h5_path << std::endl;
    if (command.plot && plot_study(result, out_dir, std::cerr))
      std::cout << "plots: " << (fs::path(out_dir) / "convergence.png").string() << ", "
                << (fs::path(out_dir) / "error_vs_time.png").string() << std::endl;
    return exit_ok;
  } catch (const SceneError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return exit_invalid;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mpm study: %s\n", e.what());
    return exit_failure;
  }
}

}  // namespace mpm
