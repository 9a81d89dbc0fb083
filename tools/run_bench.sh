#!/usr/bin/env bash
# Builds the benchmark programs (Release) if needed, runs them, and writes the summary table and plot:
#   docs/bench_table.md   machine, compiler, date; medians, particle-steps/s and the key ratios
#   docs/throughput.png   particle-steps/s against particle count, one line per (dim, scheme, threads)
#   README.md             the headline tables between its bench:begin / bench:end markers (only when --docs is
#                         the repository's docs/)
#
# Usage: tools/run_bench.sh [--build-dir DIR] [--results DIR] [--only NAME[,NAME...]] [--filter REGEX]
#                           [--no-build] [--no-plot] [--docs DIR] [--wait-idle SECONDS] [--nice N]
#   --build-dir  build tree (default: build-bench next to this script's parent; configured here if missing)
#   --results    where the JSON results go (default: <build-dir>/results)
#   --only       run a subset of bench_basis,bench_transfer,bench_step,bench_stream (default: all)
#   --filter     passed on as --benchmark_filter (e.g. 'step/2d')
#   --no-build   run the programs already in the build tree (e.g. while the engine sources do not compile)
#   --docs       where bench_table.md and throughput.png go (default: docs/ of the repository)
#   --wait-idle  before each program, wait (at most SECONDS) until other processes use < 10 % of the CPUs
#   --nice       run the programs under `nice -n N`, each started by setsid so that it gets a scheduler autogroup
#                of its own, which also gets nice N (with kernel.sched_autogroup_enabled=1, plain nice only ranks
#                processes inside one autogroup). On a shared machine a negative N (needs root) puts the benchmarks ahead of other work
#                (compiles, tests), which otherwise takes one of the two cores and distorts the 2-thread figures;
#                it also slows that other work down while the suite runs, so use it briefly and say so.
#
# The whole suite takes ~6-7 minutes on 2 cores. The machine should be otherwise idle: run_meta.txt records the
# load average and the CPU time other processes used during each program, and the table repeats it.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$root/build-bench"
results=""
docs="$root/docs"
only="bench_basis,bench_transfer,bench_step,bench_stream"
filter=""
plot=1
build_first=1
wait_max=0
nice_level=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build-dir) build=$(realpath -m "$2"); shift 2 ;;
    --results) results=$(realpath -m "$2"); shift 2 ;;
    --docs) docs=$(realpath -m "$2"); shift 2 ;;
    --only) only="$2"; shift 2 ;;
    --filter) filter="$2"; shift 2 ;;
    --no-plot) plot=0; shift ;;
    --no-build) build_first=0; shift ;;
    --wait-idle) wait_max="$2"; shift 2 ;;
    --nice) nice_level="$2"; shift 2 ;;
    -h|--help) sed -n '2,23p' "$0"; exit 0 ;;
    *) echo "run_bench.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
  esac
done
results=${results:-$build/results}
IFS=',' read -r -a programs <<< "$only"

# repetitions: 5 for the quick micro-benchmarks, 3 for the whole-step runs
# (bench_step runs its 1e7-particle cases once whatever this says, see bench/bench_step.cpp)
declare -A reps=([bench_basis]=5 [bench_transfer]=3 [bench_step]=3 [bench_stream]=3)

if [[ ! -f "$build/CMakeCache.txt" ]]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMPM_BUILD_TESTS=OFF -DMPM_BUILD_BENCH=ON
fi
build_type=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$build/CMakeCache.txt")
if [[ "$build_type" != "Release" ]]; then
  echo "run_bench.sh: $build is a '$build_type' build; benchmarks need Release (use --build-dir)" >&2
  exit 2
fi
if [[ $build_first -eq 1 ]]; then
  cmake --build "$build" -j"$(nproc)" --target "${programs[@]}"
fi
for prog in "${programs[@]}"; do
  [[ -x "$build/bench/$prog" ]] || { echo "run_bench.sh: $build/bench/$prog is missing (build it first)" >&2; exit 2; }
done

mkdir -p "$results"
meta="$results/run_meta.txt"
cxx=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")
# keep the run lines of programs not run this time (tools/run_bench.sh --only ...)
kept=""
if [[ -f "$meta" ]]; then
  kept=$(grep '^run ' "$meta" | grep -v -E "^run ($(IFS='|'; echo "${programs[*]}")) " || true)
