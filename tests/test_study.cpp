// `mpm study` (engine/study.hpp): the --vary value splitter, the cross-product order, and small real studies run
// through run_study() into a temporary directory, including rows for runs that fail.
#include <catch2/catch.hpp>

#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "engine/scene.hpp"
#include "engine/study.hpp"

using namespace mpm;
namespace fs = std::filesystem;

namespace {

/// Vibrating bar (thesis Table 5.2 settings), small enough for a unit test.
nlohmann::json bar() {
  return {{"dimension", 1},
          {"problem", {{"name", "vibrating-bar"}, {"v0", 0.28}}},
          {"grid", {{"length", {1.0}}, {"cells", {10}}, {"basis", "bspline2"}}},
          {"particles", {{"per_cell", {12}}}},
          {"material", {{"model", "linear-elastic"}, {"E", 7e6}, {"nu", 0.0}, {"density", 2000.0}}},
          {"algorithm", {{"update", "musl"}, {"mass", "lumped"}}},
          {"time", {{"dt", 1e-7}, {"end", 1.9e-6}}},
          {"output", {{"file", "must-not-be-written.h5"}}}};
}

/// A fresh directory under the system's temporary directory, removed at the end of the test.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) {
    path = fs::temp_directory_path() / ("mpm-test-study-" + name + "-" + std::to_string(getpid()));
    fs::remove_all(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::vector<std::string> lines_of(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

long h5_rows(const fs::path& file, const std::string& dataset) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) return -1;
  const hid_t d = H5Dopen2(f, dataset.c_str(), H5P_DEFAULT);
  long n = -1;
  if (d >= 0) {
    const hid_t s = H5Dget_space(d);
    hsize_t dims[1] = {0};
    if (H5Sget_simple_extent_ndims(s) == 1) {
      H5Sget_simple_extent_dims(s, dims, nullptr);
      n = static_cast<long>(dims[0]);
    }
    H5Sclose(s);
    H5Dclose(d);
  }
  H5Fclose(f);
  return n;
}

}  // namespace

TEST_CASE("split_top_level splits at top-level commas only", "[study]") {
  CHECK(split_top_level("[8,8],[16,16]") == std::vector<std::string>{"[8,8]", "[16,16]"});
  CHECK(split_top_level("\"a,b\",c") == std::vector<std::string>{"\"a,b\"", "c"});
  CHECK(split_top_level("{\"x\":[1,2]},3") == std::vector<std::string>{"{\"x\":[1,2]}", "3"});
  CHECK(split_top_level("direct, tls") == std::vector<std::string>{"direct", "tls"});
  CHECK(split_top_level("\"say \\\"a,b\\\"\",[1]") == std::vector<std::string>{"\"say \\\"a,b\\\"\"", "[1]"});
  CHECK(split_top_level("lumped") == std::vector<std::string>{"lumped"});

  CHECK_THROWS_AS(split_top_level("[8,8"), SceneError);
  CHECK_THROWS_AS(split_top_level("[8,8}]"), SceneError);
  CHECK_THROWS_AS(split_top_level("\"a,b"), SceneError);
  CHECK_THROWS_AS(split_top_level("a,,b"), SceneError);
  CHECK_THROWS_AS(split_top_level("a,"), SceneError);

  const StudyAxis axis = parse_vary("grid.cells=[8,8],[16,16]");
  CHECK(axis.key == "grid.cells");
  CHECK(axis.values == std::vector<std::string>{"[8,8]", "[16,16]"});
  CHECK_THROWS_AS(parse_vary("grid.cells"), SceneError);
  CHECK_THROWS_AS(parse_vary("=1,2"), SceneError);
  CHECK_THROWS_AS(parse_vary("grid.cells="), SceneError);

  CHECK(display_value("\"tls\"") == "tls");
  CHECK(display_value("tls") == "tls");
  CHECK(display_value("[ 8, 8 ]") == "[8,8]");
  CHECK(display_value("1e-7") == "1e-07");
}

