#pragma once
// Small problems step on the calling thread alone. A step is a dozen parallel stages (the scatter's colours, the
// gathers, the grid loops, the conservation sums); with a few thousand particles each stage is a few microseconds
// of work, less than waking a second thread and joining it costs, and two threads ran slower than one
// (docs/PERFORMANCE.md, "Small problems"). The engine's loops give the same bits however they are split, so where
// a step runs changes no result.
#include <cstddef>
#include <memory>

#include <tbb/task_arena.h>

namespace mpm {

class SmallSteps {
 public:
  /// Steps with fewer particles than this, on a grid of fewer DOFs, run serially (small_steps.cpp).
  static const std::size_t default_serial_below;

  /// Sets the size below which steps run serially (0: never).
  void set_serial_below(std::size_t size) { serial_below_ = size; }

  /// Whether a step of `particles` particles on `dofs` grid DOFs runs on the calling thread alone.
  bool serial(std::size_t particles, std::size_t dofs) const {
    return particles < serial_below_ && dofs < serial_below_;
  }

  /// Runs step() on the calling thread alone if the step is small (an arena with no worker slots), on the threads
  /// of the current arena otherwise. Exceptions reach the caller either way.
  template <class F>
  void run(std::size_t particles, std::size_t dofs, F&& step) {
    if (!serial(particles, dofs)) return step();
    if (!one_thread_) one_thread_ = std::make_unique<tbb::task_arena>(1);
    one_thread_->execute(step);
  }

 private:
  std::size_t serial_below_ = default_serial_below;
  std::unique_ptr<tbb::task_arena> one_thread_;
};

}  // namespace mpm
