// Scene file parsing and validation (DESIGN.md, "Scene file" and "Command line" contracts).
//
// Every rejection is one line, "scene: <dotted.key> = <value>: expected <what>", so that a user who mistyped a
// scene learns which key, what they gave and what would have been accepted, before anything is allocated.
// Scene::source is rebuilt from the typed result, so it records every default exactly as it will run.
#include "engine/scene.hpp"

#include "engine/triangle_mesh.hpp"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace mpm {
namespace {

using json = nlohmann::json;
using Keys = std::vector<std::string>;

// ---------------------------------------------------------------------------------------------------------
// Messages

/// A value as compact JSON, shortened so that a huge array cannot flood the one-line message.
std::string show(const json& v) {
  if (v.is_number_float() && !std::isfinite(v.get<double>())) return std::isnan(v.get<double>()) ? "nan" : "inf";
  std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
  if (s.size() > 80) {
    std::size_t n = 76;
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;  // do not split a UTF-8 character
    s = s.substr(0, n) + " ...";
  }
  return s;
}

/// Control characters (a key may contain a newline) would break the one-line promise.
std::string one_line(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (static_cast<unsigned char>(c) >= 0x20) r += c;
    else if (c == '\n') r += "\\n";
    else r += '?';
  }
  return r;
}

[[noreturn]] void fail(const std::string& path, const json& value, const std::string& what) {
  throw SceneError(one_line("scene: " + (path.empty() ? std::string("<top level>") : path) + " = " + show(value) +
                            ": " + what));
}
[[noreturn]] void missing(const std::string& path, const std::string& expected) {
  throw SceneError(one_line("scene: " + path + " is missing: expected " + expected));
}

