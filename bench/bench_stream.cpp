// Machine limits for the roofline in docs/PERFORMANCE.md.
//
// stream/<kernel>/threads:<T>: STREAM-like kernels on three arrays of 2^27 doubles (1 GiB each, far beyond any
// cache), statically split over T TBB threads (each thread first-touches the part it later streams).
// bytes_per_second counts STREAM's way: triad a = b + s c moves 3 x 8 bytes per element (2 reads, 1 write);
// with write-allocate the DRAM really moves 4 x 8 (the written line is read first), see the "dram_bytes" counter.
//
// peak/fma_avx512/threads:<T>: the FMA peak, 16 independent chains of 512-bit fused multiply-adds per thread
// (compiled for AVX-512 on this function only; skipped where the CPU has none). 1 FMA = 2 flops.
// peak/fma_avx2/threads:<T>: the same with 12 chains of 256-bit FMAs, for CPUs without AVX-512 (e.g. AMD Zen 3,
// on which this engine has also been measured).
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"  // g++ 12 false positive inside avx512fintrin.h
#include <immintrin.h>
#pragma GCC diagnostic pop
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "bench/bench_util.hpp"

namespace {

constexpr std::size_t kElements = std::size_t(1) << 27;

struct Arrays {
  std::unique_ptr<double[]> a, b, c;
  Arrays() : a(new double[kElements]), b(new double[kElements]), c(new double[kElements]) {}
};

template <class F>
void over_array(F&& f) {
  static tbb::affinity_partitioner ap;  // same split every call: each thread re-streams what it touched
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, kElements, 1 << 16),
                    [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); }, ap);
}

enum class Kernel { copy, scale, add, triad };

void BM_Stream(benchmark::State& state, Kernel kernel) {
  auto gc = mpm_bench::limit_threads(static_cast<int>(state.range(0)));
  static std::unique_ptr<Arrays> arrays;  // allocated once for all stream benchmarks (3 GiB)
  if (!arrays) arrays = std::make_unique<Arrays>();
  double* a = arrays->a.get();
  double* b = arrays->b.get();
  double* c = arrays->c.get();
  over_array([&](std::size_t lo, std::size_t hi) {
    for (std::size_t i = lo; i < hi; ++i) {
      a[i] = 1.0;
      b[i] = 2.0;
      c[i] = 0.5;
    }
  });
  const double s = 0.5;
  auto run = [&] {
    switch (kernel) {
      case Kernel::copy:
        over_array([&](std::size_t lo, std::size_t hi) {
          for (std::size_t i = lo; i < hi; ++i) c[i] = a[i];
        });
        break;
      case Kernel::scale:
        over_array([&](std::size_t lo, std::size_t hi) {
          for (std::size_t i = lo; i < hi; ++i) b[i] = s * c[i];
        });
        break;
      case Kernel::add:
        over_array([&](std::size_t lo, std::size_t hi) {
          for (std::size_t i = lo; i < hi; ++i) c[i] = a[i] + b[i];
        });
        break;
      case Kernel::triad:
        over_array([&](std::size_t lo, std::size_t hi) {
          for (std::size_t i = lo; i < hi; ++i) a[i] = b[i] + s * c[i];
        });
        break;
    }
  };
  run();
  for (auto _ : state) {
    run();
    benchmark::ClobberMemory();
  }
  const int arrays_moved = kernel == Kernel::copy || kernel == Kernel::scale ? 2 : 3;
  const double per_iter = static_cast<double>(kElements) * sizeof(double);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * arrays_moved * per_iter));
  state.counters["dram_bytes"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * (arrays_moved + 1) * per_iter,
                         benchmark::Counter::kIsRate);
}

__attribute__((target("avx512f,fma"))) double fma_chains(std::int64_t rounds) {
  __m512d acc[16];
  for (int k = 0; k < 16; ++k) acc[k] = _mm512_set1_pd(1.0 + 1e-3 * k);
  const __m512d m = _mm512_set1_pd(0.999999), add = _mm512_set1_pd(1e-7);
  for (std::int64_t r = 0; r < rounds; ++r) {
    for (int k = 0; k < 16; ++k) acc[k] = _mm512_fmadd_pd(acc[k], m, add);
    __asm__ volatile("" : "+v"(acc[0]), "+v"(acc[1]), "+v"(acc[2]), "+v"(acc[3]), "+v"(acc[4]), "+v"(acc[5]),
                     "+v"(acc[6]), "+v"(acc[7]));
  }
  __m512d sum = acc[0];
  for (int k = 1; k < 16; ++k) sum = _mm512_add_pd(sum, acc[k]);
  return _mm512_reduce_add_pd(sum);
}

__attribute__((target("avx2,fma"))) double fma_chains_avx2(std::int64_t rounds) {
  __m256d acc[12];
  for (int k = 0; k < 12; ++k) acc[k] = _mm256_set1_pd(1.0 + 1e-3 * k);
  const __m256d m = _mm256_set1_pd(0.999999), add = _mm256_set1_pd(1e-7);
  for (std::int64_t r = 0; r < rounds; ++r) {
    for (int k = 0; k < 12; ++k) acc[k] = _mm256_fmadd_pd(acc[k], m, add);
    __asm__ volatile("" : "+x"(acc[0]), "+x"(acc[1]), "+x"(acc[2]), "+x"(acc[3]), "+x"(acc[4]), "+x"(acc[5]));
  }
  __m256d sum = acc[0];
  for (int k = 1; k < 12; ++k) sum = _mm256_add_pd(sum, acc[k]);
  alignas(32) double lanes[4];
  _mm256_store_pd(lanes, sum);
  return lanes[0] + lanes[1] + lanes[2] + lanes[3];
}

/// FMA peak of one instruction set: `chains(rounds)` issues rounds x fmas_per_round FMAs of `lanes` doubles.
void fma_peak(benchmark::State& state, bool supported, const char* isa, double (*chains)(std::int64_t),
              int fmas_per_round, int lanes) {
  if (!supported) {
    state.SkipWithError((std::string("no ") + isa + " on this CPU").c_str());
    return;
  }
  const int threads = static_cast<int>(state.range(0));
  auto gc = mpm_bench::limit_threads(threads);
  constexpr std::int64_t rounds = 1 << 22;  // per task
  const int tasks = 8 * threads;
  for (auto _ : state) {
    tbb::parallel_for(0, tasks, [&](int) { benchmark::DoNotOptimize(chains(rounds)); });
  }
  const double flops = static_cast<double>(state.iterations()) * tasks * rounds * fmas_per_round * lanes * 2;
  state.counters["flops_per_s"] = benchmark::Counter(flops, benchmark::Counter::kIsRate);
}

void BM_FmaPeak(benchmark::State& state) {
  __builtin_cpu_init();
  fma_peak(state, __builtin_cpu_supports("avx512f"), "AVX-512", fma_chains, 16, 8);
}
void BM_FmaPeakAvx2(benchmark::State& state) {
  __builtin_cpu_init();
  fma_peak(state, __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma"), "AVX2+FMA", fma_chains_avx2, 12, 4);
}

const bool registered = [] {
  using benchmark::RegisterBenchmark;
  for (auto [name, k] : {std::pair{"stream/copy", Kernel::copy}, std::pair{"stream/scale", Kernel::scale},
                         std::pair{"stream/add", Kernel::add}, std::pair{"stream/triad", Kernel::triad}})
    RegisterBenchmark(name, BM_Stream, k)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);
  RegisterBenchmark("peak/fma_avx512", BM_FmaPeak)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
  RegisterBenchmark("peak/fma_avx2", BM_FmaPeakAvx2)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace
