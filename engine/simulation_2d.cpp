// Simulation<2> (see simulation_impl.hpp).
#include "engine/simulation_impl.hpp"

namespace mpm {

template class Simulation<2>;
template AnyBasis<2> make_basis<2>(const GridSpec&, int);

}  // namespace mpm
