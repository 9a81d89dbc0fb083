#include "engine/cell_bins.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

namespace mpm {

namespace {
// The sort is stable, so its order is the same for any chunking: by block, and within a block by particle index.
// The chunks are therefore as many as the threads (and at least `min_chunk` particles each), not of a fixed size:
// each chunk counts into a row of blocks() counters that are cleared and prefix-summed (serially) every binning,
// and with single-cell bins (TLS, a counter per cell) at 1e6 particles 16 fixed chunks of 65536 made that a
// 16 MB memset and a 4M-entry serial sum per step.
constexpr std::size_t min_chunk = 1 << 14;

std::size_t chunks_for(std::size_t count) {
  const std::size_t threads =
      std::min<std::size_t>(tbb::this_task_arena::max_concurrency(),
                            tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  return std::clamp<std::size_t>(count / min_chunk, 1, std::max<std::size_t>(1, threads));
}
}  // namespace

template <int Dim>
CellBins<Dim>::CellBins(std::array<int, Dim> cells, std::array<double, Dim> length, int block_width)
    : cells_(cells), block_width_(block_width) {
  if (block_width < 1) throw std::invalid_argument("CellBins: block width must be ≥ 1");
  std::size_t total = 1;
  for (int d = 0; d < Dim; ++d) {
    inv_h_[d] = cells[d] / length[d];
    nblocks_[d] = (cells[d] + block_width - 1) / block_width;
    block_part_[d].resize(cells[d]);
    for (int cell = 0; cell < cells[d]; ++cell)
      block_part_[d][cell] = static_cast<unsigned>(total * (cell / block_width));
    total *= nblocks_[d];
  }
  // colour of block (b0, b1) = (b0 mod 2) + 2 (b1 mod 2); rank blocks colour-major, row-major within a colour
  rank_.resize(total);
  std::array<std::size_t, (1 << Dim)> per_colour{};
  auto colour_of = [&](std::size_t idx) {
    int c = 0;
    for (int d = 0; d < Dim; ++d) {
      c |= static_cast<int>(idx % nblocks_[d] & 1) << d;
      idx /= nblocks_[d];
    }
    return c;
  };
  for (std::size_t b = 0; b < total; ++b) ++per_colour[colour_of(b)];
  colour_begin_[0] = 0;
  for (int c = 0; c < (1 << Dim); ++c) colour_begin_[c + 1] = colour_begin_[c] + per_colour[c];
  auto next = colour_begin_;
  block_of_rank_.resize(total);
  for (std::size_t b = 0; b < total; ++b) {
    rank_[b] = static_cast<unsigned>(next[colour_of(b)]++);
    block_of_rank_[rank_[b]] = static_cast<unsigned>(b);
  }
  block_begin_.assign(total + 1, 0);
}

template <int Dim>
CellBins<Dim> CellBins<Dim>::single_cells_in_order_of(const CellBins& layout) {
  std::array<double, Dim> length;
  for (int d = 0; d < Dim; ++d) length[d] = layout.cells_[d] / layout.inv_h_[d];
  CellBins cells(layout.cells_, length, 1);
  cells.inv_h_ = layout.inv_h_;  // the same cell of every position as the layout
  cells.block_of_rank_ = layout.cells_by_block();
  for (std::size_t k = 0; k < cells.block_of_rank_.size(); ++k) cells.rank_[cells.block_of_rank_[k]] = static_cast<unsigned>(k);
  cells.coloured_ = false;
  return cells;
}

template <int Dim>
std::vector<unsigned> CellBins<Dim>::cells_by_block() const {
  std::vector<unsigned> cells;
  cells.reserve(rank_.size() * (Dim == 1 ? block_width_ : block_width_ * block_width_));
  for (const unsigned block : block_of_rank_)
    for_each_cell_of_block(block, [&](std::size_t cell) { cells.push_back(static_cast<unsigned>(cell)); });
  return cells;
}

template <int Dim>
void CellBins<Dim>::bin(const std::array<const double*, Dim>& x, std::size_t count, bool cells_in_block) {
  order_is_identity_ = false;
  const std::size_t nb = blocks();
  const std::size_t chunks = chunks_for(count), chunk_size = (count + chunks - 1) / chunks;
  key_.resize(count);
  order_.resize(count);
  counts_.assign(chunks * nb, 0);

  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    unsigned* cnt = counts_.data() + c * nb;
    const std::size_t end = std::min(count, (c + 1) * chunk_size);
    for (std::size_t p = c * chunk_size; p < end; ++p) {
      unsigned block = 0;
      for (int d = 0; d < Dim; ++d) block += block_part_[d][cell_of(x[d][p], d)];
      const unsigned k = rank_[block];
      key_[p] = k;
      ++cnt[k];
    }
  });

  // exclusive prefix over (rank, chunk): particles of one block keep their chunk order, hence stability
  unsigned running = 0;
  for (std::size_t k = 0; k < nb; ++k) {
    block_begin_[k] = running;
    for (std::size_t c = 0; c < chunks; ++c) {
      const unsigned n = counts_[c * nb + k];
      counts_[c * nb + k] = running;
      running += n;
    }
  }
  block_begin_[nb] = running;

  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    unsigned* off = counts_.data() + c * nb;
    const std::size_t end = std::min(count, (c + 1) * chunk_size);
    for (std::size_t p = c * chunk_size; p < end; ++p) order_[off[key_[p]]++] = static_cast<unsigned>(p);
  });
  if (cells_in_block) sort_cells_in_blocks(x);
}

template <int Dim>
void CellBins<Dim>::sort_cells_in_blocks(const std::array<const double*, Dim>& x) {
  std::size_t cells_per_block = 1;
  for (int d = 0; d < Dim; ++d) cells_per_block *= block_width_;
  sorted_.resize(order_.size());
  // key_ (free after the block sort) holds the cell in its block of each position of order_
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<unsigned> start(cells_per_block + 1);
    for (std::size_t b = r.begin(); b < r.end(); ++b) {
      std::fill(start.begin(), start.end(), 0u);
      for (std::size_t k = block_begin_[b]; k < block_begin_[b + 1]; ++k) {
        unsigned local = 0;
        for (int d = Dim - 1; d >= 0; --d)
          local = local * block_width_ + static_cast<unsigned>(cell_of(x[d][order_[k]], d) % block_width_);
        key_[k] = local;
        ++start[local + 1];
      }
      for (std::size_t c = 0; c < cells_per_block; ++c) start[c + 1] += start[c];
      for (std::size_t k = block_begin_[b]; k < block_begin_[b + 1]; ++k)
        sorted_[block_begin_[b] + start[key_[k]]++] = order_[k];
    }
  });
  order_.swap(sorted_);
}

template class CellBins<1>;
template class CellBins<2>;

}  // namespace mpm
