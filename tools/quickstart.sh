#!/usr/bin/env bash
# README command 1: install dependencies, build (Release), run the default scene (the vibrating plate).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/tools/build.sh"
cd "$root"
./build/tools/mpm run tools/scenes/plate.json --out build/plate.h5 --summary build/plate-summary.json
