// Scene parsing and validation: every malformed scene is refused with a one-line message naming the key,
// and a valid scene comes back typed, with every default filled in (engine/scene.hpp, DESIGN.md "Scene file").
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <string>

#include "engine/scene.hpp"

using nlohmann::json;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;

namespace {

// Minimal valid scenes: a 2D problem, a 1D problem and a 2D scene with its own bodies.
const json plate = R"({"dimension": 2, "problem": {"name": "vibrating-plate"},
                       "grid": {"length": [1.0, 1.0], "cells": [8, 8]}})"_json;
const json bar = R"({"dimension": 1, "problem": {"name": "vibrating-bar"},
                     "grid": {"length": [25.0], "cells": [16]}})"_json;
const json bodies = R"({"dimension": 2, "grid": {"length": [1.0, 1.0], "cells": [8, 8]},
                        "bodies": [{"box": [[0.4, 0.4], [0.6, 0.6]], "velocity": [0.0, -1.0]}],
                        "time": {"dt": 1e-4, "end": 0.1}, "gravity": [0.0, -9.81], "fixed": ["x-", "x+", "y-"]})"_json;

/// The message of the SceneError that parse_scene throws, or "" if it accepts the scene.
std::string error_of(const json& scene) {
  try {
    (void)mpm::parse_scene(scene);
  } catch (const mpm::SceneError& e) {
    return e.what();
  }
  return "";
}

struct Malformed {
  const char* what;
  const json* base;
  const char* pointer;  ///< JSON pointer of the one thing changed
  json value;           ///< new value; discarded: remove the key
  const char* key;      ///< the dotted key the message must name
};

const json erase = json(json::value_t::discarded);

}  // namespace

TEST_CASE("valid base scenes parse", "[scene]") {
  CHECK(error_of(plate).empty());
  CHECK(error_of(bar).empty());
  CHECK(error_of(bodies).empty());
}

TEST_CASE("DDMPM sub-points are refused outside 1D DDMPM with direct mapping - the message names both keys", "[scene][ddmpm]") {
  json b = bar;
  b["grid"]["basis"] = "ddmpm";
  b["algorithm"]["ddmpm_subpoints"] = 8;
  CHECK(error_of(b).empty());
  b["algorithm"]["ddmpm_subpoints"] = 0;
  CHECK_THAT(error_of(b), Catch::Contains("algorithm.ddmpm_subpoints"));
  b["algorithm"]["ddmpm_subpoints"] = 8;
  b["algorithm"]["mapping"] = "tls";
  CHECK_THAT(error_of(b), Catch::Contains("algorithm.ddmpm_subpoints") && Catch::Contains("algorithm.mapping"));
  json p = plate;
  p["grid"]["basis"] = "ddmpm";
  p["algorithm"]["ddmpm_subpoints"] = 8;
  CHECK_THAT(error_of(p), Catch::Contains("algorithm.ddmpm_subpoints") && Catch::Contains("dimension"));
  json q = bar;
  q["algorithm"]["ddmpm_subpoints"] = 8;
  CHECK_THAT(error_of(q), Catch::Contains("algorithm.ddmpm_subpoints") && Catch::Contains("grid.basis"));
}

TEST_CASE("OTM and the unified approach are refused outside the thesis' combinations - the message names both keys",
          "[scene][otm]") {
  json b = bar;
  b["algorithm"] = {{"update", "unified"}, {"mass", "consistent"}};
  CHECK(error_of(b).empty());
  b["algorithm"]["update"] = "otm";
  CHECK_THAT(error_of(b), Catch::Contains("algorithm.update") && Catch::Contains("grid.basis"));
  b["grid"]["basis"] = "maxent";
  CHECK(error_of(b).empty());
  b["algorithm"]["update"] = "unified";
  CHECK_THAT(error_of(b), Catch::Contains("algorithm.update") && Catch::Contains("grid.basis"));
  json p = plate;
  p["algorithm"] = {{"update", "unified"}};
  CHECK_THAT(error_of(p), Catch::Contains("algorithm.update") && Catch::Contains("algorithm.mass"));
  p["algorithm"] = {{"update", "otm"}, {"mass", "consistent"}, {"mapping", "tls"}};
  p["grid"]["basis"] = "linear";
  CHECK_THAT(error_of(p), Catch::Contains("algorithm.update") && Catch::Contains("algorithm.mapping"));
}

