#pragma once
// The engine's reductions: sums whose results do not depend on the thread count.
#include <algorithm>
#include <array>
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "kernels/transfer.hpp"

namespace mpm {

/// Deterministic parallel sums of the K components of f(i) (a std::array<double, K>) over [0, n): fixed chunks,
/// fixed combination order, compensated. Within a chunk four interleaved sums (i mod 4) break the dependency chain
/// of one running sum, which had made the conservation checks latency-bound.
template <std::size_t K, class F>
std::array<double, K> deterministic_sums(std::size_t n, F&& f) {
  constexpr std::size_t lanes = 4;
  using Sums = std::array<CompensatedSum, K>;
  const auto plus = [](Sums a, const Sums& b) {
    for (std::size_t k = 0; k < K; ++k) a[k] = a[k] + b[k];
    return a;
  };
  const Sums total = tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, n, 4096), Sums{},
      [&](const tbb::blocked_range<std::size_t>& r, Sums acc) {
        Sums lane[lanes] = {};
        const auto add = [&](Sums& to, std::size_t i) {
          const std::array<double, K> v = f(i);
          for (std::size_t k = 0; k < K; ++k) to[k].add(v[k]);
        };
        std::size_t i = r.begin();
        for (; i + lanes <= r.end(); i += lanes)
          for (std::size_t l = 0; l < lanes; ++l) add(lane[l], i + l);
        for (; i < r.end(); ++i) add(lane[0], i);
        for (const auto& l : lane) acc = plus(acc, l);
        return acc;
      },
      plus);
  std::array<double, K> out;
  for (std::size_t k = 0; k < K; ++k) out[k] = total[k].value();
  return out;
}

/// deterministic_sums over [0, n) in fixed batches of `batch` indices: f(first, count) returns the K sums of the
/// indices [first, first + count). A batch lets f form what its terms share once for all of them (a body force's
/// coefficients, an exact solution's functions of time) and evaluate the rest in vector lanes.
template <std::size_t K, class F>
std::array<double, K> deterministic_batch_sums(std::size_t n, std::size_t batch, F&& f) {
  return deterministic_sums<K>((n + batch - 1) / batch, [&](std::size_t k) {
    const std::size_t first = k * batch;
    return f(first, std::min(batch, n - first));
  });
}

/// Deterministic parallel sum of f(i) over [0, n) (deterministic_sums of one component).
template <class F>
double deterministic_sum(std::size_t n, F&& f) {
  return deterministic_sums<1>(n, [&](std::size_t i) { return std::array<double, 1>{f(i)}; })[0];
}

}  // namespace mpm
