// The 2D steps of the Cox–de Boor and max-ent bases, compiled apart from simulation_2d.cpp so that the 2D kernels
// (three instruction-set copies of each) build on two cores at once.
#include "engine/simulation_impl.hpp"

namespace mpm {

MPM_GENERIC_STEPS_2D();

}  // namespace mpm