TEST_CASE("malformed scenes are refused with a message naming the key", "[scene]") {
  const std::vector<Malformed> cases = {
      {"unknown key in grid", &plate, "/grid/cels", json::array({8, 8}), "grid.cels"},
      {"unknown top-level key", &plate, "/colour", 1, "colour"},
      {"unknown key in time", &plate, "/time/units", "s", "time.units"},
      {"unknown key in a body", &bodies, "/bodies/0/speed", json::array({0, 0}), "bodies.0.speed"},
      {"negative E", &plate, "/material/E", -5, "material.E"},
      {"zero E", &plate, "/material/E", 0, "material.E"},
      {"E as the string nan", &plate, "/material/E", "nan", "material.E"},
      {"E as a boolean", &plate, "/material/E", true, "material.E"},
      {"nu = 0.5", &plate, "/material/nu", 0.5, "material.nu"},
      {"negative nu", &plate, "/material/nu", -0.1, "material.nu"},
      {"zero density", &plate, "/material/density", 0, "material.density"},
      {"unknown material model", &plate, "/material/model", "rubber", "material.model"},
      {"negative dt", &plate, "/time/dt", -1e-5, "time.dt"},
      {"cfl above 1", &plate, "/time/cfl", 1.5, "time.cfl"},
      {"both dt and cfl", &plate, "/time", json{{"dt", 1e-5}, {"cfl", 0.5}}, "time.cfl"},
      {"too many steps", &plate, "/time/dt", 1e-12, "time.dt"},
      {"end before dt", &bodies, "/time/end", 1e-5, "time.end"},
      {"no dt or cfl without a problem", &bodies, "/time/dt", erase, "time.dt"},
      {"negative energy tolerance", &plate, "/time/energy_tolerance", -0.1, "time.energy_tolerance"},
      {"zero energy tolerance", &plate, "/time/energy_tolerance", 0, "time.energy_tolerance"},
      {"energy tolerance as a string", &plate, "/time/energy_tolerance", "0.1", "time.energy_tolerance"},
      {"missing grid.cells", &plate, "/grid/cells", erase, "grid.cells"},
      {"missing grid.length", &plate, "/grid/length", erase, "grid.length"},
      {"zero cells", &plate, "/grid/cells", json::array({0, 8}), "grid.cells"},
      {"cells of the wrong length", &plate, "/grid/cells", json::array({8}), "grid.cells"},
      {"fractional cells", &plate, "/grid/cells", json::array({8.5, 8}), "grid.cells"},
      {"negative length", &plate, "/grid/length", json::array({1.0, -1.0}), "grid.length"},
      {"length as a string", &plate, "/grid/length", "1", "grid.length"},
      {"grid not an object", &plate, "/grid", 5, "grid"},
      {"absurd size", &plate, "/grid/cells", json::array({100000, 100000}), "grid.cells"},
      {"bad basis", &plate, "/grid/basis", "quadratic", "grid.basis"},
      {"bspline3 on the fast path", &plate, "/grid", R"({"length": [1, 1], "cells": [8, 8], "basis": "bspline3",
                                                         "basis_path": "fast"})"_json, "grid.basis_path"},
      {"ddmpm on the generic path", &plate, "/grid", R"({"length": [1, 1], "cells": [8, 8], "basis": "ddmpm",
                                                          "basis_path": "generic"})"_json, "grid.basis_path"},
      {"bad basis path", &plate, "/grid/basis_path", "quick", "grid.basis_path"},
      {"maxent_dmax without maxent", &plate, "/grid/maxent_dmax", 2.0, "grid.maxent_dmax"},
      {"maxent_dmax of 1", &plate, "/grid", R"({"length": [1, 1], "cells": [8, 8], "basis": "maxent", "maxent_dmax": 1})"_json,
       "grid.maxent_dmax"},
      {"maxent_dmax above 2", &plate, "/grid", R"({"length": [1, 1], "cells": [8, 8], "basis": "maxent", "maxent_dmax": 3})"_json,
       "grid.maxent_dmax"},
      {"DDMPM sub-points without ddmpm", &bar, "/algorithm", R"({"ddmpm_subpoints": 4})"_json, "algorithm.ddmpm_subpoints"},
      {"missing dimension", &plate, "/dimension", erase, "dimension"},
      {"dimension 3", &plate, "/dimension", 3, "dimension"},
      {"dimension as a string", &plate, "/dimension", "2", "dimension"},
      {"unknown problem", &plate, "/problem/name", "vibrating-plat", "problem.name"},
      {"problem without a name", &plate, "/problem", json::object(), "problem.name"},
      {"problem as a string", &plate, "/problem", "vibrating-plate", "problem"},
      {"1D problem in 2D", &bar, "/dimension", 2, "dimension"},
      {"parameter of another problem", &plate, "/problem/v0", 0.3, "problem.v0"},
      {"amplitude too large", &plate, "/problem/amplitude", 0.2, "problem.amplitude"},
      {"negative v0", &bar, "/problem/v0", -1, "problem.v0"},
      {"column taller than the grid", &bar, "/problem", json{{"name", "column-compaction"}}, "problem.height"},
      {"problem and bodies", &plate, "/bodies", bodies["bodies"], "bodies"},
      {"neither problem nor bodies", &bodies, "/bodies", erase, "problem"},
      {"empty bodies", &bodies, "/bodies", json::array(), "bodies"},
      {"body outside the grid", &bodies, "/bodies/0/box", R"([[0.4, 0.4], [1.2, 0.6]])"_json, "bodies.0.box"},
      {"body with lo > hi", &bodies, "/bodies/0/box", R"([[0.6, 0.4], [0.4, 0.6]])"_json, "bodies.0.box"},
      {"body without a box", &bodies, "/bodies/0/box", erase, "bodies.0.box"},
      {"body material nu = 0.5", &bodies, "/bodies/0/material", json{{"nu", 0.5}}, "bodies.0.material.nu"},
      {"duplicate fixed side", &bodies, "/fixed", json::array({"x-", "x-"}), "fixed"},
      {"unknown fixed side", &bodies, "/fixed", json::array({"z-"}), "fixed"},
      {"y side in 1D", &bar, "/fixed", json::array({"y-"}), "fixed"},
      {"gravity of the wrong length", &bodies, "/gravity", json::array({-9.81}), "gravity"},
      {"unwritable output directory", &plate, "/output/file", "/proc/nonexistent/x.h5", "output.file"},
      {"output file as a number", &plate, "/output/file", 5, "output.file"},
      {"negative output interval", &plate, "/output/every", -1, "output.every"},
      {"fractional checkpoint interval", &plate, "/output/checkpoint_every", 1.5, "output.checkpoint_every"},
      {"too many particles per cell", &plate, "/particles/per_cell", json::array({65, 2}), "particles.per_cell"},
      {"gauss layout beyond 10 per axis", &plate, "/particles", json{{"layout", "gauss"}, {"per_cell", {11, 11}}},
       "particles.per_cell"},
      {"bad layout", &plate, "/particles/layout", "grid", "particles.layout"},
      {"negative seed", &plate, "/particles/seed", -1, "particles.seed"},
      {"bad update", &plate, "/algorithm/update", "flip", "algorithm.update"},
      {"bad mass", &plate, "/algorithm/mass", "diagonal", "algorithm.mass"},
      {"cubic-spline in 2D", &plate, "/algorithm/mapping", "cubic-spline", "algorithm.mapping"},
      {"zero Gauss points", &plate, "/algorithm/gauss_per_cell", json::array({0, 2}), "algorithm.gauss_per_cell"},
      {"MLS support 0.5", &plate, "/algorithm/mls_support", 0.5, "algorithm.mls_support"},
      {"TLS degree 3", &plate, "/algorithm/tls_degree", 3, "algorithm.tls_degree"},
  };
  REQUIRE(cases.size() >= 30);
  for (const auto& c : cases) {
    json scene = *c.base;
    const json::json_pointer at(c.pointer);
    if (c.value.is_discarded()) scene[at.parent_pointer()].erase(at.back());
    else scene[at] = c.value;
    INFO(c.what << ": " << scene.dump());
    const std::string msg = error_of(scene);
    REQUIRE_FALSE(msg.empty());
    CHECK_THAT(msg, StartsWith("scene: "));
    CHECK_THAT(msg, Contains(c.key));
    CHECK(msg.find('\n') == std::string::npos);
  }
}

