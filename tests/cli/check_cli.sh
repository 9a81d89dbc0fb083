#!/usr/bin/env bash
# The `mpm` command-line contract (DESIGN.md): exit statuses, one-line errors naming the key, the summary JSON.
set -uo pipefail
mpm=$1 scenes=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
fail=0 pass=0
expect() {  # expect STATUS PATTERN -- command...
  local want=$1 pattern=$2; shift 3
  local out status
  out=$("$@" 2>&1); status=$?
  if [ "$status" -ne "$want" ] || ! grep -qE -- "$pattern" <<<"$out"; then
    echo "FAIL: $* -> status $status (want $want), output: $out"; fail=$((fail+1))
  else pass=$((pass+1)); fi
}
expect 0 "valid 2D scene" -- "$mpm" validate "$scenes/plate.json"
for scene in "$scenes"/*.json "$scenes"/stability/*.json; do  # every scene the repository ships is valid
  expect 0 "valid" -- "$mpm" validate "$scene"
done
expect 2 "material.E" -- "$mpm" validate "$scenes/plate.json" --set material.E=-1
expect 2 "grid.cells" -- "$mpm" run "$scenes/plate.json" --set grid.cells=[0,8] --quiet
expect 2 "material.nu" -- "$mpm" run "$scenes/plate.json" --set material.nu=0.5 --quiet
expect 2 "time.dt" -- "$mpm" run "$scenes/plate.json" --set time.dt=0.01 --quiet
expect 2 "--out" -- "$mpm" run "$scenes/plate.json" --out /nonexistent/dir/x.h5 --quiet
expect 2 "plate.json|cannot read" -- "$mpm" run "$work/missing.json" --quiet
printf '{\n  "dimension": 2,\n  "grid": {,}\n}\n' > bad.json
expect 2 "bad.json:3:" -- "$mpm" validate bad.json
expect 2 "not expected" -- "$mpm" run --no-such-option
# a short successful run with a summary and an output file; nothing written for invalid scenes above
expect 0 "errors \(RMS\)" -- "$mpm" run "$scenes/plate.json" --set grid.cells=[8,8] --set time.end=0.001 \
  --out run.h5 --summary s.json --threads 2
python3 - <<'PY' || { echo "FAIL: summary contract"; fail=$((fail+1)); }
import json, os
s = json.load(open("s.json"))
for k in ["status", "steps", "particles", "threads", "wall_s", "particle_steps_per_s", "errors", "conservation",
          "fallbacks", "pipeline", "columns", "bytes_per_particle", "isa"]:
    assert k in s, k
assert s["status"] == "ok" and s["steps"] == 100 and s["threads"] == 2
assert s["isa"] in ("avx512", "avx2", "sse2", "native", "baseline"), s["isa"]
# the DESIGN.md contract keys, plus the relative L2 errors of thesis Figs 5.12-5.14
assert set(s["errors"]) == {"displacement_rms", "velocity_rms", "stress_rms", "displacement_rel_l2", "stress_rel_l2"}
assert s["conservation"]["mass_rel_max"] <= 1e-13
assert os.path.exists("run.h5") and os.path.exists("run.xdmf") and not os.path.exists("run.h5.partial")
PY
# the kernels' instruction set: MPM_ISA=baseline is honoured and reported, an unknown value refused
MPM_ISA=baseline expect 0 "threads \((sse2|native|baseline)\)" -- "$mpm" run "$scenes/plate.json" --set grid.cells=[8,8] \
  --set time.end=0.0001
MPM_ISA=sse9 expect 2 "MPM_ISA = 'sse9': expected auto, baseline, avx2 or avx512" -- "$mpm" validate "$scenes/plate.json"
# the 1D cubic-spline mapping (thesis §3.2) runs and names its stages; refused in 2D naming the key
expect 0 "errors \(RMS\)" -- "$mpm" run "$scenes/bar.json" --set algorithm.mapping=cubic-spline --summary cs.json
grep -q '"cubic-spline-rebuild+p2g-mass"' cs.json && pass=$((pass+1)) || { echo "FAIL: cubic-spline stages"; fail=$((fail+1)); }
expect 2 "algorithm.mapping" -- "$mpm" validate "$scenes/plate.json" --set algorithm.mapping=cubic-spline
# a particle leaving the grid: exit 3, a precise reason, the output file still written
cat > escape.json <<'J'
{"dimension": 2, "grid": {"length": [1, 1], "cells": [10, 10]},
 "bodies": [{"box": [[0.4, 0.4], [0.6, 0.6]], "velocity": [50.0, 0.0]}],
 "material": {"E": 1e5, "nu": 0.3, "density": 1000}, "time": {"dt": 1e-3, "end": 1.0}}
J
expect 3 "left the grid.*last good state" -- "$mpm" run escape.json --out escape.h5 --summary e.json --quiet
# a block compressed against a wall: its wave speed c(J) rises above what time.cfl = 0.95 of the initial critical
# step allows; exit 3 naming the CFL condition with the ratio (the energy guard, which this near-critical impact also
# trips, is relaxed here to see the CFL check alone)
cat > cfl.json <<'J'
{"dimension": 2, "grid": {"length": [1, 1], "cells": [20, 20]}, "particles": {"per_cell": [2, 2]},
 "bodies": [{"box": [[0.4, 0.4], [0.6, 0.6]], "velocity": [6.0, 0.0]}], "fixed": ["x+"],
 "material": {"E": 1e5, "nu": 0.3, "density": 1000}, "time": {"cfl": 0.95, "end": 0.2, "energy_tolerance": 1e9}}
J
expect 3 "CFL violated at step .* by a factor .*wave speed c = " -- "$mpm" run cfl.json --quiet
# a blow-up that stays finite (BSMPM-TLS MUSL block impact): the energy guard stops it, exit 3 with the balance
expect 3 "energy balance violated at step .*external work.*last good state" -- "$mpm" run \
  "$scenes/stability/block-impact.json" --set algorithm.mapping=tls --set algorithm.update=musl --quiet
[ -f escape.h5 ] && pass=$((pass+1)) || { echo "FAIL: no output after an unstable run"; fail=$((fail+1)); }
# faults that end cleanly with exit 2 naming what is wrong, before any run
deep=$(printf '%*s' 100000 '' | tr ' ' '[')
printf '%s' "$deep" > deep.json
expect 2 "deep.json: .*nested deeper than" -- "$mpm" run deep.json --quiet
expect 2 "^--set material.E: nested deeper than" -- "$mpm" validate "$scenes/plate.json" --set "material.E=$deep"
sed 's/"E": 1.0e7/"E": 1e400/' "$scenes/plate.json" > huge.json
expect 2 "huge.json: material.E: .*1e400" -- "$mpm" validate huge.json
expect 2 "^--set material.E = 1e400: expected a finite number" -- "$mpm" validate "$scenes/plate.json" --set material.E=1e400
# a triangle mesh: a bad mesh is refused naming the file and the element; a mesh path is relative to the scene
meshes=$(cd "$scenes/../../tests/meshes" && pwd)
expect 2 "bad_quad.msh: line [0-9]+: element 17 is a 4-node quadrangle" -- "$mpm" validate \
  "$scenes/plate-triangles.json" --set grid.mesh="\"$meshes/bad_quad.msh\""
expect 2 "bad_inverted.msh: .*element" -- "$mpm" run "$scenes/plate-triangles.json" \
  --set grid.mesh="\"$meshes/bad_inverted.msh\"" --quiet
expect 2 "nope.msh: cannot open" -- "$mpm" validate "$scenes/plate-triangles.json" --set grid.mesh=nope.msh
expect 2 "grid.cells = \[8,8\]: expected either grid.cells or grid.mesh" -- "$mpm" validate \
  "$scenes/plate-triangles.json" --set 'grid.cells=[8,8]'
mkdir adir
expect 2 "cannot read adir: is a directory" -- "$mpm" run adir --quiet
expect 2 "cannot read adir: is a directory" -- "$mpm" validate adir
expect 2 "^--out = adir: expected a file name, not a directory" -- "$mpm" run "$scenes/plate.json" --out adir --quiet
expect 2 "^--summary = adir: expected a file name, not a directory" -- "$mpm" run "$scenes/plate.json" --summary adir
expect 2 "^--summary = nodir/s.json: expected a file in an existing, writable directory" -- \
  "$mpm" run "$scenes/plate.json" --summary nodir/s.json
# a write that fails (here a file size limit, as a full disk; SIGXFSZ ignored so that write() reports EFBIG): exit 1
# naming the file and what was lost, no crash, no .partial file left; a resumed run keeps the file it continued
limited() { local blocks=$1; shift; bash -c 'trap "" XFSZ; ulimit -f "$0"; exec "$@"' "$blocks" "$@"; }
expect 1 "full.h5.partial.*failed.*nothing was saved \('full.h5' was not written\)" -- limited 150 \
  "$mpm" run "$scenes/plate.json" --set grid.cells=[8,8] --set output.every=1 --out full.h5 --quiet
[ ! -e full.h5 ] && [ ! -e full.h5.partial ] && [ ! -e full.xdmf ] && pass=$((pass+1)) ||
  { echo "FAIL: files left after a failed write: $(ls full*)"; fail=$((fail+1)); }
"$mpm" run "$scenes/plate.json" --set grid.cells=[8,8] --set output.checkpoint_every=100 --out kept.h5 --quiet >/dev/null
cp kept.h5 kept.orig
expect 1 "kept.h5.partial.*failed.*'kept.h5' is kept as it was" -- limited $(( $(stat -c %s kept.h5) / 1024 + 4 )) \
  "$mpm" run --resume kept.h5 --quiet
cmp -s kept.h5 kept.orig && [ ! -e kept.h5.partial ] && pass=$((pass+1)) ||
  { echo "FAIL: the resumed file was not kept"; fail=$((fail+1)); }
echo "cli: $pass passed, $fail failed"
[ "$fail" -eq 0 ]
