#pragma once
// Particles binned by block of cells, blocks split into 2^Dim colour classes, for the lock-free scatter:
// two blocks of one colour are separated by a block of another colour along every axis, and a block is wide
// enough (block_width_for) that blocks of one colour never write the same DOF, even after their particles have
// moved a little since they were binned. One tbb::parallel_for per colour needs no atomics, and since the order
// of the sums into each DOF is fixed by the (stable) sort and the colour sequence, the result is bitwise
// identical for any thread count.
#include <array>
#include <cstddef>
#include <span>
#include <utility>
#include <type_traits>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mpm {

template <int Dim>
class CellBins {
 public:
  /// The narrowest block width for which blocks of one colour never write the same DOF while every particle is
  /// less than `slack` cells (per axis) away from where it was binned. A particle of cell c writes functions
  /// c … c + reach − 1 (`reach`: the stencil width with the kernels' padding lanes, stencil.hpp); binned into block
  /// [0, W) it is in a cell of [−slack, W − 1 + slack], the next block of its colour starts at 2W, so the two stay
  /// apart when W − 1 + slack + reach − 1 < 2W − slack.
  static constexpr int block_width_for(int reach, int slack) { return reach + 2 * slack - 1; }

  /// `block_width` cells per block and axis (block_width_for).
  CellBins(std::array<int, Dim> cells, std::array<double, Dim> length, int block_width);

  /// Stable counting sort of the particles by block, colour-major. Positions outside the grid are binned into
  /// the nearest cell (the run's guards report them).
  void bin(const std::array<const double*, Dim>& x, std::size_t count);

  /// After the caller permuted the particles into order(): the order becomes the identity, block ranges stay.
  void adopt_order() {
    for (std::size_t k = 0; k < order_.size(); ++k) order_[k] = static_cast<unsigned>(k);
  }

  /// The range of order() holding the particles of a block, by its row-major block index (with a block width of
  /// 1: a cell's particles).
  std::pair<std::size_t, std::size_t> block_range(std::size_t row_major) const {
    const unsigned r = rank_[row_major];
    return {block_begin_[r], block_begin_[r + 1]};
  }

  /// Particle indices in block order.
  std::span<const unsigned> order() const { return order_; }
  int block_width() const { return block_width_; }
  std::size_t blocks() const { return block_begin_.size() - 1; }

  /// Calls f(begin, end) — or f(block, begin, end) — for every non-empty block's range of order(), colour after
  /// colour, blocks of one colour in parallel. Block indices run over [0, blocks()).
  template <class F>
  void for_each_block_coloured(F&& f) const {
    for (int c = 0; c < (1 << Dim); ++c)
      tbb::parallel_for(tbb::blocked_range<std::size_t>(colour_begin_[c], colour_begin_[c + 1], 1),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b < r.end(); ++b) {
                            if (block_begin_[b] == block_begin_[b + 1]) continue;
                            if constexpr (std::is_invocable_v<F, std::size_t, std::size_t, std::size_t>)
                              f(b, block_begin_[b], block_begin_[b + 1]);
                            else
                              f(block_begin_[b], block_begin_[b + 1]);
                          }
                        });
  }

  /// Calls f(begin, end) for every block's range in a fixed serial order (the reference for the scatter).
  template <class F>
  void for_each_block_serial(F&& f) const {
    for (std::size_t b = 0; b + 1 < block_begin_.size(); ++b)
      if (block_begin_[b] < block_begin_[b + 1]) f(block_begin_[b], block_begin_[b + 1]);
  }

 private:
  std::array<int, Dim> cells_;
  std::array<double, Dim> inv_h_;
  std::array<int, Dim> nblocks_;
  int block_width_;
  std::vector<unsigned> rank_;          ///< colour-major rank of each block (row-major block index)
  std::array<std::size_t, (1 << Dim) + 1> colour_begin_{};
  std::vector<std::size_t> block_begin_;  ///< by rank, size blocks+1
  std::vector<unsigned> key_;           ///< block rank per particle
  std::vector<unsigned> order_;
  std::vector<std::size_t> counts_;     ///< per chunk and rank
};

extern template class CellBins<1>;
extern template class CellBins<2>;

}  // namespace mpm
