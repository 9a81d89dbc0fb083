#!/usr/bin/env bash
# Sanitizer and fuzzing runs (CI runs all three after the test suite, see .ci/run).
#
#   tools/sanitize.sh asan          build-asan/: -fsanitize=address,undefined (clang++, -O1 -g1), the CTest suite
#                                   without the long numerical studies (Catch2 tag [long]), the install-and-consume
#                                   and the kill-and-resume tests; any ASan/UBSan/LSan report fails the test
#   tools/sanitize.sh tsan          build-tsan/: -fsanitize=thread (clang++, oneTBB built alike), the multithreaded
#                                   tests only (Catch2 tag [parallel])
#   tools/sanitize.sh fuzz [SECS]   build-fuzz/: clang++ libFuzzer + ASan + UBSan on the scene parser
#                                   (tests/fuzz/), both targets side by side for SECS seconds each (default 60)
#   tools/sanitize.sh all [SECS]    asan, tsan, then fuzz SECS (default 60); runs every mode, fails if any failed
#
# Exit status: 0 clean; 1 a finding or a build failure (the report says which mode and where the reproducer is).
# Every mode prints its wall time; `all` ends with a table of them.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
jobs=$(nproc)

usage() { sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//' >&2; exit 1; }

log() { echo "sanitize: $*" >&2; }

# symbolised stack traces in ASan/UBSan/TSan reports of clang-built code (g++'s runtime symbolises by itself)
for sym in llvm-symbolizer llvm-symbolizer-14; do
  if command -v "$sym" >/dev/null; then export ASAN_SYMBOLIZER_PATH; ASAN_SYMBOLIZER_PATH=$(command -v "$sym"); break; fi
done

configure_and_build() {  # DIR TARGETS... -- CMAKE_ARGS...
  local dir=$1; shift
  local targets=()
  while [ $# -gt 0 ] && [ "$1" != "--" ]; do targets+=("$1"); shift; done
  shift
  mkdir -p "$root/$dir"
  cmake -S "$root" -B "$root/$dir" -DMPM_BUILD_BENCH=OFF "$@" >"$root/$dir/configure.log" 2>&1 ||
    { cat "$root/$dir/configure.log" >&2; log "$dir: configure failed"; return 1; }
  local t args=()
  for t in "${targets[@]}"; do args+=(--target "$t"); done
  cmake --build "$root/$dir" -j"$jobs" "${args[@]}" || { log "$dir: build failed"; return 1; }
}

# clang-14 is what tools/install-deps.sh installs (its sanitizer and libFuzzer runtimes: libclang-rt-14-dev); an
# unversioned clang++ works too. Sets $clang and $clangxx.
pick_clang() {
  clang=clang-14 clangxx=clang++-14
  command -v "$clangxx" >/dev/null || { clang=clang; clangxx=clang++; }
}

# CMake drops the -D options when the compiler of an existing cache changes: start such a cache afresh.
reset_cache_unless() {  # DIR COMPILER [CACHE-LINE-REGEX]
  local cache="$root/$1/CMakeCache.txt"
  if [ -f "$cache" ] && ! { grep -q "^CMAKE_CXX_COMPILER:[A-Z]*=.*/$2\$" "$cache" && { [ -z "${3:-}" ] || grep -q "$3" "$cache"; }; }; then
    rm -rf "$cache" "$root/$1/CMakeFiles"
  fi
}

run_asan() {
  # clang++ -O1 -g1 (CMakeLists adds -g1 to every sanitizer build): optimised enough for the tests to run fast, line
  # tables for the reports. clang, not g++: measured, engine/simulation_2d.cpp compiles under ASan+UBSan in 228 s
  # and 2.9 GB with clang 14 against 8.5 min and 10 GB with g++ 12 (the whole g++ job took 18 min). [long] test
  # cases are the numerical studies: minutes under ASan and no code path the others do not take; the
  # kill-and-resume test runs a 3000-step plate five times (over its 300 s limit under ASan; its code paths are
  # the checkpoint ones, covered by the resume tests of mpm_tests).
  pick_clang
  reset_cache_unless build-asan "$clangxx"
  configure_and_build build-asan mpm_tests mpm -- \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1" -DMPM_SANITIZE=address,undefined \
    -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" "-DMPM_TEST_SPEC=~[long]" || return 1
  # halt_on_error: a UBSan report aborts the test (UBSan is built recoverable); LSan runs at every exit.
  # check_initialization_order / detect_stack_use_after_return: cheap extra ASan checks.
  (cd "$root/build-asan" &&
    UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    ASAN_OPTIONS=detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1 \
    ctest -j"$jobs" --output-on-failure -LE install -E kill_and_resume --timeout 1200)
}

# TSan needs every library that synchronises threads to be instrumented: Debian's libtbb is not, so TSan cannot see
# the happens-before edges of TBB's task spawn / join and reports hundreds of false races in mpm's parallel loops
# (and a real race would be indistinguishable from them). So the tsan mode builds oneTBB itself, from the Debian
# source package of the installed libtbb-dev (same version), with -fsanitize=thread, into build-tsan/tbb/ (once;
# ~1 min). apt-get runs with private lists and cache under that directory: the system's apt configuration is not
# touched.
build_tsan_tbb() {  # with $clang / $clangxx: TBB and the tests must use the same TSan runtime
  local dir="$root/build-tsan/tbb"
  local prefix="$dir/prefix-$clangxx"
  if [ -f "$prefix/lib/cmake/TBB/TBBConfig.cmake" ]; then echo "$prefix"; return 0; fi
  local pkg version
  pkg=$(dpkg-query -W -f='${source:Package}' libtbb-dev) && version=$(dpkg-query -W -f='${source:Version}' libtbb-dev) ||
    { log "tsan: libtbb-dev is not installed"; return 1; }
  rm -rf "$dir" && mkdir -p "$dir/apt/lists/partial" "$dir/apt/cache/archives/partial" "$dir/src"
  echo "deb-src [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] http://deb.debian.org/debian $(. /etc/os-release && echo "$VERSION_CODENAME") main" \
    >"$dir/apt/sources.list"
  local apt=(apt-get -qq -o Dir::Etc::SourceList="$dir/apt/sources.list" -o Dir::Etc::SourceParts=/dev/null
             -o Dir::State::Lists="$dir/apt/lists" -o Dir::Cache="$dir/apt/cache" -o APT::Sandbox::User=root)
  log "tsan: building $pkg $version with -fsanitize=thread (Debian source package)"
  "${apt[@]}" update >&2 && (cd "$dir/src" && "${apt[@]}" source --download-only "$pkg=$version" >&2) ||
    { log "tsan: cannot download the source of $pkg $version"; return 1; }
  tar -xf "$dir"/src/*.orig.tar.* -C "$dir/src" || return 1
  local src; src=$(find "$dir/src" -mindepth 2 -maxdepth 2 -name CMakeLists.txt -printf '%h\n' | head -1)
  cmake -S "$src" -B "$dir/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTBB_SANITIZE=thread -DTBB_TEST=OFF \
    -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" \
    -DTBB_STRICT=OFF -DTBBMALLOC_BUILD=OFF -DTBB_DISABLE_HWLOC_AUTOMATIC_SEARCH=ON -DCMAKE_INSTALL_PREFIX="$prefix" \
    >"$dir/configure.log" 2>&1 || { cat "$dir/configure.log" >&2; return 1; }
  cmake --build "$dir/build" -j"$jobs" >"$dir/build.log" 2>&1 || { tail -30 "$dir/build.log" >&2; return 1; }
  cmake --install "$dir/build" >"$dir/install.log" 2>&1 || { cat "$dir/install.log" >&2; return 1; }
  echo "$prefix"
}

run_tsan() {
  local tbb
  pick_clang  # clang, as for asan: the instrumented build takes a fraction of g++'s time and memory
  tbb=$(build_tsan_tbb) || { log "tsan: could not build an instrumented oneTBB"; return 1; }
  reset_cache_unless build-tsan "$clangxx"
  configure_and_build build-tsan mpm_tests -- \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1" -DMPM_SANITIZE=thread \
    -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" \
    -DTBB_DIR="$tbb/lib/cmake/TBB" "-DMPM_TEST_SPEC=[parallel]" || return 1
  # CMake links with a RUNPATH, which yields to LD_LIBRARY_PATH: a caller's LD_LIBRARY_PATH naming the directory of
  # Debian's libtbb loads the uninstrumented library, so the instrumented one's directory goes first
  local -x LD_LIBRARY_PATH="$tbb/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  # ldd's output is captured first: under pipefail, `ldd | grep -q` fails whenever grep exits at its first match
  # before ldd has written everything (SIGPIPE); and grep -F, since the path holds "clang++".
  local libs; libs=$(ldd "$root/build-tsan/tests/mpm_tests") || { log "tsan: ldd mpm_tests failed"; return 1; }
  if ! grep -qF "$tbb/lib/libtbb" <<<"$libs"; then
    log "tsan: mpm_tests does not load the instrumented libtbb from $tbb:"
    grep -i tbb <<<"$libs" >&2
    return 1
  fi
  local supp="$root/tools/tsan.supp"
  local tests
  # only mpm_tests is built here: the command-line and install tests (labels cli, install) are left out
  tests=$(cd "$root/build-tsan" && ctest -N -LE 'cli|install' | grep -c 'Test *#')
  if [ "$tests" -eq 0 ]; then log "tsan: no test tagged [parallel] (ctest -N)"; return 1; fi
  log "tsan: $tests multithreaded test(s)"
  # TSan needs a non-randomised address space on kernels with 32 bits of mmap randomisation (otherwise it dies
  # with "unexpected memory mapping"); setarch -R turns ASLR off for this process tree only.
  local norand=()
  if [ "$(cat /proc/sys/vm/mmap_rnd_bits 2>/dev/null || echo 0)" -gt 28 ] && setarch "$(uname -m)" -R true 2>/dev/null; then
    norand=(setarch "$(uname -m)" -R)
  fi
  (cd "$root/build-tsan" &&
    TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$supp" \
    "${norand[@]}" ctest --output-on-failure -LE 'cli|install' --timeout 1200)
}

run_fuzz() {
  local secs=${1:-60}
  pick_clang
  reset_cache_unless build-fuzz "$clangxx" '^MPM_FUZZ:BOOL=ON'
  configure_and_build build-fuzz fuzz_scene fuzz_scene_set -- \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$clang" -DCMAKE_CXX_COMPILER="$clangxx" -DMPM_FUZZ=ON || return 1
  local b="$root/build-fuzz" seeds="$root/tests/fuzz/corpus" status=0 mode pids=() names=()
  rm -rf "$b/artifacts" && mkdir -p "$b/artifacts"
  for mode in scene set; do
    local target=fuzz_scene
    [ "$mode" = set ] && target=fuzz_scene_set
    mkdir -p "$b/corpus-$mode"  # what the fuzzer found, kept between runs (seeds stay untouched)
    ASAN_OPTIONS=detect_leaks=1 "$b/tests/fuzz/$target" "$b/corpus-$mode" "$seeds/$mode" \
      -dict="$root/tests/fuzz/scene.dict" -max_total_time="$secs" -max_len=4096 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$b/artifacts/$target-" >"$b/$target.log" 2>&1 &
    pids+=($!); names+=("$target")
  done
  local i
  for i in "${!pids[@]}"; do
    if ! wait "${pids[$i]}"; then status=1; log "fuzz: ${names[$i]} reported a finding; its log:"; tail -60 "$b/${names[$i]}.log" >&2; fi
    grep -E '^stat::(number_of_executed_units|peak_rss_mb)|cov: ' "$b/${names[$i]}.log" | tail -3 | sed "s/^/  ${names[$i]}: /" >&2
  done
  if compgen -G "$b/artifacts/*" >/dev/null; then
    status=1
    log "fuzz: reproducers (run: build-fuzz/tests/fuzz/TARGET FILE):"
    ls -l "$b/artifacts" >&2
  fi
  return $status
}

cpu_file=$(mktemp)
trap 'rm -f "$cpu_file"' EXIT
cpu_now() {  # sets $cpu: user + system CPU seconds of this shell's finished children (times runs in this shell)
  { times; } >"$cpu_file"
  cpu=$(awk 'NR == 2 { t = 0; for (i = 1; i <= 2; i++) { split($i, a, /[ms]/); t += a[1] * 60 + a[2] } printf "%d", t }' "$cpu_file")
}

timed() {  # NAME FUNC ARGS...
  local name=$1; shift
  local t0=$SECONDS c0 cpu
  cpu_now; c0=$cpu
  log "== $name: start"
  "$@"; local rc=$?
  local dt=$((SECONDS - t0))
  cpu_now; cpu=$((cpu - c0))
  local verdict; verdict=$([ $rc -eq 0 ] && echo clean || echo FAILED)
  log "== $name: $verdict in ${dt} s wall, ${cpu} s CPU"
  summary+=("$(printf '%-5s %-7s %6d s wall %6d s CPU' "$name" "$verdict" "$dt" "$cpu")")
  return $rc
}

summary=()
mode=${1:-}
[ -n "$mode" ] || usage
bash "$root/tools/install-deps.sh" || exit 1
case "$mode" in
  asan) timed asan run_asan ;;
  tsan) timed tsan run_tsan ;;
  fuzz) timed fuzz run_fuzz "${2:-60}" ;;
  all)
    rc=0
    timed asan run_asan || rc=1
    timed tsan run_tsan || rc=1
    timed fuzz run_fuzz "${2:-60}" || rc=1
    log "summary:"
    printf '  %s\n' "${summary[@]}" >&2
    exit $rc
    ;;
  *) usage ;;
esac
