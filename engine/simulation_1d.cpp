// Simulation<1> (see simulation_impl.hpp).
#include "engine/simulation_impl.hpp"

namespace mpm {

template class Simulation<1>;
template AnyBasis<1> make_basis<1>(const GridSpec&, int);

}  // namespace mpm
