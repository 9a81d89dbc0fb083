#!/usr/bin/env bash
# Configures and builds the project (Release) into build/, after installing the Debian packages it needs.
# Extra arguments go to CMake's configure step (e.g. -DMPM_NATIVE=ON).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/tools/install-deps.sh"
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$root/build" -j"$(nproc)"