TEST_CASE("error messages have the form key = value: expectation", "[scene]") {
  json s = plate;
  s["material"]["E"] = -5;
  CHECK(error_of(s) == "scene: material.E = -5: expected a positive number (Pa)");

  s = plate;
  s["material"]["E"] = "nan";
  CHECK(error_of(s) == "scene: material.E = \"nan\": expected a positive number (Pa)");

  s = plate;
  s["material"]["nu"] = 0.5;
  CHECK_THAT(error_of(s), Contains("expected 0 ≤ ν < 0.5"));

  s = plate;
  s["grid"].erase("cells");
  CHECK_THAT(error_of(s), StartsWith("scene: grid.cells is missing: expected an array of 2 integers ≥ 1"));

  s = plate;
  s["grid"]["cels"] = s["grid"]["cells"];
  CHECK_THAT(error_of(s), Contains("did you mean \"grid.cells\""));

  s = plate;
  s["dt"] = 1e-5;  // a key of a section, misplaced at the top level
  CHECK_THAT(error_of(s), Contains("did you mean \"time.dt\""));

  s = plate;
  s["grid"]["basis"] = "bspline3";
  s["grid"]["basis_path"] = "fast";
  CHECK_THAT(error_of(s), Contains("\"generic\""));

  s = plate;
  s["grid"]["cells"] = {100000, 100000};
  CHECK_THAT(error_of(s), Contains("particles") && Contains("GiB"));

  s = plate;
  s["problem"]["name"] = "nope";
  CHECK_THAT(error_of(s), Contains("vibrating-bar") && Contains("column-compaction"));

  CHECK_THAT(error_of(json::array({1})), StartsWith("scene: <top level> = [1]: expected an object"));
}

