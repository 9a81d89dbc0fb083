// Simulation<2> (see simulation_impl.hpp), with the steps of the uniform B-spline and DDMPM bases; the other bases'
// steps compile in simulation_2d_generic.cpp.
#include "engine/simulation_impl.hpp"

namespace mpm {

MPM_GENERIC_STEPS_2D(extern);
template class Simulation<2>;
template AnyBasis<2> make_basis<2>(const GridSpec&, int);

}  // namespace mpm
