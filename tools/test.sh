#!/usr/bin/env bash
# README command 2: install dependencies, build (Release), run the whole test suite.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/tools/build.sh"
cd "$root/build"
ctest -j"$(nproc)" --output-on-failure