std::string num(double x) { return json(x).dump(); }
/// A large count or size for a message: "4e10", "9313".
std::string approx(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, x < 1e5 ? "%.0f" : "%.3g", x);
  std::string r = buf;
  if (auto e = r.find("e+"); e != std::string::npos) {
    std::size_t digits = e + 2;
    while (digits + 1 < r.size() && r[digits] == '0') ++digits;
    r = r.substr(0, e + 1) + r.substr(digits);
  }
  return r;
}
std::string plural(int n, const std::string& noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); }
std::string quoted_list(const Keys& names) {
  std::string r;
  for (std::size_t i = 0; i < names.size(); ++i) r += (i ? ", \"" : "\"") + names[i] + "\"";
  return r;
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (same ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

/// The known name closest to a typo, if it is close enough to be what was meant.
std::optional<std::string> closest(const std::string& given, const Keys& known) {
  std::optional<std::string> best;
  std::size_t best_d = std::max<std::size_t>(1, given.size() / 3) + 1;
  for (const auto& k : known) {
    const std::size_t d = edit_distance(given, k);
    if (d < best_d) best_d = d, best = k;
  }
  return best;
}

// ---------------------------------------------------------------------------------------------------------
// Reading typed values

/// An object of the scene at a dotted path. An absent object reads as empty, so that a missing required key
/// inside it is reported by its full path ("grid.cells is missing"), not as a missing section.
struct Node {
  const json* j = nullptr;
  std::string path;

  const json* find(const std::string& key) const {
    if (!j) return nullptr;
    auto it = j->find(key);
    return it == j->end() ? nullptr : &*it;
  }
  std::string at(const std::string& key) const { return path.empty() ? key : path + "." + key; }
};

/// Where a key misplaced at the top level belongs, for the "did you mean" hint.
const std::vector<std::pair<std::string, Keys>>& sections() {
  static const std::vector<std::pair<std::string, Keys>> s = {
      {"grid", {"length", "cells", "mesh", "basis", "basis_path", "maxent_dmax"}},
      {"particles", {"per_cell", "layout", "seed"}},
      {"material", {"model", "E", "nu", "density"}},
      {"algorithm", {"update", "mass", "mapping", "gauss_per_cell", "mls_support", "tls_degree", "ddmpm_subpoints"}},
      {"time", {"dt", "cfl", "end", "energy_tolerance", "start"}},
      {"output", {"file", "every", "checkpoint_every"}},
  };
  return s;
}
const Keys& section_keys(const std::string& name) {
  for (const auto& [section, keys] : sections())
    if (section == name) return keys;
  throw std::logic_error("scene: no section " + name);
}

/// Checks that `j` (if present) is an object whose keys are all in `allowed`.
Node object_at(const json* j, const std::string& path, const Keys& allowed) {
  if (j && !j->is_object()) fail(path, *j, "expected an object");
  if (j) {
    for (const auto& [key, value] : j->items()) {
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      const std::string where = path.empty() ? key : path + "." + key;
      std::string hint;
      if (auto near = closest(key, allowed)) hint = "; did you mean \"" + (path.empty() ? "" : path + ".") + *near + "\"?";
      else if (path.empty())
        for (const auto& [section, keys] : sections())
          if (std::find(keys.begin(), keys.end(), key) != keys.end()) hint = "; did you mean \"" + section + "." + key + "\"?";
      if (hint.empty()) hint = " (known keys: " + quoted_list(allowed) + ")";
      fail(where, value, "unknown key" + hint);
    }
  }
  return Node{j, path};
}

/// An integer, or an integral float such as 1e3 (JSON has one number type; "1e3 cells" is not a type error).
std::optional<long long> integer_value(const json& v) {
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    return u > static_cast<std::uint64_t>(std::numeric_limits<long long>::max()) ? std::numeric_limits<long long>::max()
                                                                                 : static_cast<long long>(u);
  }
  if (v.is_number_integer()) return v.get<long long>();
  if (v.is_number_float()) {
    const double x = v.get<double>();
    if (std::isfinite(x) && std::floor(x) == x && std::fabs(x) < 9.0e18) return static_cast<long long>(x);
  }
  return std::nullopt;
}

std::optional<double> number_value(const json& v) {
  if (!v.is_number()) return std::nullopt;  // strings such as "nan" or "1e6" are type errors
  const double x = v.get<double>();
  return std::isfinite(x) ? std::optional<double>(x) : std::nullopt;
}

using Pred = std::function<bool(double)>;
bool positive(double x) { return x > 0; }

/// A finite number satisfying `ok`; `def` when absent (missing if there is no default).
double number(const Node& n, const std::string& key, std::optional<double> def, const Pred& ok,
              const std::string& expected) {
  const json* v = n.find(key);
  if (!v) {
    if (!def) missing(n.at(key), expected);
    return *def;
  }
  const auto x = number_value(*v);
  if (!x || !ok(*x)) fail(n.at(key), *v, "expected " + expected);
  return *x;
}

long long integer(const Node& n, const std::string& key, std::optional<long long> def, long long lo, long long hi,
                  const std::string& expected) {
  const json* v = n.find(key);
  if (!v) {
    if (!def) missing(n.at(key), expected);
    return *def;
  }
  const auto x = integer_value(*v);
  if (!x || *x < lo || *x > hi) fail(n.at(key), *v, "expected " + expected);
  return *x;
}

/// One of a fixed set of names; a near miss gets a suggestion.
template <class E, std::size_t N>
E choice(const Node& n, const std::string& key, E def, const std::array<std::pair<const char*, E>, N>& names) {
  const json* v = n.find(key);
  if (!v) return def;
  Keys known;
  for (const auto& [name, e] : names) {
    if (v->is_string() && v->get<std::string>() == name) return e;
    known.push_back(name);
  }
  std::string what = "expected one of " + quoted_list(known);
  if (v->is_string())
    if (auto near = closest(v->get<std::string>(), known)) what += "; did you mean \"" + *near + "\"?";
  fail(n.at(key), *v, what);
}

template <class E, std::size_t N>
std::string name_of(E e, const std::array<std::pair<const char*, E>, N>& names) {
  for (const auto& [name, value] : names)
    if (value == e) return name;
  throw std::logic_error("scene: enum value without a name");
}

/// An array of exactly `dim` finite numbers satisfying `ok`.
std::array<double, 3> numbers(const Node& n, const std::string& key, int dim, std::optional<std::array<double, 3>> def,
                              const Pred& ok, const std::string& expected) {
  const json* v = n.find(key);
  if (!v) {
    if (!def) missing(n.at(key), expected);
    return *def;
  }
  std::array<double, 3> r = def.value_or(std::array<double, 3>{1, 1, 1});
  if (!v->is_array() || v->size() != static_cast<std::size_t>(dim)) fail(n.at(key), *v, "expected " + expected);
  for (int i = 0; i < dim; ++i) {
    const auto x = number_value((*v)[i]);
    if (!x || !ok(*x)) fail(n.at(key), *v, "expected " + expected);
    r[i] = *x;
  }
  return r;
}

/// An array of exactly `dim` integers in [lo, hi]; unused axes are 1 so a product over all three is still right.
std::array<int, 3> integers(const Node& n, const std::string& key, int dim, std::optional<int> def, int lo, int hi,
                            const std::string& expected) {
  std::array<int, 3> r{1, 1, 1};
  const json* v = n.find(key);
  if (!v) {
    if (!def) missing(n.at(key), expected);
    for (int i = 0; i < dim; ++i) r[i] = *def;
    return r;
  }
  if (!v->is_array() || v->size() != static_cast<std::size_t>(dim)) fail(n.at(key), *v, "expected " + expected);
  for (int i = 0; i < dim; ++i) {
    const auto x = integer_value((*v)[i]);
    if (!x || *x < lo || *x > hi) fail(n.at(key), *v, "expected " + expected);
    r[i] = static_cast<int>(*x);
  }
  return r;
}

// ---------------------------------------------------------------------------------------------------------
// Names

constexpr std::array<std::pair<const char*, Basis>, 6> kBasis{{{"linear", Basis::linear},
                                                              {"bspline2", Basis::bspline2},
                                                              {"bspline3", Basis::bspline3},
                                                              {"ddmpm", Basis::ddmpm},
                                                              {"maxent", Basis::maxent},
                                                              {"powell-sabin", Basis::powell_sabin}}};
constexpr std::array<std::pair<const char*, BasisPath>, 2> kPath{{{"fast", BasisPath::fast}, {"generic", BasisPath::generic}}};
constexpr std::array<std::pair<const char*, Layout>, 3> kLayout{
    {{"uniform", Layout::uniform}, {"gauss", Layout::gauss}, {"random", Layout::random}}};
constexpr std::array<std::pair<const char*, MaterialModel>, 2> kModel{
    {{"linear-elastic", MaterialModel::linear_elastic}, {"neo-hookean", MaterialModel::neo_hookean}}};
constexpr std::array<std::pair<const char*, Update>, 5> kUpdate{{{"usl", Update::usl},
                                                                 {"musl", Update::musl},
                                                                 {"usf", Update::usf},
                                                                 {"otm", Update::otm},
                                                                 {"unified", Update::unified}}};
constexpr std::array<std::pair<const char*, MassMatrix>, 3> kMass{
    {{"lumped", MassMatrix::lumped}, {"projection", MassMatrix::projection}, {"consistent", MassMatrix::consistent}}};
constexpr std::array<std::pair<const char*, Mapping>, 4> kMapping{{{"direct", Mapping::direct},
                                                                   {"mls", Mapping::mls},
                                                                   {"tls", Mapping::tls},
                                                                   {"cubic-spline", Mapping::cubic_spline}}};
constexpr std::array<std::pair<const char*, TimeStart>, 2> kTimeStart{
    {{"collocated", TimeStart::collocated}, {"staggered", TimeStart::staggered}}};
const Keys kSides{"x-", "x+", "y-", "y+"};

/// What a built-in problem brings: its dimension, parameters and the defaults of the keys a scene may omit.
struct ProblemInfo {
  const char* name;
  ProblemName id;
  int dim;
  Keys params;
  MaterialSpec material;
  double dt, end;
  std::vector<int> fixed;
  bool exact_before_start;  ///< the exact solution holds for t < 0 (a vibration), so time.start may be "staggered"
};

const std::vector<ProblemInfo>& problems() {
  using M = MaterialModel;
  static const std::vector<ProblemInfo> p = {
      {"vibrating-bar", ProblemName::vibrating_bar, 1, {"v0"}, {M::linear_elastic, 7e6, 0.0, 2000.0}, 1e-7, 1.9e-6, {0, 1}, true},
      {"vibrating-plate", ProblemName::vibrating_plate, 2, {"amplitude"}, {M::neo_hookean, 1e7, 0.3, 1000.0}, 1e-5, 0.2,
       {0, 1, 2, 3}, true},
      {"column-compaction", ProblemName::column_compaction, 1, {"height", "max_body_force", "ramp_time"},
       {M::linear_elastic, 1e6, 0.0, 1.0}, 1e-4, 0.5, {0}, false},
      {"vibrating-bar-traction", ProblemName::vibrating_bar_traction, 1, {}, {M::neo_hookean, 100.0, 0.0, 100.0}, 1e-4,
       0.4, {0}, false},
  };
  return p;
}

// ---------------------------------------------------------------------------------------------------------
// Sections

const ProblemInfo* read_problem(const json& top, int dim, ProblemSpec& spec) {
  const json* p = top.contains("problem") ? &top["problem"] : nullptr;
  if (!p) return nullptr;
  if (!p->is_object()) fail("problem", *p, "expected an object {\"name\": ..., parameters}");
  Keys names;
  for (const auto& info : problems()) names.push_back(info.name);
  auto it = p->find("name");
  if (it == p->end()) missing("problem.name", "one of " + quoted_list(names));
  const ProblemInfo* info = nullptr;
  for (const auto& candidate : problems())
    if (it->is_string() && it->get<std::string>() == candidate.name) info = &candidate;
  if (!info) {
    std::string what = "expected one of " + quoted_list(names);
    if (it->is_string())
      if (auto near = closest(it->get<std::string>(), names)) what += "; did you mean \"" + *near + "\"?";
    fail("problem.name", *it, what);
  }
  if (dim != info->dim)
    fail("dimension", top["dimension"], "problem \"" + std::string(info->name) + "\" needs dimension " + std::to_string(info->dim));

  // Each problem accepts only its own parameters: a parameter of another problem is a mistake, not a no-op.
  for (const auto& [key, value] : p->items())
    if (key != "name" && std::find(info->params.begin(), info->params.end(), key) == info->params.end()) {
      std::string what = "unknown parameter of problem \"" + std::string(info->name) + "\"";
      if (auto near = closest(key, info->params)) what += "; did you mean \"problem." + *near + "\"?";
      else what += info->params.empty() ? " (it has none)" : " (known: " + quoted_list(info->params) + ")";
      fail("problem." + key, value, what);
    }
  Node n{p, "problem"};
  spec.name = info->id;
  spec.v0 = number(n, "v0", spec.v0, positive, "a positive number (m/s)");
  spec.amplitude = number(n, "amplitude", spec.amplitude, [](double a) { return a > 0 && a <= 0.15; },
                          "0 < A ≤ 0.15 (m; larger amplitudes drive J = det F to ≤ 0, and J must stay > 0)");
  spec.height = number(n, "height", spec.height, positive, "a positive number (m)");
  spec.max_body_force = number(n, "max_body_force", spec.max_body_force, [](double) { return true; }, "a number (m/s²)");
  spec.ramp_time = number(n, "ramp_time", spec.ramp_time, positive, "a positive number (s)");
  return info;
}

MaterialSpec read_material(const json* j, const std::string& path, const MaterialSpec& base) {
  const Node n = object_at(j, path, section_keys("material"));
  MaterialSpec m;
  m.model = choice(n, "model", base.model, kModel);
  m.E = number(n, "E", base.E, positive, "a positive number (Pa)");
  m.nu = number(n, "nu", base.nu, [](double nu) { return nu >= 0 && nu < 0.5; }, "0 ≤ ν < 0.5");
  m.density = number(n, "density", base.density, positive, "a positive number (kg/m³)");
  return m;
}

json material_json(const MaterialSpec& m) {
  return {{"model", name_of(m.model, kModel)}, {"E", m.E}, {"nu", m.nu}, {"density", m.density}};
}

/// Refuses a scene whose particles could not fit in memory, before anything is allocated.
void check_memory(const Scene& s, const json& cells) {
  constexpr double bytes_per_particle = 250.0, engine_limit = 2e8;
  double particles = s.grid.triangles ? static_cast<double>(s.grid.triangles->triangle_count()) : 1.0;
  for (int i = 0; i < s.dimension; ++i) particles *= s.grid.cells[i];
  for (int i = 0; i < s.dimension; ++i) particles *= s.particles.per_cell[i];  // random: per_cell = {total, 1, 1}
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  double limit = engine_limit;
  if (pages > 0 && page > 0) limit = std::min(limit, static_cast<double>(pages) * static_cast<double>(page) / bytes_per_particle);
  if (particles <= limit) return;
  const double gib = bytes_per_particle / 1073741824.0;
  fail(s.grid.triangles ? "grid.mesh" : "grid.cells", cells, "would need " + approx(particles) + " particles ≈ " + approx(particles * gib) +
                                " GiB; this machine's limit is " + approx(limit) + " particles (≈ " + approx(limit * gib) +
                                " GiB at ~250 bytes each)");
}

json source_of(const Scene& s, const ProblemInfo* info) {
  const int d = s.dimension;
  auto vec = [d](const auto& a) {
    json r = json::array();
    for (int i = 0; i < d; ++i) r.push_back(a[i]);
    return r;
  };
  json j;
  j["dimension"] = d;
  if (info) {
    json p{{"name", info->name}};
    const ProblemSpec& q = s.problem;
    for (const auto& k : info->params)
      p[k] = k == "v0" ? q.v0 : k == "amplitude" ? q.amplitude : k == "height" ? q.height
           : k == "max_body_force" ? q.max_body_force : q.ramp_time;
    j["problem"] = p;
  }
  if (s.grid.triangles)
    j["grid"] = {{"length", vec(s.grid.length)}, {"mesh", s.grid.mesh}, {"basis", name_of(s.grid.basis, kBasis)}};
  else
    j["grid"] = {{"length", vec(s.grid.length)}, {"cells", vec(s.grid.cells)}, {"basis", name_of(s.grid.basis, kBasis)},
                 {"basis_path", name_of(s.grid.path, kPath)}};
  if (s.grid.basis == Basis::maxent) j["grid"]["maxent_dmax"] = s.grid.maxent_dmax;
  const bool total = s.particles.layout == Layout::random || s.grid.triangles;
  j["particles"] = {{"per_cell", total ? json(s.particles.per_cell[0]) : vec(s.particles.per_cell)},
                    {"layout", name_of(s.particles.layout, kLayout)}, {"seed", s.particles.seed}};
  j["material"] = material_json(s.material);
  const AlgorithmSpec& a = s.algorithm;
  j["algorithm"] = {{"update", name_of(a.update, kUpdate)}, {"mass", name_of(a.mass, kMass)},
                    {"mapping", name_of(a.mapping, kMapping)}, {"gauss_per_cell", vec(a.gauss_per_cell)},
                    {"mls_support", a.mls_support}, {"tls_degree", a.tls_degree},
                    {"ddmpm_subpoints", a.ddmpm_subpoints}};
  j["time"] = {{"end", s.time.end}};
  if (s.time.dt) j["time"]["dt"] = *s.time.dt;
  if (s.time.cfl) j["time"]["cfl"] = *s.time.cfl;
  j["time"]["energy_tolerance"] = s.time.energy_tolerance;
  j["time"]["start"] = name_of(s.time.start, kTimeStart);
  j["output"] = {{"file", s.output.file}, {"every", s.output.every}, {"checkpoint_every", s.output.checkpoint_every}};
  if (!s.bodies.empty()) {
    json bodies = json::array();
    for (const auto& b : s.bodies) {
      json body{{"box", {vec(b.lo), vec(b.hi)}}, {"velocity", vec(b.velocity)}};
      if (b.material) body["material"] = material_json(*b.material);
      bodies.push_back(body);
    }
    j["bodies"] = bodies;
  }
  j["gravity"] = vec(s.gravity);
  j["fixed"] = json::array();
  for (int side : s.fixed_sides) j["fixed"].push_back(kSides[side]);
  return j;
}

// One reader per section of the scene; each fills its part of `s` and may read what earlier sections set.

/// A triangle mesh instead of cells (thesis §3.3, ch. 6): 2D, the P1 or Powell–Sabin basis; the file is read and
/// checked here, so `mpm validate` refuses a bad mesh naming the file and the element.
void read_mesh(const Node& grid, Scene& s) {
  const json& mesh = *grid.find("mesh");
  if (!mesh.is_string() || mesh.get<std::string>().empty()) fail("grid.mesh", mesh, "expected the path of a Gmsh mesh file");
  if (s.dimension != 2) fail("grid.mesh", mesh, "a triangle mesh needs dimension 2, not " + std::to_string(s.dimension));
  if (const json* cells = grid.find("cells"))
    fail("grid.cells", *cells, "expected either grid.cells or grid.mesh, not both");
  if (const json* path = grid.find("basis_path")) fail("grid.basis_path", *path, "a triangle mesh has one path; leave it out");
  if (const json* d = grid.find("maxent_dmax")) fail("grid.maxent_dmax", *d, "it applies to grid.basis = \"maxent\" only");
  s.grid.basis = choice(grid, "basis", Basis::linear, kBasis);
  if (s.grid.basis != Basis::linear && s.grid.basis != Basis::powell_sabin)
    fail("grid.basis", *grid.find("basis"), "on a triangle mesh expected \"linear\" or \"powell-sabin\"");
  s.grid.mesh = mesh.get<std::string>();
  s.grid.triangles = std::make_shared<const TriangleMesh>(read_gmsh(s.grid.mesh, {s.grid.length[0], s.grid.length[1]}));
}

void read_grid(const Node& top, Scene& s, const ProblemInfo* info) {
  const int dim = s.dimension;
  const std::string arr = "an array of " + std::to_string(dim) + " ";
  const Node grid = object_at(top.find("grid"), "grid", section_keys("grid"));
  s.grid.length = numbers(grid, "length", dim, std::nullopt, positive, arr + "positive numbers (m)");
  if (grid.find("mesh")) return read_mesh(grid, s);
  s.grid.cells = integers(grid, "cells", dim, std::nullopt, 1, 1 << 20, arr + "integers ≥ 1 and ≤ 1048576");
  s.grid.basis = choice(grid, "basis", Basis::bspline2, kBasis);
  if (s.grid.basis == Basis::powell_sabin)
    fail("grid.basis", *grid.find("basis"), "Powell–Sabin splines live on a triangle mesh: give grid.mesh (a Gmsh file) "
                                            "instead of grid.cells");
  // The fast path exists for linear and quadratic only, so an unspecified path follows the basis.
  s.grid.path = choice(grid, "basis_path", s.grid.basis == Basis::bspline3 ? BasisPath::generic : BasisPath::fast, kPath);
  if (s.grid.basis == Basis::bspline3 && s.grid.path == BasisPath::fast)
    fail("grid.basis_path", *grid.find("basis_path"), "there is no fast path for bspline3; use \"generic\"");
  if (has_ghost_ends(s.grid.basis) && s.grid.path == BasisPath::generic)
    fail("grid.basis_path", *grid.find("basis_path"),
         "grid.basis = \"" + name_of(s.grid.basis, kBasis) + "\" has one path; use \"fast\"");
  if (const json* d = grid.find("maxent_dmax"); d && s.grid.basis != Basis::maxent)
    fail("grid.maxent_dmax", *d, "it applies to grid.basis = \"maxent\" only, not \"" + name_of(s.grid.basis, kBasis) + "\"");
  s.grid.maxent_dmax = number(grid, "maxent_dmax", 2.0, [](double d) { return d > 1.0 && d <= 2.0; },
                              "a number in (1, 2] (the prior's support radius in cells; the stencil holds 4 nodes per axis)");

  // Problems whose body does not fill the grid need a grid that holds it.
  if (info && info->id == ProblemName::column_compaction && s.problem.height > s.grid.length[0])
    fail("problem.height", (*top.j)["problem"].value("height", json(s.problem.height)),
         "expected a column that fits in the grid: height ≤ grid.length.0 = " + num(s.grid.length[0]));
  if (info && info->id == ProblemName::vibrating_bar_traction && s.grid.length[0] < 1.0)
    fail("grid.length", *grid.find("length"), "expected grid.length.0 ≥ 1 (the bar occupies [0, 1] m)");
}

void read_seed(const Node& part, ParticleSpec& p) {
  if (const json* seed = part.find("seed")) {
    if (seed->is_number_unsigned()) p.seed = seed->get<std::uint64_t>();
    else if (auto x = integer_value(*seed); x && *x >= 0) p.seed = static_cast<std::uint64_t>(*x);
    else fail("particles.seed", *seed, "expected a non-negative integer");
  }
}

/// Particles per triangle: `[N]` (or N); the uniform layout puts them at the centroids of N equal sub-triangles,
/// which needs N = k², 3k² or 6k² (MeshSimulation); the random layout takes any N.
void read_triangle_particles(const Node& part, const json* per_cell, Basis basis, ParticleSpec& p) {
  if (p.layout == Layout::gauss)
    fail("particles.layout", *part.find("layout"), "on a triangle mesh expected \"uniform\" or \"random\"");
  const std::string expected = "[N] particles per triangle, N in 1..384";
  if (!per_cell) missing("particles.per_cell", expected);
  const json& n = per_cell->is_array() && per_cell->size() == 1 ? (*per_cell)[0] : *per_cell;
  const auto count = integer_value(n);
  if (!count || *count < 1 || *count > 384) fail("particles.per_cell", *per_cell, "expected " + expected);
  const auto square = [](long long x) { const long long r = std::llround(std::sqrt(static_cast<double>(x))); return r * r == x; };
  if (p.layout == Layout::uniform && !square(*count) && !(*count % 3 == 0 && square(*count / 3)) &&
      !(*count % 6 == 0 && square(*count / 6)))
    fail("particles.per_cell", *per_cell, "the uniform layout on triangles places k², 3k² or 6k² particles "
                                          "(1, 3, 4, 6, 9, 12, 16, 24, 25, 27, ...); use one of them or layout \"random\"");
  if (basis == Basis::powell_sabin) {
    const long long each = *count / 6;  // the six parts of a Powell–Sabin split share a triangle's particles
    if (*count % 6 != 0 || (p.layout == Layout::uniform && !square(each)))
      fail("particles.per_cell", *per_cell, "with grid.basis = \"powell-sabin\" each of a triangle's six split "
                                            "triangles gets N/6 particles: expected N = 6k² (6, 24, 54, 96, ...) for "
                                            "the uniform layout, a multiple of 6 for the random one");
  }
  p.per_cell = {static_cast<int>(*count), 1, 1};
  read_seed(part, p);
}

void read_particles(const Node& top, Scene& s) {
  const int dim = s.dimension;
  const std::string arr = "an array of " + std::to_string(dim) + " ";
  const Node part = object_at(top.find("particles"), "particles", section_keys("particles"));
  ParticleSpec& p = s.particles;
  p.layout = choice(part, "layout", Layout::uniform, kLayout);
  const json* per_cell = part.find("per_cell");
  if (!s.grid.mesh.empty()) return read_triangle_particles(part, per_cell, s.grid.basis, p);
  if (p.layout == Layout::random && per_cell && !per_cell->is_array()) {
    // random takes a total per cell, kept in per_cell[0] (scene.hpp)
    const long long most = static_cast<long long>(std::pow(64, dim));
    p.per_cell = {static_cast<int>(integer(part, "per_cell", std::nullopt, 1, most,
                                           "an integer in 1.." + std::to_string(most) + " or " + arr + "integers in 1..64")),
                  1, 1};
  } else {
    const int most = p.layout == Layout::gauss ? 10 : 64;
    p.per_cell = integers(part, "per_cell", dim, 2, 1, most,
                          arr + "integers in 1.." + std::to_string(most) +
                              (p.layout == Layout::gauss ? " (the gauss layout has at most 10 points per axis)" : ""));
    if (p.layout == Layout::random) p.per_cell = {p.per_cell[0] * p.per_cell[1] * p.per_cell[2], 1, 1};
  }
  read_seed(part, p);
}

/// OTM (thesis §4.2.1) is defined for consistent bases, piecewise-linear or max-ent; the unified approach
/// (Algorithm 4) for B-splines; both scatter from the particles and solve with the consistent mass (eqs 4.28, 4.81).
void check_moving_basis(const Node& alg, const Scene& s) {
  const AlgorithmSpec& a = s.algorithm;
  const json& update = *alg.find("update");
  const std::string method = a.update == Update::otm ? "OTM (thesis §4.2.1)" : "the unified approach (thesis Algorithm 4)";
  const bool otm_basis = s.grid.basis == Basis::linear || s.grid.basis == Basis::maxent;
  const bool bspline = s.grid.basis == Basis::linear || s.grid.basis == Basis::bspline2 || s.grid.basis == Basis::bspline3;
  if (a.update == Update::otm ? !otm_basis : !bspline)
    fail("algorithm.update", update,
         method + " is defined with grid.basis = " + (a.update == Update::otm ? "\"linear\" or \"maxent\"" : "\"linear\", \"bspline2\" or \"bspline3\"") +
             ", not \"" + name_of(s.grid.basis, kBasis) + "\"");
  if (a.mass != MassMatrix::consistent)
    fail("algorithm.update", update, method + " solves with the consistent mass: expected algorithm.mass = \"consistent\", not \"" +
                                         name_of(a.mass, kMass) + "\"");
  if (a.mapping != Mapping::direct)
    fail("algorithm.update", update, method + " integrates at the particles: expected algorithm.mapping = \"direct\", not \"" +
                                         name_of(a.mapping, kMapping) + "\"");
}

/// On a triangle mesh: USL or MUSL (thesis §3.4.4, §6.3.1); the TLS reconstruction with the P1 basis and the lumped
/// mass (thesis §6.1.2), direct mapping with either basis and any mass.
void check_mesh_algorithm(const Node& alg, const Scene& s) {
  const AlgorithmSpec& a = s.algorithm;
  if (a.update != Update::usl && a.update != Update::musl)
    fail("algorithm.update", *alg.find("update"), "on a triangle mesh (grid.mesh) expected \"usl\" or \"musl\"");
  if (a.mass != MassMatrix::lumped && a.mapping != Mapping::direct)
    fail("algorithm.mass", *alg.find("mass"), "the consistent mass on a triangle mesh takes the particles as carriers: "
                                              "expected algorithm.mapping = \"direct\", or algorithm.mass = \"lumped\"");
  if (a.mapping != Mapping::direct && a.mapping != Mapping::tls)
    fail("algorithm.mapping", *alg.find("mapping"), "on a triangle mesh (grid.mesh) expected \"direct\" or \"tls\"");
  if (a.mapping == Mapping::tls && s.grid.basis != Basis::linear)
    fail("algorithm.mapping", *alg.find("mapping"),
         "the TLS reconstruction on triangles is defined with grid.basis = \"linear\" (thesis §6.1.2), not \"" +
             name_of(s.grid.basis, kBasis) + "\"");
  if (const json* g = alg.find("gauss_per_cell"))
    fail("algorithm.gauss_per_cell", *g, "a triangle has its own Gauss rule (6 points); leave it out");
}

void read_algorithm(const Node& top, Scene& s) {
  const int dim = s.dimension;
  const Node alg = object_at(top.find("algorithm"), "algorithm", section_keys("algorithm"));
  AlgorithmSpec& a = s.algorithm;
  a.update = choice(alg, "update", Update::musl, kUpdate);
  a.mass = choice(alg, "mass", MassMatrix::lumped, kMass);
  a.mapping = choice(alg, "mapping", Mapping::direct, kMapping);
  if (a.mapping == Mapping::cubic_spline && dim != 1)
    fail("algorithm.mapping", *alg.find("mapping"), "\"cubic-spline\" is 1D only; expected \"direct\", \"mls\" or \"tls\"");
  a.gauss_per_cell = integers(alg, "gauss_per_cell", dim, 2, 1, 10, "an array of " + std::to_string(dim) + " integers in 1..10");
  a.mls_support = number(alg, "mls_support", 2.0, [](double r) { return r > 0.5 && r <= 10; }, "a number in (0.5, 10] (cells)");
  a.tls_degree = static_cast<int>(integer(alg, "tls_degree", 1, 0, 2, "0, 1 or 2"));
  a.ddmpm_subpoints = static_cast<int>(integer(alg, "ddmpm_subpoints", 1, 1, 1024, "an integer in 1..1024"));
  if (basis_moves_with_body(a.update)) check_moving_basis(alg, s);
  if (s.grid.triangles) check_mesh_algorithm(alg, s);
  if (const json* sub = alg.find("ddmpm_subpoints"); sub && a.ddmpm_subpoints > 1) {
    // the sub-point integration of Dhakal & Zhang replaces DDMPM's particle integration of the force in 1D
    if (s.grid.basis != Basis::ddmpm)
      fail("algorithm.ddmpm_subpoints", *sub, "sub-points need grid.basis = \"ddmpm\", not \"" +
                                                  std::string(name_of(s.grid.basis, kBasis)) + "\"");
    if (dim != 1) fail("algorithm.ddmpm_subpoints", *sub, "sub-points are defined in 1D only; this scene has dimension 2");
    if (a.mapping != Mapping::direct)
      fail("algorithm.ddmpm_subpoints", *sub, "sub-points integrate the particles' own stress: expected "
                                              "algorithm.mapping = \"direct\", not \"" +
                                                  std::string(name_of(a.mapping, kMapping)) + "\"");
  }
}

/// Exactly one of dt and cfl; the problem's dt applies only when the scene gives neither.
void read_time(const Node& top, Scene& s, const ProblemInfo* info) {
  const Node time = object_at(top.find("time"), "time", section_keys("time"));
  if (time.find("dt") && time.find("cfl"))
    fail("time.cfl", *time.find("cfl"), "expected either time.dt or time.cfl, not both");
  if (time.find("cfl"))
    s.time.cfl = number(time, "cfl", std::nullopt, [](double c) { return c > 0 && c <= 1; },
                        "a number in (0, 1] (fraction of the critical time step)");
  else if (time.find("dt") || !info)
    s.time.dt = number(time, "dt", std::nullopt, positive, "a positive number (s), or time.cfl in (0, 1]");
  else
    s.time.dt = info->dt;
  s.time.end = number(time, "end", info ? std::optional<double>(info->end) : std::nullopt, positive, "a positive number (s)");
  s.time.energy_tolerance = number(time, "energy_tolerance", s.time.energy_tolerance, positive,
                                   "a positive number (allowed energy gain beyond the external work, as a fraction "
                                   "of the largest energy; default 0.15)");
  s.time.start = choice(time, "start", TimeStart::collocated, kTimeStart);
  if (s.time.start == TimeStart::staggered && !(info && info->exact_before_start))
    fail("time.start", "staggered",
         "the velocity at t = -dt/2 comes from the exact solution of a vibration: expected problem.name = "
         "\"vibrating-bar\" or \"vibrating-plate\", not " +
             (info ? "\"" + std::string(info->name) + "\"" : std::string("a scene of bodies")));
  if (s.time.dt) {
    if (s.time.end < *s.time.dt) fail("time.end", s.time.end, "expected end ≥ time.dt = " + num(*s.time.dt));
    if (s.time.end / *s.time.dt > 1e9)
      fail("time.dt", *s.time.dt, "time.end / time.dt = " + approx(s.time.end / *s.time.dt) + " steps; expected at most 1e9 steps");
  }
}

void read_output(const Node& top, Scene& s) {
  const Node out = object_at(top.find("output"), "output", section_keys("output"));
  if (const json* f = out.find("file")) {
    if (!f->is_string()) fail("output.file", *f, "expected a string (path of the HDF5 file)");
    s.output.file = f->get<std::string>();
    if (!s.output.file.empty()) {
      // Checked now so that a long run does not fail at its first write; the file itself need not exist.
      const std::filesystem::path p(s.output.file);
      std::error_code ec;
      if (std::filesystem::is_directory(p, ec)) fail("output.file", *f, "expected a file name, not a directory");
      const std::string dir = p.parent_path().empty() ? "." : p.parent_path().string();
      if (access(dir.c_str(), W_OK | X_OK) != 0)
        fail("output.file", *f, "expected a file in a writable directory: " + dir + ": " + std::strerror(errno));
    }
  }
  const long long most = std::numeric_limits<int>::max();
  s.output.every = static_cast<int>(integer(out, "every", 0, 0, most, "an integer ≥ 0 (steps; 0: first and last only)"));
  s.output.checkpoint_every = static_cast<int>(integer(out, "checkpoint_every", 0, 0, most, "an integer ≥ 0 (steps; 0: none)"));
}

void read_bodies(const Node& top, Scene& s) {
  const json* b = top.find("bodies");
  if (!b) return;
  const int dim = s.dimension;
  if (!b->is_array() || b->empty()) fail("bodies", *b, "expected a non-empty array of bodies {\"box\": [[lo], [hi]], ...}");
  json length = json::array();
  for (int k = 0; k < dim; ++k) length.push_back(s.grid.length[k]);
  const std::string box_expected =
      "[[lo], [hi]] of " + plural(dim, "number") + " each with 0 ≤ lo < hi ≤ grid.length = " + show(length);
  for (std::size_t i = 0; i < b->size(); ++i) {
    const Node bn = object_at(&(*b)[i], "bodies." + std::to_string(i), {"box", "velocity", "material"});
    BodySpec body;
    const json* box = bn.find("box");
    if (!box) missing(bn.at("box"), box_expected);
    auto bad_box = [&] { fail(bn.at("box"), *box, "expected " + box_expected); };
    if (!box->is_array() || box->size() != 2) bad_box();
    for (int c = 0; c < 2; ++c) {
      const json& corner = (*box)[c];
      if (!corner.is_array() || corner.size() != static_cast<std::size_t>(dim)) bad_box();
      for (int k = 0; k < dim; ++k) {
        const auto x = number_value(corner[k]);
        if (!x || *x < 0 || *x > s.grid.length[k]) bad_box();
        (c == 0 ? body.lo : body.hi)[k] = *x;
      }
    }
    for (int k = 0; k < dim; ++k)
      if (!(body.lo[k] < body.hi[k])) bad_box();
    body.velocity = numbers(bn, "velocity", dim, std::array<double, 3>{0, 0, 0}, [](double) { return true; },
                            "an array of " + std::to_string(dim) + " numbers (m/s)");
    // a body's partial material is completed from the scene's
    if (const json* m = bn.find("material")) body.material = read_material(m, bn.at("material"), s.material);
    s.bodies.push_back(body);
  }
  // one global spline through the particles of separate bodies would bridge the gaps between them (thesis §3.2
  // reconstructs one body)
  if (s.algorithm.mapping == Mapping::cubic_spline && s.bodies.size() > 1)
    fail("bodies", *b, "expected one body with algorithm.mapping = \"cubic-spline\" (one spline per body), or "
                       "mapping \"direct\", \"mls\" or \"tls\"");
}

/// A scene's own list of fixed sides replaces the problem's.
void read_fixed(const Node& top, Scene& s, const ProblemInfo* info) {
  const Keys sides(kSides.begin(), kSides.begin() + 2 * s.dimension);
  const json* f = top.find("fixed");
  if (!f) {
    if (info) s.fixed_sides = info->fixed;
    return;
  }
  if (!f->is_array()) fail("fixed", *f, "expected an array of sides from " + quoted_list(sides));
  for (std::size_t i = 0; i < f->size(); ++i) {
    const json& e = (*f)[i];
    const std::string where = "fixed." + std::to_string(i);
    const auto it = e.is_string() ? std::find(sides.begin(), sides.end(), e.get<std::string>()) : sides.end();
    if (it == sides.end()) fail(where, e, "expected one of " + quoted_list(sides));
    const int side = static_cast<int>(it - sides.begin());
    if (std::find(s.fixed_sides.begin(), s.fixed_sides.end(), side) != s.fixed_sides.end())
      fail(where, e, "expected each side at most once (duplicate)");
    s.fixed_sides.push_back(side);
  }
}

}  // namespace

