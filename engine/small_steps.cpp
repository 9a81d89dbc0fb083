#include "engine/small_steps.hpp"

namespace mpm {

// Where one thread and two ran level (docs/PERFORMANCE.md, "Small problems": bench_step's usl-parallel,
// musl-parallel and musl-tls-parallel against one thread).
const std::size_t SmallSteps::default_serial_below = 4096;

}  // namespace mpm
