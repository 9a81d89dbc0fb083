#pragma once
// The engine's reduction: a sum whose result does not depend on the thread count.
#include <cstddef>
#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "kernels/transfer.hpp"

namespace mpm {

/// Deterministic parallel sum of f(i) over [0, n): fixed chunks, fixed combination order, compensated. Within a
/// chunk four interleaved sums (i mod 4) break the dependency chain of one running sum, which had made the
/// conservation checks latency-bound.
template <class F>
double deterministic_sum(std::size_t n, F&& f) {
  constexpr std::size_t lanes = 4;
  return tbb::parallel_deterministic_reduce(
             tbb::blocked_range<std::size_t>(0, n, 4096), CompensatedSum{},
             [&](const tbb::blocked_range<std::size_t>& r, CompensatedSum acc) {
               CompensatedSum lane[lanes];
               std::size_t i = r.begin();
               for (; i + lanes <= r.end(); i += lanes)
                 for (std::size_t k = 0; k < lanes; ++k) lane[k].add(f(i + k));
               for (; i < r.end(); ++i) lane[0].add(f(i));
               for (const auto& l : lane) acc = acc + l;
               return acc;
             },
             std::plus<>())
      .value();
}

}  // namespace mpm