// -------------------------------------------------------------------------------------------------------------

Scene parse_scene(const json& j) {
  const Node top = object_at(&j, "", {"dimension", "problem", "grid", "particles", "material", "algorithm", "time",
                                      "output", "bodies", "gravity", "fixed"});
  Scene s;
  s.dimension = static_cast<int>(integer(top, "dimension", std::nullopt, 1, 2, "1 or 2"));
  if (!top.find("problem") && !top.find("bodies"))
    missing("problem", "a built-in problem {\"name\": ...} or a \"bodies\" array (one of the two)");
  if (top.find("problem") && top.find("bodies"))
    fail("bodies", *top.find("bodies"), "expected either \"problem\" or \"bodies\", not both (a problem supplies its own body)");
  const ProblemInfo* info = read_problem(j, s.dimension, s.problem);

  read_grid(top, s, info);
  read_particles(top, s);
  check_memory(s, *top.find("grid")->find(s.grid.triangles ? "mesh" : "cells"));
  // a partial material is completed from the problem's (or the generic) default
  s.material = read_material(top.find("material"), "material", info ? info->material : MaterialSpec{});
  read_algorithm(top, s);
  read_time(top, s, info);
  read_output(top, s);
  read_bodies(top, s);
  s.gravity = numbers(top, "gravity", s.dimension, std::array<double, 3>{0, 0, 0}, [](double) { return true; },
                      "an array of " + std::to_string(s.dimension) + " numbers (m/s²)");
  read_fixed(top, s, info);
  s.source = source_of(s, info);
  return s;
}