fi
{
  echo "date=$(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "built=$(for p in "${programs[@]}"; do stat -c "$p %y" "$build/bench/$p" | cut -d. -f1; done | paste -sd, -)"
  # a virtual machine's model name can be as bare as "AMD EPYC": family and model tell the generation apart
  echo "cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -1) (family $(sed -n 's/^cpu family[[:space:]]*: //p' /proc/cpuinfo | head -1), model $(sed -n 's/^model[[:space:]]*: //p' /proc/cpuinfo | head -1))"
  echo "nproc=$(nproc)"
  echo "compiler=$("$cxx" --version | head -1)"
  echo "cxx_flags_release=$(sed -n 's/^CMAKE_CXX_FLAGS_RELEASE:[A-Z]*=//p' "$build/CMakeCache.txt")"
  echo "mpm_native=$(sed -n 's/^MPM_NATIVE:[A-Z]*=//p' "$build/CMakeCache.txt")"
  echo "kernel=$(uname -r)"
  echo "mem_total=$(sed -n 's/^MemTotal:[[:space:]]*//p' /proc/meminfo)"
  echo "nice=${nice_level:-0}"
  if [[ -n "$kept" ]]; then echo "$kept"; fi
} > "$meta"

busy_jiffies() { awk '/^cpu /{print $2+$3+$4+$7+$8+$9}' /proc/stat; }
hz=$(getconf CLK_TCK)
# share of all CPUs busy over the next 5 s (nothing of ours runs meanwhile)
busy_share() {
  local b0 b1
  b0=$(busy_jiffies); sleep 5; b1=$(busy_jiffies)
  awk -v b="$((b1 - b0))" -v hz="$hz" -v n="$(nproc)" 'BEGIN{printf "%.2f", b/hz/(5*n)}'
}
wait_idle() {
  local waited=0 share
  while :; do
    share=$(busy_share)
    awk -v s="$share" 'BEGIN{exit !(s < 0.10)}' && return 0
    waited=$((waited + 5))
    if [[ $waited -ge $wait_max ]]; then
      echo "   machine still busy (${share} of the CPUs) after ${waited}s; running anyway"
      return 0
    fi
  done
}

for prog in "${programs[@]}"; do
  exe="$build/bench/$prog"
  out="$results/$prog.json"
  args=(--benchmark_repetitions="${reps[$prog]:-3}" --benchmark_report_aggregates_only=true --benchmark_format=json)
  [[ -n "$filter" ]] && args+=(--benchmark_filter="$filter")
  echo "== $prog (${reps[$prog]:-3} repetitions) -> $out"
  [[ $wait_max -gt 0 ]] && wait_idle
  load_before=$(cut -d' ' -f1 /proc/loadavg)
  b0=$(busy_jiffies)
  prefix=()
  if [[ -n "$nice_level" ]]; then
    # setsid gives a new autogroup; set its nice (best effort), then the process's own
    prefix=(setsid --wait sh -c 'echo "$0" > /proc/self/autogroup 2>/dev/null; exec nice -n "$0" "$@"' "$nice_level")
  fi
  /usr/bin/time -f '%e %U %S' -o "$results/$prog.time" "${prefix[@]}" "$exe" "${args[@]}" > "$out"
  b1=$(busy_jiffies)
  read -r wall user sys < "$results/$prog.time"
  # CPU seconds that other processes used while this program ran (all CPUs), and their share of the machine
  other=$(awk -v b="$((b1 - b0))" -v hz="$hz" -v u="$user" -v s="$sys" 'BEGIN{o=b/hz-u-s; if(o<0)o=0; printf "%.1f", o}')
  share=$(awk -v o="$other" -v w="$wall" -v n="$(nproc)" 'BEGIN{printf "%.2f", o/(w*n)}')
  echo "run $prog wall=$wall user=$user sys=$sys load_before=$load_before other_cpu_s=$other other_share=$share" >> "$meta"
  echo "   ${wall}s wall; other processes used ${other} CPU-s (${share} of the machine)"
done

if [[ $plot -eq 1 ]]; then
  mkdir -p "$docs"
  # the README's headline tables only from a run that writes the repository's own docs
  readme=()
  [[ "$(realpath -m "$docs")" == "$root/docs" ]] && readme=(--readme "$root/README.md")
  /usr/bin/python3 "$root/tools/plot_bench.py" --results "$results" --build-dir "$build" \
    --table "$docs/bench_table.md" --png "$docs/throughput.png" "${readme[@]}"
fi
