#!/usr/bin/env bash
# Regenerates docs/RESULTS.md and docs/results/: every table and figure there comes from the `mpm study` runs
# below (each study's command is written beside its CSV and quoted in RESULTS.md). Sized for minutes on 2 cores:
# the plate runs to T = 0.0125 s (5/8 of a period, where every exact field is non-zero; PROBLEMS.md) instead of
# the paper's T = 0.2 s, on 8-64 cells (MLS on 64x64 alone takes ~6 min: most of the script's time).
#
# Usage: tools/reproduce.sh [--mpm build/tools/mpm] [--threads 2]
set -euo pipefail
cd "$(dirname "$0")/.."
MPM=build/tools/mpm
THREADS=2
while [[ $# -gt 0 ]]; do
  case "$1" in
    --mpm) MPM=$2; shift 2 ;;
    --threads) THREADS=$2; shift 2 ;;
    *) echo "usage: tools/reproduce.sh [--mpm PATH] [--threads N]" >&2; exit 2 ;;
  esac
done
OUT=docs/results
mkdir -p "$OUT"
start=$(date +%s)

# study NAME SCENE ARGS...: one `mpm study` into docs/results/NAME, its command line kept beside the table
study() {
  local name=$1; shift
  rm -rf "${OUT:?}/$name"
  mkdir -p "$OUT/$name"
  echo "mpm study $*" > "$OUT/$name/command.txt"
  echo "== $name: mpm study $*"
  "$MPM" study "$@" --threads "$THREADS" --out "$OUT/$name" > "$OUT/$name/table.txt"
  # the CSV holds the same table (tools/plot_study.py redraws its plots); only text and the combined PNGs are kept
  rm -f "$OUT/$name/study.h5" "$OUT/$name/convergence.png" "$OUT/$name/error_vs_time.png"
}

PLATE_CELLS='grid.cells=[8,8],[16,16],[32,32],[64,64]'
# paper Figs 2-4: plate, A = 0.1 (plate-paper.json), MPM, BSMPM, BSMPM-MLS, BSMPM-TLS
study plate-mpm tools/scenes/plate-paper.json --set time.end=0.0125 --set grid.basis=linear --vary "$PLATE_CELLS"
study plate-bsmpm tools/scenes/plate-paper.json --set time.end=0.0125 --vary "$PLATE_CELLS" \
  --vary algorithm.mapping=direct,tls
# MLS: its own study, so that the cross product does not run MPM with MLS
study plate-mls tools/scenes/plate-paper.json --set time.end=0.0125 --set algorithm.mapping=mls --vary "$PLATE_CELLS"
# thesis §4.6.1, Fig 4.7 and Table 4.1: the fixed-ends bar (E = 4 kPa, 12 particles per cell), 8-512 cells
study bar-otm tools/scenes/bar-otm.json --repeat 3 --vary 'grid.cells=[8],[16],[32],[64],[128],[256],[511]' \
  --vary grid.basis=linear,ddmpm,maxent,bspline2
# the same bar with the basis carried by the body: OTM-P1 and OTM-maxent (thesis Algorithm 3), the unified approach
# (Algorithm 4), both with the consistent mass
study bar-otm-moving tools/scenes/bar-otm.json --repeat 3 --set algorithm.mass=consistent --set grid.basis=linear \
  --vary algorithm.update=otm \
  --vary 'grid.cells=[8],[16],[32],[64],[128],[256],[511]' --vary grid.basis=linear,maxent
study bar-otm-unified tools/scenes/bar-otm.json --repeat 3 --set algorithm.mass=consistent \
  --vary algorithm.update=unified --vary 'grid.cells=[8],[16],[32],[64],[128],[256],[511]'
# OTM-maxent and the unified approach again with the staggered start (time.start): the velocity at half steps, as
# the leapfrog update carries it, which removes the time-step floor of their errors
study bar-otm-staggered tools/scenes/bar-otm.json --repeat 3 --set algorithm.mass=consistent \
  --set time.start=staggered --set grid.basis=maxent --vary algorithm.update=otm --vary 'grid.cells=[8],[16],[32],[64],[128],[256],[511]' \
  --vary grid.basis=maxent
study bar-unified-staggered tools/scenes/bar-otm.json --repeat 3 --set algorithm.mass=consistent \
  --set time.start=staggered --vary algorithm.update=unified --vary 'grid.cells=[8],[16],[32],[64],[128],[256],[511]'
# thesis §4.6.3, Fig 4.10: the plate with B = 0.005 m on 32x32 cells, every method of chapter 4 (USL, as the thesis)
study plate-4-6-3 tools/scenes/plate-unified.json --set algorithm.update=usl --vary 'grid.cells=[32,32]' \
  --vary grid.basis=linear,maxent,bspline2
study plate-4-6-3-otm tools/scenes/plate-unified.json --set algorithm.mass=consistent --set grid.basis=linear \
  --vary algorithm.update=otm \
  --vary 'grid.cells=[32,32]' --vary grid.basis=linear,maxent
study plate-4-6-3-unified tools/scenes/plate-unified.json --set algorithm.mass=consistent \
  --vary algorithm.update=unified --vary 'grid.cells=[32,32]'
