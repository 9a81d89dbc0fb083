#pragma once
// The engine's one form of a parallel loop over an index range: oneTBB's blocked range with a fixed grain and the
// default (auto) partitioner, handing each task a contiguous [begin, end) so the loop body stays a plain loop the
// compiler can vectorise. (With tbb::parallel_for's index form, grain 1, the partitioner's splitting was 5 % of a
// TLS step.)
#include <cstddef>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mpm {

/// Calls f(begin, end) on chunks of [0, n) of at least `grain` indices (fewer in the last), in parallel.
template <class F>
void parallel_over(std::size_t n, std::size_t grain, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                    [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
}

}  // namespace mpm
