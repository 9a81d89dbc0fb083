#pragma once
// Point forces on the grid (problem.hpp PointLoad): the boundary term of thesis eq. 2.21, f_i += ∫_Γ φ_i τ dΓ,
// for a traction concentrated at one point x of the current configuration: f_i += φ_i(x) force. With an open
// knot vector the first and last functions are interpolatory, so a load at a grid end lands on one DOF; a load
// inside the grid (the traction bar's end, thesis §4.6.2) is shared by the functions non-zero at x.
#include <vector>

#include "engine/problem.hpp"
#include "kernels/stencil.hpp"

namespace mpm {

template <int Dim, int S, class Axis>
void add_point_loads(const TensorBasis<Dim, Axis>& basis, const GridView<Dim>& g,
                     const std::vector<PointLoad<Dim>>& loads) {
  for (const auto& load : loads) {
    const auto st = stencil_at<Dim, S>(basis, load.x.data());
    for_each_node(st, g.stride1, [&](int i, double w, const std::array<double, Dim>&) {
      for (int d = 0; d < Dim; ++d) g.f[d][i] += w * load.force[d];
    });
  }
}

}  // namespace mpm
