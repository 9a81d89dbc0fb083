# The options shared by the side-by-side cost scripts (tls_cost.sh, plate_cost.sh), sourced after they set
# `root` and the default `steps`: --mpm BINARY, --reps N, --threads T, --steps S, -h (prints the script's header
# comment, lines 2 to `help_lines`). Sets mpm, reps, threads and steps.
mpm="$root/build/tools/mpm"
reps=3
threads=2
script=$(basename "$0")
while [[ $# -gt 0 ]]; do
  case "$1" in
    --mpm) mpm=$(realpath "$2"); shift 2 ;;
    --reps) reps="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --steps) steps="$2"; shift 2 ;;
    -h|--help) sed -n "2,${help_lines}p" "$0"; exit 0 ;;
    *) echo "$script: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
[[ -x "$mpm" ]] || { echo "$script: no mpm binary at $mpm (build first, or pass --mpm)" >&2; exit 2; }
