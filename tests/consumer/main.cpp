// Drives the installed static library from C++: parse a scene, run it, check the summary.
#include <cstdio>

#include "engine/run.hpp"
#include "engine/scene.hpp"

int main() {
  const auto scene = mpm::parse_scene(nlohmann::json::parse(R"({
    "dimension": 1,
    "problem": {"name": "vibrating-bar"},
    "grid": {"length": [1.0], "cells": [10]},
    "particles": {"per_cell": [4]}
  })"));
  const mpm::RunResult r = mpm::run_scene(scene, {1, "", true});
  std::printf("%s\n", r.summary.dump().c_str());
  return r.status == mpm::exit_ok && r.summary.contains("errors") ? 0 : 1;
}