TEST_CASE("a plate scene gets the problem's defaults", "[scene]") {
  const mpm::Scene s = mpm::parse_scene(plate);
  CHECK(s.dimension == 2);
  CHECK(s.problem.name == mpm::ProblemName::vibrating_plate);
  CHECK(s.problem.amplitude == 0.1);
  CHECK(s.grid.length[0] == 1.0);
  CHECK(s.grid.cells[1] == 8);
  CHECK(s.grid.basis == mpm::Basis::bspline2);
  CHECK(s.grid.path == mpm::BasisPath::fast);
  CHECK(s.particles.per_cell[0] == 2);
  CHECK(s.particles.per_cell[1] == 2);
  CHECK(s.particles.layout == mpm::Layout::uniform);
  CHECK(s.particles.seed == 1);
  CHECK(s.material.model == mpm::MaterialModel::neo_hookean);
  CHECK(s.material.E == 1e7);
  CHECK(s.material.nu == 0.3);
  CHECK(s.material.density == 1000.0);
  CHECK(s.algorithm.update == mpm::Update::musl);
  CHECK(s.algorithm.mass == mpm::MassMatrix::lumped);
  CHECK(s.algorithm.mapping == mpm::Mapping::direct);
  CHECK(s.algorithm.gauss_per_cell[0] == 2);
  CHECK(s.algorithm.mls_support == 2.0);
  CHECK(s.algorithm.tls_degree == 1);
  REQUIRE(s.time.dt);
  CHECK(*s.time.dt == 1e-5);
  CHECK_FALSE(s.time.cfl);
  CHECK(s.time.end == 0.2);
  CHECK(s.time.energy_tolerance == 0.15);
  CHECK(s.output.file.empty());
  CHECK(s.output.every == 0);
  CHECK(s.fixed_sides == std::vector<int>{0, 1, 2, 3});
  CHECK(s.bodies.empty());

  // The recorded source is complete and parses to itself.
  const json& src = s.source;
  CHECK(src["material"]["model"] == "neo-hookean");
  CHECK(src["material"]["E"] == 1e7);
  CHECK(src["time"]["dt"] == 1e-5);
  CHECK(src["grid"]["basis"] == "bspline2");
  CHECK(src["algorithm"]["mapping"] == "direct");
  CHECK(src["problem"] == json({{"name", "vibrating-plate"}, {"amplitude", 0.1}}));
  CHECK(src["fixed"] == json({"x-", "x+", "y-", "y+"}));
  CHECK(mpm::parse_scene(src).source == src);
}

