#pragma once
// The instruction set of the hot kernels, chosen when the program starts: the portable library (baseline x86-64,
// SSE2) carries two more copies of each transfer kernel, compiled for AVX2 + FMA (x86-64-v3) and for AVX-512
// (x86-64-v4), and runs the best the CPU has, so that users who link `mpm::engine` without building it for their
// machine (MPM_NATIVE) get its speed. In the AVX-512 copy the cell moments keep their 256-bit vectors and gain 32
// registers instead of 16 (with 16 they spilled at every particle); the gather's loop across particles runs in 8
// lanes of 512 bits (docs/PERFORMANCE.md).
//
// `with_active_isa(f)` runs f inlined into a function compiled for the active instruction set: `flatten` inlines
// everything f calls (the kernels are templates and always-inline helpers). f receives the instruction set as a
// compile-time tag (IsaTag), so that a kernel can pick the code that suits it (log_for, kernels/vector_log.hpp).
// The stencil rows keep the portable build's width (std::experimental::simd fixes it per translation unit: two
// 128-bit halves), now VEX-encoded with fused multiply-adds; the scalar work of the gather (F update, σ, guards)
// gains most (docs/PERFORMANCE.md).
// The environment variable MPM_ISA=baseline forces the portable code (to compare the copies, or to reproduce a
// baseline CPU's round-off bit for bit), MPM_ISA=avx2 or avx512 that copy; auto (the default) takes the best the
// CPU supports. The copies differ in round-off only: the vector copies fuse multiply-adds.
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>

namespace mpm {

enum class Isa {
  baseline,  ///< the build's own instruction set (SSE2, or the machine's with MPM_NATIVE)
  avx2_fma,  ///< x86-64 with AVX2 and FMA (x86-64-v3), in a portable build
  avx512,    ///< x86-64 with AVX-512 F, CD, BW, DQ and VL as well (x86-64-v4), in a portable build
};

/// Whether the build carries the vector copies: an x86-64 build not already compiled for AVX2.
#if defined(__x86_64__) && !defined(__AVX2__)
#define MPM_ISA_DISPATCH 1
#else
#define MPM_ISA_DISPATCH 0
#endif
inline constexpr bool isa_dispatch = MPM_ISA_DISPATCH;

/// Whether this CPU runs the AVX2 copy.
inline bool cpu_has_avx2_fma() {
#if MPM_ISA_DISPATCH
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

/// Whether this CPU (and its operating system) runs the AVX-512 copy.
inline bool cpu_has_avx512() {
#if MPM_ISA_DISPATCH
  __builtin_cpu_init();
  return cpu_has_avx2_fma() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
         __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
         __builtin_cpu_supports("avx512vl");
#else
  return false;
#endif
}

/// Whether this build and CPU run the copy for `isa`.
inline bool cpu_runs(Isa isa) {
  switch (isa) {
    case Isa::avx2_fma: return cpu_has_avx2_fma();
    case Isa::avx512: return cpu_has_avx512();
    default: return true;
  }
}

/// The instruction set for `request` (auto, baseline, avx2, avx512); throws std::invalid_argument naming MPM_ISA
/// and the value when it is none of them or the CPU or build cannot run it.
inline Isa isa_for(std::string_view request) {
  if (request == "auto") return cpu_has_avx512() ? Isa::avx512 : cpu_has_avx2_fma() ? Isa::avx2_fma : Isa::baseline;
  if (request == "baseline") return Isa::baseline;
  if (request == "avx2" || request == "avx512") {
    const Isa isa = request == "avx2" ? Isa::avx2_fma : Isa::avx512;
    if (cpu_runs(isa)) return isa;
    const char* why = !isa_dispatch ? "this build has no separate vector code (not a portable x86-64 build)"
                      : isa == Isa::avx2_fma ? "this CPU lacks AVX2 or FMA"
                                             : "this CPU lacks AVX-512 (F, CD, BW, DQ, VL)";
    throw std::invalid_argument("MPM_ISA = " + std::string(request) + ": " + why);
  }
  throw std::invalid_argument("MPM_ISA = '" + std::string(request) + "': expected auto, baseline, avx2 or avx512");
}

/// The ISA the environment asks for; an invalid MPM_ISA falls back to auto here (the mpm program refuses it).
inline Isa isa_from_environment() {
  const char* request = std::getenv("MPM_ISA");
  try {
    return isa_for(request ? request : "auto");
  } catch (const std::invalid_argument&) {
    return isa_for("auto");
  }
}

namespace detail {
inline Isa active_isa = isa_from_environment();
}

/// The instruction set the kernels run with.
inline Isa active_isa() { return detail::active_isa; }

/// The name the run summary reports as `isa`: avx2 or avx512 (those copies of a portable build), sse2 (its
/// baseline x86-64 code), native (a build for the build machine's CPU, MPM_NATIVE), or baseline (another
/// architecture).
inline const char* isa_name(Isa isa) {
  if (isa == Isa::avx2_fma) return "avx2";
  if (isa == Isa::avx512) return "avx512";
#if defined(__x86_64__) && !defined(__AVX2__) && !defined(__AVX__) && !defined(__SSE4_1__)
  return "sse2";
#elif defined(__x86_64__)
  return "native";
#else
  return "baseline";
#endif
}

/// Selects the kernels' instruction set (not while a step runs); tests use it to run every copy in one process.
inline void set_active_isa(Isa isa) {
  if (!cpu_runs(isa))
    throw std::invalid_argument(std::string("set_active_isa: this CPU or build cannot run ") + isa_name(isa));
  detail::active_isa = isa;
}

/// The instruction set a piece of code is compiled for, as a type: f(IsaTag<I>{}) can use I in `if constexpr`.
template <Isa I>
using IsaTag = std::integral_constant<Isa, I>;

/// Whether code compiled for instruction set I has AVX2: the vector copies, or a build for an AVX2 machine.
template <Isa I>
inline constexpr bool has_avx2 = I == Isa::avx2_fma || I == Isa::avx512 ||
#if defined(__AVX2__)
                                 true;
#else
                                 false;
#endif

#if MPM_ISA_DISPATCH
namespace detail {
template <class F>
[[gnu::target("avx2,fma"), gnu::flatten]] void run_avx2_fma(F& f) {
  f(IsaTag<Isa::avx2_fma>{});
}
template <class F>
[[gnu::target("avx2,fma,avx512f,avx512cd,avx512bw,avx512dq,avx512vl"), gnu::flatten]] void run_avx512(F& f) {
  f(IsaTag<Isa::avx512>{});
}
}  // namespace detail
#endif

/// Runs f(IsaTag<I>{}) compiled for the active instruction set I.
template <class F>
[[gnu::always_inline]] inline void with_active_isa(F&& f) {
#if MPM_ISA_DISPATCH
  if (detail::active_isa == Isa::avx512) {
    detail::run_avx512(f);
    return;
  }
  if (detail::active_isa == Isa::avx2_fma) {
    detail::run_avx2_fma(f);
    return;
  }
#endif
  f(IsaTag<Isa::baseline>{});
}

}  // namespace mpm