// Deeper JSON than any scene needs (the deepest key, bodies.N.box.N.N, is 5 levels) is refused while parsing:
// printing or copying a value is recursive, and 1e5 nested arrays overflow the stack.
constexpr int kMaxDepth = 32;

[[noreturn]] void too_deep(const std::string& where) {
  throw SceneError(one_line(where + ": nested deeper than " + std::to_string(kMaxDepth) + " levels"));
}

json read_json_text(const std::string& text, const std::string& origin) {
  // Duplicate keys are silently collapsed by JSON parsers; in a scene that hides a mistake, so they are errors.
  struct Frame {
    bool array;
    std::set<std::string> keys;
    std::string key;
    std::size_t index = 0;
  };
  std::vector<Frame> stack;
  auto path = [&stack] {
    std::string p;
    for (const auto& f : stack) p += (p.empty() ? "" : ".") + (f.array ? std::to_string(f.index) : f.key);
    return p;
  };
  auto child_done = [&stack] {
    if (!stack.empty() && stack.back().array) ++stack.back().index;
  };
  const json::parser_callback_t track = [&](int, json::parse_event_t ev, json& parsed) {
    if (stack.size() > kMaxDepth) too_deep("scene: " + origin + ": " + path());
    switch (ev) {
      case json::parse_event_t::object_start: stack.push_back({false, {}, {}, 0}); break;
      case json::parse_event_t::array_start: stack.push_back({true, {}, {}, 0}); break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!stack.empty()) stack.pop_back();
        child_done();
        break;
      case json::parse_event_t::key: {
        auto& f = stack.back();
        f.key = parsed.get<std::string>();
        if (!f.keys.insert(f.key).second)
          throw SceneError(one_line("scene: " + origin + ": " + path() + " is given twice (duplicate key)"));
        break;
      }
      case json::parse_event_t::value: child_done(); break;
    }
    return true;
  };
  try {
    return json::parse(text, track);
  } catch (const json::parse_error& e) {
    // nlohmann reports the 1-based byte position of the offending character; count lines and columns from it.
    const std::size_t pos = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    const std::size_t line = 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + pos, '\n'));
    const std::size_t nl = pos == 0 ? std::string::npos : text.rfind('\n', pos - 1);
    const std::size_t column = nl == std::string::npos ? pos + 1 : pos - nl;
    std::string msg = e.what();
    if (auto c = msg.find("] "); !msg.empty() && msg[0] == '[' && c != std::string::npos) msg.erase(0, c + 2);
    if (msg.rfind("parse error at line", 0) == 0)
      if (auto c = msg.find(": "); c != std::string::npos) msg.erase(0, c + 2);
    throw SceneError(one_line("scene: " + origin + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + msg));
  } catch (const json::exception& e) {
    // e.g. a number too large for a double (1e400): no position is reported, but the key being read is known
    std::string msg = e.what();
    if (auto c = msg.find("] "); !msg.empty() && msg[0] == '[' && c != std::string::npos) msg.erase(0, c + 2);
    const std::string key = path();
    throw SceneError(one_line("scene: " + origin + ": " + (key.empty() ? "" : key + ": ") + msg +
                              " (expected a finite number)"));
  }
}