TEST_CASE("problem defaults and partial overrides", "[scene]") {
  const mpm::Scene b = mpm::parse_scene(bar);
  CHECK(b.material.model == mpm::MaterialModel::linear_elastic);
  CHECK(b.material.E == 7e6);
  CHECK(b.material.density == 2000.0);
  CHECK(*b.time.dt == 1e-7);
  CHECK(b.time.end == 1.9e-6);
  CHECK(b.fixed_sides == std::vector<int>{0, 1});
  CHECK(b.problem.v0 == 0.28);

  SECTION("partial material keeps the problem's other fields") {
    json s = plate;
    s["material"] = {{"E", 2e7}};
    const mpm::Scene p = mpm::parse_scene(s);
    CHECK(p.material.E == 2e7);
    CHECK(p.material.nu == 0.3);
    CHECK(p.material.model == mpm::MaterialModel::neo_hookean);
    CHECK(p.source["material"]["nu"] == 0.3);
  }
  SECTION("a scene's own fixed sides replace the problem's") {
    json s = bar;
    s["fixed"] = {"x-"};
    CHECK(mpm::parse_scene(s).fixed_sides == std::vector<int>{0});
  }
  SECTION("cfl replaces the problem's dt") {
    json s = plate;
    s["time"] = {{"cfl", 0.5}};
    const mpm::Scene p = mpm::parse_scene(s);
    CHECK_FALSE(p.time.dt);
    CHECK(*p.time.cfl == 0.5);
    CHECK(p.time.end == 0.2);
    CHECK_FALSE(p.source["time"].contains("dt"));
  }
  SECTION("column compaction and traction bar") {
    json s = bar;
    s["grid"]["length"] = {60.0};
    s["problem"] = {{"name", "column-compaction"}, {"max_body_force", -100}};
    const mpm::Scene c = mpm::parse_scene(s);
    CHECK(c.problem.height == 50.0);
    CHECK(c.problem.max_body_force == -100.0);
    CHECK(c.material.density == 1.0);
    CHECK(c.fixed_sides == std::vector<int>{0});
    s["problem"] = {{"name", "vibrating-bar-traction"}};
    const mpm::Scene t = mpm::parse_scene(s);
    CHECK(t.material.model == mpm::MaterialModel::neo_hookean);
    CHECK(t.material.E == 100.0);
    CHECK(*t.time.dt == 1e-4);
  }
}

TEST_CASE("a scene with its own bodies", "[scene]") {
  json s = bodies;
  s["bodies"].push_back(R"({"box": [[0.0, 0.0], [1.0, 0.2]], "material": {"E": 5e5}})"_json);
  s["particles"] = {{"layout", "random"}, {"per_cell", 5}, {"seed", 42}};
  s["grid"]["basis"] = "bspline3";
  const mpm::Scene p = mpm::parse_scene(s);
  CHECK(p.problem.name == mpm::ProblemName::none);
  CHECK(p.material.model == mpm::MaterialModel::linear_elastic);
  CHECK(p.material.E == 1e6);
  CHECK(p.material.density == 1000.0);
  REQUIRE(p.bodies.size() == 2);
  CHECK(p.bodies[0].lo[0] == 0.4);
  CHECK(p.bodies[0].hi[1] == 0.6);
  CHECK(p.bodies[0].velocity[1] == -1.0);
  CHECK_FALSE(p.bodies[0].material);
  REQUIRE(p.bodies[1].material);
  CHECK(p.bodies[1].material->E == 5e5);
  CHECK(p.bodies[1].material->density == 1000.0);  // the rest from the scene's material
  CHECK(p.gravity[1] == -9.81);
  CHECK(p.fixed_sides == std::vector<int>{0, 1, 2});
  CHECK(p.particles.layout == mpm::Layout::random);
  CHECK(p.particles.per_cell == std::array<int, 3>{5, 1, 1});
  CHECK(p.particles.seed == 42);
  CHECK(p.grid.path == mpm::BasisPath::generic);  // bspline3 has no fast path, so it is not the default there
  CHECK(p.source["particles"]["per_cell"] == 5);
  CHECK(mpm::parse_scene(p.source).source == p.source);
}

TEST_CASE("a writable output directory is accepted", "[scene]") {
  json s = plate;
  s["output"] = {{"file", "/tmp/mpm_test_scene_out.h5"}, {"every", 100}};
  const mpm::Scene p = mpm::parse_scene(s);
  CHECK(p.output.file == "/tmp/mpm_test_scene_out.h5");
  CHECK(p.output.every == 100);
  s["output"]["file"] = "relative.h5";  // the current directory
  if (access(".", W_OK) == 0) CHECK(error_of(s).empty());
}