# thesis Fig 5.9 and Table 5.3: bar without grid crossing (Table 5.2), 5-40 cells, 12 particles per cell
study bar-mpm tools/scenes/bar.json --repeat 5 --set grid.basis=linear --vary 'grid.cells=[5],[10],[20],[40]' \
  --vary algorithm.mapping=direct,cubic-spline,tls
study bar-ddmpm tools/scenes/bar.json --repeat 5 --set grid.basis=ddmpm --vary 'grid.cells=[5],[10],[20],[40]' \
  --vary algorithm.mapping=direct,cubic-spline,tls
study bar-bsmpm tools/scenes/bar.json --repeat 5 --vary 'grid.cells=[5],[10],[20],[40]' \
  --vary algorithm.mapping=direct,cubic-spline,tls
# thesis Figs 5.12-5.13 and Table 5.5: large-deformation bar (Table 5.4), 20 cells, 8 particles per cell
study bar-large tools/scenes/bar-large.json --vary 'grid.cells=[20],[40],[80]' --vary grid.basis=linear,ddmpm,maxent,bspline2 \
  --vary algorithm.mapping=direct,cubic-spline,tls
# thesis Fig 5.14 and Table 5.7: column compaction (Table 5.6), 50 cells, 20 particles per cell
study column tools/scenes/column-compaction.json --vary 'grid.cells=[25],[50],[100]' \
  --vary grid.basis=linear,ddmpm,maxent,bspline2 --vary algorithm.mapping=direct,cubic-spline,tls
# thesis Table 5.8: DDMPM with sub-points on the column, beside DDMPM-TLS (50 cells, 20 particles per cell)
study column-subpoints tools/scenes/column-compaction.json --repeat 3 --set grid.basis=ddmpm \
  --set algorithm.mapping=direct --vary 'grid.cells=[50]' --vary algorithm.ddmpm_subpoints=1,2,4,8,16,32,64,128
study column-ddmpm-tls tools/scenes/column-compaction.json --repeat 3 --set grid.basis=ddmpm --vary 'grid.cells=[50]'
# thesis §4.6.2: bar with a traction at its free end (neo-Hookean as in the thesis, and linear elastic)
study bar-traction tools/scenes/bar-traction.json --vary 'grid.cells=[20],[40],[80],[160]' \
  --vary material.model=neo-hookean,linear-elastic --vary algorithm.mapping=direct,cubic-spline,tls
# thesis §4.6.2, Fig 4.9: convergence of every chapter-4 method with 12 particles per cell to T = 0.1 s, USL
TRACTION_49="--set particles.per_cell=[12] --set time.end=0.1 --vary grid.cells=[20],[40],[80],[160]"
study traction-4-9 tools/scenes/bar-traction.json --set algorithm.update=usl $TRACTION_49 \
  --vary grid.basis=linear,maxent,bspline2
study traction-4-9-otm tools/scenes/bar-traction.json --set algorithm.mass=consistent --set grid.basis=linear \
  --vary algorithm.update=otm $TRACTION_49 --vary grid.basis=linear,maxent
study traction-4-9-unified tools/scenes/bar-traction.json --set algorithm.mass=consistent \
  --vary algorithm.update=unified $TRACTION_49
# thesis §4.6.2: the unified approach on the bar of section 5 (the material domain carries the basis)
study bar-traction-unified tools/scenes/bar-traction.json --set algorithm.mass=consistent --vary algorithm.update=unified \
  --vary 'grid.cells=[20],[40],[80],[160]' --vary material.model=neo-hookean,linear-elastic

# thesis §6.3.1 Table 6.1 and §3.4.4: the plate on triangle meshes, MPM-P1, MPM-TLS and PS-MPM
bash tools/triangle_study.sh "$MPM" > "$OUT/triangles.md"
TRI_MESHES='grid.mesh="tools/meshes/plate_h1.msh","tools/meshes/plate_h2.msh","tools/meshes/plate_h3.msh"'
study triangles-p1 tools/scenes/plate-triangles.json --set algorithm.update=usl --set time.dt=2.5e-5 \
  --set time.end=0.02 --vary "$TRI_MESHES" --vary algorithm.mapping=direct,tls
study triangles-ps tools/scenes/plate-triangles.json --set algorithm.update=usl --set time.dt=2.5e-5 \
  --set time.end=0.02 --set grid.basis=powell-sabin --set algorithm.mapping=direct --vary "$TRI_MESHES" \
  --vary algorithm.mass=lumped,projection,consistent
/usr/bin/python3 tools/plot_triangles.py --mpm "$MPM" --out "$OUT"

# thesis Figs 4.6 and 4.8: stress profiles of the chapter-4 methods on the two bars
/usr/bin/python3 tools/plot_profiles.py --mpm "$MPM" --out "$OUT"
/usr/bin/python3 tools/results_md.py --results "$OUT" --out docs/RESULTS.md --seconds $(( $(date +%s) - start ))
echo "wrote docs/RESULTS.md and $OUT/ in $(( $(date +%s) - start )) s"
