// The binning of the coloured scatter (engine/cell_bins.hpp): a stable counting sort by block (and optionally by
// cell within the block), chunked by the thread count, whose order must not depend on that count.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <catch2/catch.hpp>
#include <tbb/global_control.h>

#include "engine/cell_bins.hpp"

using namespace mpm;

TEST_CASE("binning is a stable sort by block, the same order for 1 and 2 threads", "[bins][parallel]") {
  const std::array<int, 2> cells{37, 23};  // partial blocks at the far edges
  const std::array<double, 2> length{2.0, 1.0};
  const int width = GENERATE(1, 5);  // single cells (TLS) and the scatter's blocks
  const bool cells_in_block = GENERATE(false, true);
  // more particles than two chunks' minimum, in random order, some outside the grid (binned to the nearest cell)
  const std::size_t n = 100000;
  std::array<std::vector<double>, 2> x;
  std::mt19937_64 rng(11);
  for (int d = 0; d < 2; ++d) {
    std::uniform_real_distribution<double> u(-0.01 * length[d], 1.01 * length[d]);
    for (std::size_t p = 0; p < n; ++p) x[d].push_back(u(rng));
  }
  const std::array<const double*, 2> positions{x[0].data(), x[1].data()};
  // the row-major block of a position, computed here independently of the bins
  auto cell_of = [&](std::size_t p, int d) {
    return std::clamp(static_cast<int>(std::floor(x[d][p] / length[d] * cells[d])), 0, cells[d] - 1);
  };
  auto block_of = [&](std::size_t p) {
    std::size_t block = 0, stride = 1;
    for (int d = 0; d < 2; ++d) {
      block += stride * static_cast<std::size_t>(cell_of(p, d) / width);
      stride *= static_cast<std::size_t>((cells[d] + width - 1) / width);
    }
    return block;
  };
  // the sort key within a block: the cell in the block, row-major, with cells_in_block; else none
  auto key_in_block = [&](std::size_t p) {
    return cells_in_block ? cell_of(p, 0) % width + width * (cell_of(p, 1) % width) : 0;
  };

  std::vector<std::vector<unsigned>> orders;
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    CellBins<2> bins(cells, length, width);
    bins.bin(positions, n, cells_in_block);
    std::vector<int> seen(n, 0);
    std::size_t total = 0;
    for (std::size_t b = 0; b < bins.blocks(); ++b) {
      const auto [begin, end] = bins.block_range(b);
      for (std::size_t k = begin; k < end; ++k) {
        const unsigned p = bins.order()[k];
        REQUIRE(block_of(p) == b);
        if (k > begin) {  // stable: input order within a block (and cell)
          const unsigned previous = bins.order()[k - 1];
          REQUIRE(key_in_block(previous) <= key_in_block(p));
          if (key_in_block(previous) == key_in_block(p)) REQUIRE(previous < p);
        }
        ++seen[p];
      }
      total += end - begin;
    }
    CHECK(total == n);
    CHECK(std::count(seen.begin(), seen.end(), 1) == static_cast<long>(n));
    orders.emplace_back(bins.order().begin(), bins.order().end());
  }
  CHECK(orders[0] == orders[1]);
}