TEST_CASE("cross_product: nested loops in --vary order - the last axis fastest", "[study]") {
  using Tuples = std::vector<std::vector<std::size_t>>;
  CHECK(cross_product({2, 3}) == Tuples{{0, 0}, {0, 1}, {0, 2}, {1, 0}, {1, 1}, {1, 2}});
  CHECK(cross_product({3}) == Tuples{{0}, {1}, {2}});
  CHECK(cross_product({1, 2, 2}) == Tuples{{0, 0, 0}, {0, 0, 1}, {0, 1, 0}, {0, 1, 1}});
  CHECK(cross_product({}) == Tuples{{}});
  CHECK(cross_product({2, 0}).empty());
}

TEST_CASE("validate_study names the key and the value of a bad --vary value", "[study]") {
  const nlohmann::json base = bar();
  CHECK_NOTHROW(validate_study(base, {parse_vary("grid.cells=[10],[20]")}));
  try {
    validate_study(base, {parse_vary("algorithm.mass=lumped,projection"), parse_vary("grid.cells=[10],[0]")});
    FAIL("expected a SceneError");
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    CHECK_THAT(msg, Catch::Contains("grid.cells") && Catch::Contains("[0]"));
  }
  try {
    validate_study(base, {parse_vary("algorithm.mass=lumped,heavy")});
    FAIL("expected a SceneError");
  } catch (const SceneError& e) {
    CHECK_THAT(std::string(e.what()), Catch::Contains("algorithm.mass") && Catch::Contains("heavy"));
  }
  nlohmann::json bad = base;
  bad["material"]["E"] = -1.0;
  CHECK_THROWS_AS(validate_study(bad, {parse_vary("grid.cells=[10]")}), SceneError);
  CHECK_THROWS_AS(validate_study(base, {parse_vary("grid.cells=[10]"), parse_vary("grid.cells=[20]")}), SceneError);
}

TEST_CASE("a small vibrating-bar study: 4 rows - CSV and HDF5 - errors decrease with cells", "[study]") {
  TempDir dir("bar");
  StudyOptions options;
  options.out_dir = dir.path.string();
  options.threads = 2;
  std::ostringstream log;
  options.log = &log;
  const StudyResult r =
      run_study(bar(), {parse_vary("grid.cells=[10],[20]"), parse_vary("algorithm.mass=lumped,projection")}, options);

  REQUIRE(r.rows.size() == 4);
  CHECK(r.keys == std::vector<std::string>{"grid.cells", "algorithm.mass"});
  // first axis slowest
  CHECK(r.rows[0].values == std::vector<std::string>{"[10]", "lumped"});
  CHECK(r.rows[1].values == std::vector<std::string>{"[10]", "projection"});
  CHECK(r.rows[2].values == std::vector<std::string>{"[20]", "lumped"});
  CHECK(r.rows[3].values == std::vector<std::string>{"[20]", "projection"});
  for (const auto& row : r.rows) {
    CHECK(row.status == "ok");
    CHECK(row.exit_status == exit_ok);
    CHECK(row.reason.empty());
    CHECK(row.steps == 19);
    CHECK(row.wall_s >= 0);
    CHECK(std::isfinite(row.displacement_rms));
    CHECK(row.mass_rel_max <= 1e-13);
    CHECK(row.fallbacks == 0);
  }
  CHECK(r.rows[0].particles == 120);
  CHECK(r.rows[2].particles == 240);
  CHECK(r.rows[0].cell_size == Approx(0.1));
  CHECK(r.rows[2].cell_size == Approx(0.05));
  for (int m = 0; m < 2; ++m) {
    const StudyRow &coarse = r.rows[m], &fine = r.rows[2 + m];
    INFO("mass option " << coarse.values[1]);
    CHECK(fine.displacement_rms < coarse.displacement_rms);
    CHECK(fine.stress_rms < coarse.stress_rms);
  }
  // with lumped mass the velocity error at this early end time does not fall with h (MUSL's lumped projection
  // error dominates, thesis ch. 5); with the consistent-mass projection it does
  CHECK(r.rows[3].velocity_rms < r.rows[1].velocity_rms);

  // no per-run output files
  CHECK_FALSE(fs::exists("must-not-be-written.h5"));
  CHECK_FALSE(fs::exists(dir.path / "must-not-be-written.h5"));

  const auto lines = lines_of(dir.path / "study.csv");
  REQUIRE(lines.size() == 5);
  CHECK(lines[0] ==
        "grid.cells,algorithm.mass,wall_s,particle_steps_per_s,displacement_rms,velocity_rms,stress_rms,"
        "displacement_rel_l2,stress_rel_l2,mass_rel_max,momentum_rel_max,fallbacks,steps,particles,status,reason");
  CHECK(lines[1].rfind("[10],lumped,", 0) == 0);
  CHECK(lines[4].rfind("[20],projection,", 0) == 0);
  CHECK(lines[1].size() > 8);
  CHECK(lines[1].substr(lines[1].size() - 4) == ",ok,");
  CHECK_FALSE(fs::exists(dir.path / "study.csv.partial"));

  CHECK(h5_rows(dir.path / "study.h5", "table/displacement_rms") == 4);
  CHECK(h5_rows(dir.path / "study.h5", "table/grid.cells") == 4);
  CHECK(h5_rows(dir.path / "study.h5", "table/status") == 4);

  // the printed table: a header, then one line per row with its progress count
  const std::string printed = log.str();
  CHECK_THAT(printed, Catch::Contains("grid.cells") && Catch::Contains("algorithm.mass"));
  CHECK_THAT(printed, Catch::Contains("[1/4]") && Catch::Contains("[4/4]"));
}