TEST_CASE("apply_override", "[scene]") {
  json s = plate;
  mpm::apply_override(s, "grid.cells=[64,64]");
  CHECK(s["grid"]["cells"] == json({64, 64}));
  mpm::apply_override(s, "algorithm.mapping=mls");  // bare string
  CHECK(s["algorithm"]["mapping"] == "mls");
  mpm::apply_override(s, "algorithm.mapping=\"tls\"");  // JSON string
  CHECK(s["algorithm"]["mapping"] == "tls");
  mpm::apply_override(s, "material.E=2e7");
  CHECK(s["material"]["E"] == 2e7);
  mpm::apply_override(s, "problem.amplitude=0.05");
  CHECK(s["problem"]["name"] == "vibrating-plate");
  CHECK(s["problem"]["amplitude"] == 0.05);
  mpm::apply_override(s, "grid.cells.0=32");
  CHECK(s["grid"]["cells"] == json({32, 64}));
  mpm::apply_override(s, "output.file=run/plate.h5");
  CHECK(s["output"]["file"] == "run/plate.h5");
  mpm::apply_override(s, "particles={\"per_cell\": [3, 3]}");
  CHECK(s["particles"]["per_cell"] == json({3, 3}));
  mpm::apply_override(s, "time.dt=1e-6");
  mpm::apply_override(s, "time.dt=null");  // null removes the key
  CHECK_FALSE(s["time"].contains("dt"));

  json empty;
  mpm::apply_override(empty, "a.b.c=1");
  CHECK(empty == json({{"a", {{"b", {{"c", 1}}}}}}));

  auto message = [](json j, const std::string& a) {
    try {
      mpm::apply_override(j, a);
    } catch (const mpm::SceneError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(message(plate, "grid.cells") == "--set grid.cells: expected KEY=VALUE");
  CHECK(message(plate, "=5") == "--set =5: expected KEY=VALUE");
  CHECK_THAT(message(plate, "grid..cells=1"), StartsWith("--set grid..cells=1"));
  CHECK_THAT(message(plate, "grid.cells.2=1"), Contains("grid.cells"));
  CHECK_THAT(message(plate, "dimension.x=1"), Contains("dimension"));
}

TEST_CASE("JSON syntax errors give line and column", "[scene]") {
  const std::string text = "{\n  \"dimension\": 2,\n  \"grid\": ,\n}\n";
  try {
    (void)mpm::read_json_text(text, "plate.json");
    FAIL("no error");
  } catch (const mpm::SceneError& e) {
    CHECK_THAT(e.what(), StartsWith("scene: plate.json:3:11: "));
    CHECK_THAT(e.what(), Contains("unexpected ','"));
  }
  CHECK_THROWS_WITH(mpm::read_json_text("", "empty.json"), StartsWith("scene: empty.json:1:1: "));
  CHECK_THROWS_WITH(mpm::read_json_text("{\"a\": 1e400}", "big.json"), StartsWith("scene: big.json"));
  CHECK_THROWS_WITH(mpm::read_json_text("{\"grid\": {\"cells\": [1], \"cells\": [2]}}", "dup.json"),
                    Contains("grid.cells") && Contains("twice"));
  CHECK_THROWS_WITH(mpm::read_json_text("{\"bodies\": [{}, {\"box\": 1, \"box\": 2}]}", "dup.json"),
                    Contains("bodies.1.box"));
  CHECK(mpm::read_json_text("{\"a\": [1, {\"b\": 2}], \"b\": 3}", "ok.json") ==
        json({{"a", {1, {{"b", 2}}}}, {"b", 3}}));
}

TEST_CASE("load_scene_file", "[scene]") {
  CHECK_THROWS_WITH(mpm::load_scene_file("/nonexistent/scene.json"),
                    StartsWith("scene: cannot read /nonexistent/scene.json: "));
  const std::string path = "/tmp/mpm_test_scene_" + std::to_string(getpid()) + ".json";
  {
    std::ofstream(path) << plate.dump(2);
  }
  CHECK(mpm::load_scene_file(path).problem.name == mpm::ProblemName::vibrating_plate);
  {
    std::ofstream(path) << "{\n  \"dimension\": 2,\n  \"grid\": {]\n}\n";
  }
  CHECK_THROWS_WITH(mpm::load_scene_file(path), StartsWith("scene: " + path + ":3:"));
  std::remove(path.c_str());
}

TEST_CASE("apply_override refuses a bare value that is not valid UTF-8", "[scene]") {
  nlohmann::json j = nlohmann::json::object();
  REQUIRE_THROWS_WITH(mpm::apply_override(j, "output.file=\xff.h5"), Catch::Contains("output.file") && Catch::Contains("UTF-8"));
}
