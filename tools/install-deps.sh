#!/usr/bin/env bash
# Installs the Debian packages the engine, its tests, benchmarks and plots need.
# Idempotent: packages already present are skipped, so a second call costs one dpkg query.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libtbb-dev libhdf5-dev
  catch2 libbenchmark-dev nlohmann-json3-dev libcli11-dev
  python3 python3-matplotlib python3-h5py python3-numpy
  clang-14 libclang-rt-14-dev llvm-14  # tools/sanitize.sh: the sanitizer builds, libFuzzer (clang only), llvm-symbolizer
  paraview python3-paraview xvfb xauth  # tests/cli/check_paraview.sh: ParaView's own reader opens the output
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "install-deps: need root or sudo to install: ${missing[*]}" >&2; exit 1; }
  sudo_cmd=(sudo)
fi
echo "install-deps: installing ${missing[*]}" >&2
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -qq
"${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