TEST_CASE("runs that cannot run or go unstable become rows - the study completes", "[study]") {
  TempDir dir("failed");
  StudyOptions options;
  options.out_dir = dir.path.string();
  options.threads = 1;
  options.repeat = 3;
  SECTION("invalid: time.dt above the critical step") {
    // dt = 0.01 s is far above the critical step h/c (about 1.7e-3 s at 10 cells): status "invalid"
    const StudyResult r = run_study(
        bar(), {parse_vary(R"(time={"dt":1e-7,"end":1.9e-6},{"dt":0.01,"end":0.02})")}, options);
    REQUIRE(r.rows.size() == 2);
    CHECK(r.rows[0].status == "ok");
    CHECK(r.rows[1].status == "invalid");
    CHECK(r.rows[1].exit_status == exit_invalid);
    CHECK_THAT(r.rows[1].reason, Catch::Contains("time.dt") && Catch::Contains("critical"));
    CHECK(std::isnan(r.rows[1].displacement_rms));
    CHECK(std::isnan(r.rows[1].wall_s));
    CHECK(r.rows[1].steps == -1);

    const auto lines = lines_of(dir.path / "study.csv");
    REQUIRE(lines.size() == 3);
    CHECK(lines[0].rfind("time,wall_s,", 0) == 0);
    CHECK(lines[2].rfind(R"("{""dt"":0.01,""end"":0.02}",)", 0) == 0);
    CHECK_THAT(lines[2], Catch::Contains(",invalid,") && Catch::Contains("critical"));
    CHECK(h5_rows(dir.path / "study.h5", "table/reason") == 2);
  }
  SECTION("unstable: a body leaving the grid") {
    const nlohmann::json block = {{"dimension", 2},
                                  {"grid", {{"length", {1.0, 1.0}}, {"cells", {10, 10}}}},
                                  {"bodies", {{{"box", {{0.4, 0.4}, {0.6, 0.6}}}, {"velocity", {0.0, 0.0}}}}},
                                  {"material", {{"E", 1e5}, {"nu", 0.3}, {"density", 1000.0}}},
                                  {"time", {{"cfl", 0.5}, {"end", 0.05}}}};
    const StudyResult r = run_study(block, {parse_vary("bodies.0.velocity=[0.0,0.0],[50.0,0.0]")}, options);
    REQUIRE(r.rows.size() == 2);
    CHECK(r.rows[0].status == "ok");
    CHECK(r.rows[1].status == "unstable");
    CHECK(r.rows[1].exit_status == exit_unstable);
    CHECK_FALSE(r.rows[1].reason.empty());  // the engine's reason (CFL violated, or a particle left the grid)
    CHECK(r.rows[1].steps > 0);
    CHECK(std::isnan(r.rows[1].displacement_rms));  // no exact solution here, and none kept for a failed run
    const auto lines = lines_of(dir.path / "study.csv");
    REQUIRE(lines.size() == 3);
    CHECK_THAT(lines[2], Catch::Contains(",unstable,") && Catch::Contains(r.rows[1].reason));
  }
}
