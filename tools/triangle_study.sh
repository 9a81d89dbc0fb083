#!/usr/bin/env bash
# The plate on triangle meshes (thesis §6.3.1 Table 6.1): MPM-P1, MPM-TLS and PS-MPM on the 1056-triangle mesh with
# 24 particles per triangle (dt = 1.25e-4, T = 0.015); PS-MPM with the lumped mass and with the consistent one for
# the velocities (projection) or everywhere. Prints a markdown table of the errors, conservation and throughput
# from each run's summary. (The convergence over tools/meshes/plate_h{1,2,3}.msh: `mpm study`, tools/reproduce.sh.)
# Usage: tools/triangle_study.sh [MPM]   (default build/tools/mpm)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
mpm=${1:-$root/build/tools/mpm}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
scene=$root/tools/scenes/plate-triangles.json

run() {  # run NAME ARGS...: one run, its summary in $work/NAME.json
  local name=$1
  shift
  "$mpm" run "$scene" "$@" --summary "$work/$name.json" --quiet >/dev/null 2>"$work/$name.err" || true
}
row() {  # row NAME LABEL: a table row from a summary
  /usr/bin/python3 - "$work/$1.json" "$2" "$work/$1.err" <<'EOF'
import json, os, sys
if not os.path.exists(sys.argv[1]):  # refused: the reason, e.g. a time.dt above the critical step
    print(f"| {sys.argv[2]} | — | refused: {open(sys.argv[3]).read().strip()[:110]} | | | | | | |")
    sys.exit()
s = json.load(open(sys.argv[1]))
e, c = s.get("errors"), s["conservation"]
err = " | ".join(f"{e[k]:.3g}" for k in ("displacement_rms", "velocity_rms", "stress_rms")) if e else "— | — | —"
print(f"| {sys.argv[2]} | {s['particles']} | {s['status']} | {err} | {c['mass_rel_max']:.1e} | {c['momentum_rel_max']:.1e} |"
      f" {s['particle_steps_per_s'] / 1e6:.2f} |")
EOF
}

header() {
  echo
  echo "$1"
  echo
  echo "| method | particles | status | u RMS (m) | v RMS (m/s) | σ RMS (Pa) | mass rel. | momentum rel. | M particle-steps/s |"
  echo "|---|---|---|---|---|---|---|---|---|"
}

methods=("MPM-P1:linear:direct:lumped" "MPM-TLS:linear:tls:lumped" "PS-MPM lumped:powell-sabin:direct:lumped"
  "PS-MPM projection:powell-sabin:direct:projection" "PS-MPM consistent:powell-sabin:direct:consistent")
header "Plate of thesis §6.3.1 on tools/meshes/plate_1058.msh (1056 triangles), 24 particles per triangle, MUSL"
for m in "${methods[@]}"; do
  IFS=: read -r label basis mapping mass <<<"$m"
  run "t61-$label" --set grid.basis="$basis" --set algorithm.mapping="$mapping" --set algorithm.mass="$mass"
  row "t61-$label" "$label"
done
