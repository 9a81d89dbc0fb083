#include "engine/gauss_points.hpp"

namespace mpm {

template <int Dim>
GaussPoints<Dim>::GaussPoints(const Scene& scene)
    : GaussPoints(scene, CellBins<Dim>::block_width_for(stencil_reach(stencil_width_of(scene.grid.basis)), 0)) {}

template <int Dim>
GaussPoints<Dim>::GaussPoints(const Scene& scene, int block_width)
    : store_(scene, block_width), method_(method_of(scene)) {}

template <int Dim>
typename GaussPoints<Dim>::Method GaussPoints<Dim>::method_of(const Scene& scene) {
  switch (scene.algorithm.mapping) {
    case Mapping::mls: return MlsReconstruction<Dim>(scene);
    case Mapping::cubic_spline: return CubicSplineReconstruction<Dim>(scene);
    default: return TlsReconstruction<Dim>(scene);
  }
}

template class GaussPoints<1>;
template class GaussPoints<2>;

}  // namespace mpm
