#pragma once
// Particles binned by block of cells, blocks split into 2^Dim colour classes, for the lock-free scatter:
// two blocks of one colour are separated by a block of another colour along every axis, and a block is wide
// enough (block_width_for) that blocks of one colour never write the same DOF, even after their particles have
// moved a little since they were binned. One tbb::parallel_for per colour needs no atomics, and since the order
// of the sums into each DOF is fixed by the (stable) sort and the colour sequence, the result is bitwise
// identical for any thread count.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
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

  /// Single cells of `layout`'s grid, ranked in the order layout.for_each_cell_by_block visits them instead of by
  /// colour, for per-cell work over particles that lie in `layout`'s order: the visit then reads this order() and
  /// the particle columns front to back. (With colour-major single cells, a TLS rebuild stalled on loading its
  /// own order(), whose cells it met in another order.) Such bins have no colour classes: no coloured loops.
  static CellBins single_cells_in_order_of(const CellBins& layout);

  /// Stable counting sort of the particles by block, colour-major; with `cells_in_block`, by cell within each block
  /// as well (row-major), so that the particles of a cell are contiguous in order(): the scatter by cell moments
  /// (kernels/cell_moments.hpp) sums each cell's particles before it touches the grid. Positions outside the grid
  /// are binned into the nearest cell (the run's guards report them).
  void bin(const std::array<const double*, Dim>& x, std::size_t count, bool cells_in_block = false);

  /// After the caller permuted the particles into order(): the order becomes the identity, block ranges stay.
  void adopt_order() {
    for (std::size_t k = 0; k < order_.size(); ++k) order_[k] = static_cast<unsigned>(k);
    order_is_identity_ = true;
  }
  /// Whether order() is the identity (from adopt_order to the next bin): a block's range of order() is then the
  /// range of particle indices itself.
  bool order_is_identity() const { return order_is_identity_; }

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
    for_each_colour(1, tbb::auto_partitioner(), [&](std::size_t first, std::size_t last) {
      for_each_nonempty_block(first, last, [&](std::size_t block, std::size_t begin, std::size_t end) {
        if constexpr (std::is_invocable_v<F, std::size_t, std::size_t, std::size_t>)
          f(block, begin, end);
        else
          f(begin, end);
      });
    });
  }

  /// Calls f(first, last) for runs [first, last) of at most `run_blocks` consecutive block indices of one colour,
  /// colour after colour, the runs of one colour in parallel. A run's blocks lie back to back in order(): from
  /// block_begin(first) to block_begin(last).
  template <class F>
  void for_each_block_run_coloured(std::size_t run_blocks, F&& f) const {
    for_each_colour(std::max<std::size_t>(run_blocks, 1), tbb::simple_partitioner(), f);
  }

  /// Where the range of order() of the block with index `block` begins; block_begin(blocks()) is its end.
  std::size_t block_begin(std::size_t block) const { return block_begin_[block]; }

  /// Calls f(block, begin, end) for the non-empty blocks among block indices [first, last), in index order, with
  /// each block's range of order() (for the blocks of a run of for_each_block_run_coloured).
  template <class F>
  void for_each_nonempty_block(std::size_t first, std::size_t last, F&& f) const {
    for (std::size_t b = first; b < last; ++b)
      if (block_begin_[b] < block_begin_[b + 1]) f(b, block_begin_[b], block_begin_[b + 1]);
  }

  /// Calls f(cell) for every cell (row-major index), blocks in parallel in their rank order, the cells of a block
  /// one after another: the order in which the particle columns lie after a reordering by these bins, so per-cell
  /// work that reads the particles of each cell (the TLS sums) streams through them instead of jumping between
  /// the colour classes, as a row-major sweep of the cells does. Not coloured: f may write only its cell's data.
  /// f(rank, cell) is also told its block's rank: the cells of a block are visited in order by one task, so f may
  /// accumulate into data of the block's rank, in an order that does not depend on the thread count.
  template <class F>
  void for_each_cell_by_block(F&& f) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block_of_rank_.size(), 4),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t k = r.begin(); k < r.end(); ++k)
                          if constexpr (std::is_invocable_v<F, std::size_t, std::size_t>)
                            for_each_cell_of_block(block_of_rank_[k], [&](std::size_t c) { f(k, c); });
                          else
                            for_each_cell_of_block(block_of_rank_[k], f);
                      });
  }

  /// The cells (row-major indices) in the order for_each_cell_by_block visits them, blocks by rank.
  std::vector<unsigned> cells_by_block() const;

  /// Calls f(begin, end) for every block's range in a fixed serial order (the reference for the scatter).
  template <class F>
  void for_each_block_serial(F&& f) const {
    for_each_nonempty_block(0, blocks(), [&](std::size_t, std::size_t begin, std::size_t end) { f(begin, end); });
  }

 private:
  /// f(first, last) over ranges of block indices, colour after colour, the blocks of one colour in parallel,
  /// split by `partitioner` down to `grain` blocks.
  template <class Partitioner, class F>
  void for_each_colour(std::size_t grain, Partitioner partitioner, F&& f) const {
    if (!coloured_) throw std::logic_error("CellBins: these bins have no colour classes");
    for (int c = 0; c < (1 << Dim); ++c)
      tbb::parallel_for(
          tbb::blocked_range<std::size_t>(colour_begin_[c], colour_begin_[c + 1], grain),
          [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); }, partitioner);
  }

  /// f(cell) for the cells of a block (row-major block index), row-major.
  template <class F>
  void for_each_cell_of_block(std::size_t block, F&& f) const {
    std::array<int, Dim> lo, hi;
    for (int d = 0; d < Dim; ++d) {
      lo[d] = static_cast<int>(block % nblocks_[d]) * block_width_;
      hi[d] = std::min(lo[d] + block_width_, cells_[d]);
      block /= nblocks_[d];
    }
    const int j_lo = Dim > 1 ? lo[Dim - 1] : 0, j_hi = Dim > 1 ? hi[Dim - 1] : 1;
    for (int j = j_lo; j < j_hi; ++j)
      for (int i = lo[0]; i < hi[0]; ++i)
        f(static_cast<std::size_t>(i) + (Dim > 1 ? static_cast<std::size_t>(j) * cells_[0] : 0));
  }

  std::array<int, Dim> cells_;
  std::array<double, Dim> inv_h_;
  std::array<int, Dim> nblocks_;
  int block_width_;
  /// Per axis and cell along it: that axis' share of the row-major block index, stride × (cell / block width).
  /// A table, not a division: the integer divisions by the run-time block width were most of the time of the
  /// binning's first pass, which the single-cell bins of a reconstruction run every step.
  std::array<std::vector<unsigned>, Dim> block_part_;
  /// The cell of position x along axis d, clamped to the grid.
  int cell_of(double x, int d) const {
    return std::clamp(static_cast<int>(std::floor(x * inv_h_[d])), 0, cells_[d] - 1);
  }
  /// Stable counting sort of each block's range of order() by the particles' cells in the block (row-major).
  void sort_cells_in_blocks(const std::array<const double*, Dim>& x);
  std::vector<unsigned> rank_;          ///< colour-major rank of each block (row-major block index)
  std::vector<unsigned> block_of_rank_;  ///< the inverse: row-major index of the block of each rank
  std::array<std::size_t, (1 << Dim) + 1> colour_begin_{};
  std::vector<std::size_t> block_begin_;  ///< by rank, size blocks+1
  std::vector<unsigned> key_;           ///< block rank per particle
  std::vector<unsigned> order_;
  std::vector<unsigned> sorted_;        ///< sort_cells_in_blocks' output, swapped with order_
  std::vector<unsigned> counts_;        ///< per chunk and rank (particle indices fit: order_ holds them)
  bool coloured_ = true;                ///< ranks are colour-major (false: single_cells_in_order_of)
  bool order_is_identity_ = false;
};

extern template class CellBins<1>;
extern template class CellBins<2>;

}  // namespace mpm
