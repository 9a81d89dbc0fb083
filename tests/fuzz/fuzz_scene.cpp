// libFuzzer target for the scene parser (DESIGN.md "Scene file" and "Command line" contracts).
//
// Two modes, chosen at compile time (tests/fuzz/CMakeLists.txt builds both):
//   FUZZ_MODE_SCENE (fuzz_scene):     the input is scene-file text → read_json_text → parse_scene.
//   FUZZ_MODE_SET   (fuzz_scene_set): the input is a list of `--set KEY=VALUE` assignments, one per line, applied
//                                     with apply_override to a valid base scene, then parse_scene. A first line
//                                     "@plate", "@bar" or "@block" picks the base scene (default: plate).
//
// mpm::SceneError is the expected way to reject an input. A finding is anything else: another exception
// (escapes this function, libFuzzer reports it as a crash: "deadly signal" after std::terminate), a crash, a leak,
// an ASan/UBSan report (UBSan is built with -fno-sanitize-recover, so it aborts too), or a broken invariant of an
// accepted scene, which aborts with a message on stderr:
//   - Scene::source (what the run file records and what `mpm run` dumps into it) serialises without throwing;
//   - Scene::source is itself a valid scene, and parsing it again (through its text, as a resume would) gives the
//     same source: "Scene::source records every default exactly as it will run" (engine/scene.cpp).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "engine/scene.hpp"

#if !defined(FUZZ_MODE_SCENE) && !defined(FUZZ_MODE_SET)
#define FUZZ_MODE_SCENE 1
#endif

namespace {

using json = nlohmann::json;

[[noreturn]] void finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "\n==FINDING== %s\n%s\n", what, detail.c_str());
  std::fflush(stderr);
  std::abort();
}

/// The invariants of an accepted scene (see the top of this file).
void check_accepted(const mpm::Scene& s) {
  std::string text;
  try {
    text = s.source.dump();
  } catch (const std::exception& e) {
    finding("Scene::source of an accepted scene cannot be serialised", e.what());
  }
  try {
    const mpm::Scene again = mpm::parse_scene(mpm::read_json_text(text, "<source>"));
    if (again.source != s.source)
      finding("parsing Scene::source again gives a different source", text + "\n-- became --\n" + again.source.dump());
  } catch (const mpm::SceneError& e) {
    finding("Scene::source of an accepted scene is refused when parsed again", text + "\n" + e.what());
  }
}

#ifdef FUZZ_MODE_SET
// Base scenes: tools/scenes/plate.json, bar.json and block-falling.json as shipped (output.file left out, so an
// accepted scene never depends on the working directory).
constexpr const char* kPlate = R"({
  "dimension": 2,
  "problem":   { "name": "vibrating-plate", "amplitude": 0.05 },
  "grid":      { "length": [1.0, 1.0], "cells": [32, 32], "basis": "bspline2", "basis_path": "fast" },
  "particles": { "per_cell": [3, 3], "layout": "uniform" },
  "material":  { "model": "neo-hookean", "E": 1.0e7, "nu": 0.3, "density": 1000.0 },
  "algorithm": { "update": "musl", "mass": "lumped", "mapping": "direct" },
  "time":      { "dt": 1.0e-5, "end": 0.0125 },
  "output":    { "every": 250 }
})";
constexpr const char* kBar = R"({
  "dimension": 1,
  "problem":   { "name": "vibrating-bar", "v0": 0.28 },
  "grid":      { "length": [1.0], "cells": [40], "basis": "bspline2" },
  "particles": { "per_cell": [12] },
  "material":  { "model": "linear-elastic", "E": 7.0e6, "nu": 0.0, "density": 2000.0 },
  "algorithm": { "update": "musl", "mass": "projection", "mapping": "direct" },
  "time":      { "dt": 1.0e-7, "end": 1.9e-6 }
})";
constexpr const char* kBlock = R"({
  "dimension": 2,
  "grid":      { "length": [1.0, 1.0], "cells": [40, 40], "basis": "bspline2" },
  "particles": { "per_cell": [2, 2] },
  "material":  { "model": "neo-hookean", "E": 1.0e6, "nu": 0.3, "density": 1000.0 },
  "bodies":    [ { "box": [[0.4, 0.5], [0.6, 0.7]], "velocity": [0.0, -1.0] } ],
  "gravity":   [0.0, -9.81],
  "fixed":     ["x-", "x+", "y-", "y+"],
  "algorithm": { "update": "musl", "mass": "lumped" },
  "time":      { "cfl": 0.5, "end": 0.2 }
})";

const json& base(std::string_view name) {
  static const json plate = json::parse(kPlate), bar = json::parse(kBar), block = json::parse(kBlock);
  return name == "@bar" ? bar : name == "@block" ? block : plate;
}
#endif

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
#ifdef FUZZ_MODE_SET
  std::string_view rest(input);
  std::string_view first = rest.substr(0, rest.find('\n'));
  json scene = base(first);
  if (!first.empty() && first[0] == '@') rest.remove_prefix(std::min(rest.size(), first.size() + 1));
  try {
    // at most 8 assignments, as a long command line would give them
    for (int n = 0; n < 8 && !rest.empty(); ++n) {
      const std::size_t nl = rest.find('\n');
      const std::string assignment(rest.substr(0, nl));
      rest.remove_prefix(nl == std::string_view::npos ? rest.size() : nl + 1);
      mpm::apply_override(scene, assignment);
    }
    check_accepted(mpm::parse_scene(scene));
  } catch (const mpm::SceneError&) {
    // expected: the assignment or the resulting scene was refused with a message
  }
#else
  try {
    check_accepted(mpm::parse_scene(mpm::read_json_text(input, "fuzz.json")));
  } catch (const mpm::SceneError&) {
    // expected: refused with a message naming the key
  }
#endif
  return 0;
}