json read_json_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw SceneError(one_line("scene: cannot read " + path + ": is a directory"));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(one_line("scene: cannot read " + path + ": " + std::strerror(errno)));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw SceneError(one_line("scene: cannot read " + path + ": " + std::strerror(errno)));
  json scene = read_json_text(text.str(), path);
  // a relative mesh path is relative to the scene file, wherever the run starts
  if (auto grid = scene.find("grid"); scene.is_object() && grid != scene.end() && grid->is_object())
    if (auto mesh = grid->find("mesh"); mesh != grid->end() && mesh->is_string() && !mesh->get<std::string>().empty()) {
      const std::filesystem::path m(mesh->get<std::string>());
      if (m.is_relative()) *mesh = (std::filesystem::path(path).parent_path() / m).lexically_normal().string();
    }
  return scene;
}

Scene load_scene_file(const std::string& path) { return parse_scene(read_json_file(path)); }

void apply_override(json& scene, const std::string& assignment) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0) throw SceneError(one_line("--set " + assignment + ": expected KEY=VALUE"));
  const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
  std::vector<std::string> parts;
  for (std::size_t start = 0;;) {
    const auto dot = key.find('.', start);
    parts.push_back(key.substr(start, dot - start));
    if (parts.back().empty()) throw SceneError(one_line("--set " + assignment + ": expected KEY=VALUE with a dotted KEY such as grid.cells"));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  // A JSON value if it parses as one; otherwise the text itself, so that `algorithm.mapping=mls` works unquoted.
  json value;
  try {
    value = json::parse(text, [&](int depth, json::parse_event_t, json&) {
      if (depth > kMaxDepth) too_deep("--set " + key);
      return true;
    });
  } catch (const json::parse_error&) {
    value = json::value_t::discarded;
  } catch (const json::out_of_range& e) {  // 1e400: a number, but not one a double holds
    throw SceneError(one_line("--set " + key + " = " + text + ": expected a finite number (" +
                              std::string(e.what()).substr(std::string(e.what()).find("] ") + 2) + ")"));
  }
  if (value.is_discarded()) {
    value = text;
    try {  // a scene is JSON text: a value that is not valid UTF-8 could never be written back (found by fuzzing)
      (void)value.dump();
    } catch (const json::type_error&) {
      throw SceneError(one_line("--set " + key + ": the value is not valid UTF-8 text"));
    }
  }

  json* node = &scene;
  std::string walked;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string& part = parts[i];
    const bool last = i + 1 == parts.size();
    if (node->is_null()) *node = json::object();
    if (node->is_array()) {
      // numeric path segments index arrays: grid.cells.0=64
      const bool digits = part.find_first_not_of("0123456789") == std::string::npos && part.size() < 10;
      const std::size_t idx = digits ? std::stoul(part) : 0;
      if (!digits || idx >= node->size())
        throw SceneError(one_line("--set " + assignment + ": " + walked + " is an array of " + std::to_string(node->size()) +
                                  "; expected an index below " + std::to_string(node->size()) + ", not " + part));
      if (last) (*node)[idx] = value;
      node = &(*node)[idx];
    } else if (node->is_object()) {
      // null removes a key (as in JSON merge patch), e.g. time.dt=null before setting time.cfl
      if (last && value.is_null()) node->erase(part);
      else if (last) (*node)[part] = value;
      else node = &(*node)[part];
    } else {
      throw SceneError(one_line("--set " + assignment + ": " + walked + " = " + show(*node) + " is not an object"));
    }
    walked += (walked.empty() ? "" : ".") + part;
  }
}

}  // namespace mpm
