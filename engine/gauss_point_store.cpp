#include "engine/gauss_point_store.hpp"

#include <stdexcept>
#include <string>

namespace mpm {

namespace {

/// The Gauss points of the unit cell [0, 1]^Dim and their weights (sum 1).
template <int Dim>
void place_unit_cell_rule(const Scene& scene, GaussPointStore<Dim>& gp) {
  if (scene.algorithm.mapping == Mapping::cubic_spline) {
    // Gauss points in each half of the knot span (thesis §3.2.3, Fig. 3.4): 2 per half integrate a cubic
    // exactly on each half, whatever the spline's knots (the particles) do inside the span
    const GaussRule half = gauss_legendre(scene.algorithm.gauss_per_cell[0]);
    for (int h = 0; h < 2; ++h)
      for (std::size_t j = 0; j < half.x.size(); ++j) {
        std::array<double, Dim> xi{};
        xi[0] = 0.5 * (h + half.x[j]);
        gp.local.push_back(xi);
        gp.local_w.push_back(0.5 * half.w[j]);
      }
    return;
  }
  // tensor-product Gauss–Legendre rule of the unit cell (paper eqs 22–25, thesis eq. 3.3)
  std::array<GaussRule, Dim> rules;
  for (int d = 0; d < Dim; ++d) {
    rules[d] = gauss_legendre(scene.algorithm.gauss_per_cell[d]);
    gp.axis_points[d] = rules[d].x;
  }
  const int n0 = rules[0].x.size(), n1 = Dim > 1 ? rules[Dim - 1].x.size() : 1;
  for (int j = 0; j < n1; ++j)
    for (int i = 0; i < n0; ++i) {
      std::array<double, Dim> xi;
      xi[0] = rules[0].x[i];
      double w = rules[0].w[i];
      if constexpr (Dim > 1) {
        xi[1] = rules[1].x[j];
        w *= rules[1].w[j];
      }
      gp.local.push_back(xi);
      gp.local_w.push_back(w);
    }
}

template <int Dim>
std::array<double, Dim> grid_length(const Scene& scene) {
  std::array<double, Dim> l;
  for (int d = 0; d < Dim; ++d) l[d] = scene.grid.length[d];
  return l;
}

}  // namespace

template <int Dim>
GaussPointStore<Dim>::GaussPointStore(const Scene& scene, int block_width)
    : grid(CellGrid<Dim>::of(scene.grid.cells, scene.grid.length)),
      bins(grid.cells, grid_length<Dim>(scene), block_width) {
  const int narrowest = CellBins<Dim>::block_width_for(stencil_reach(stencil_width_of(scene.grid.basis)), 0);
  if (block_width < narrowest)
    throw std::logic_error("GaussPoints: blocks of " + std::to_string(block_width) + " cells, at least " +
                           std::to_string(narrowest) + " needed for the scene's basis");
  place_unit_cell_rule(scene, *this);
  per_cell = static_cast<int>(local.size());
  if (per_cell > max_per_cell)  // the scene caps gauss_per_cell at 10 per axis
    throw std::logic_error("GaussPoints: " + std::to_string(per_cell) + " Gauss points per cell, at most " +
                           std::to_string(max_per_cell) + " supported");
  const std::size_t ncells = grid.count(), n = ncells * per_cell;
  m.assign(n, 0.0);
  for (int d = 0; d < Dim; ++d) {
    x[d].assign(n, 0.0);
    q[d].assign(n, 0.0);
    fb[d].assign(n, 0.0);
  }
  for (auto& col : s) col.assign(n, 0.0);
  cell_of_slot = bins.cells_by_block();
  slot_of_cell.assign(ncells, 0);
  for (std::size_t k = 0; k < ncells; ++k) slot_of_cell[cell_of_slot[k]] = static_cast<unsigned>(k);
  for (std::size_t c = 0; c < ncells; ++c) {
    const CellBox<Dim> box = grid.box(c);
    for (int g = 0; g < per_cell; ++g)
      for (int d = 0; d < Dim; ++d) x[d][first_point(c) + g] = box.lo[d] + local[g][d] * grid.h[d];
  }
  std::array<const double*, Dim> xs;
  for (int d = 0; d < Dim; ++d) xs[d] = x[d].data();
  bins.bin(xs, n);  // Gauss points never move: binned once (in storage order, as they are placed)
  // GaussPoints::scatter reads a block's range of the order as whole cells in storage order
  const auto order = bins.order();
  for (std::size_t k = 0; k < n; ++k)
    if (order[k] != k) throw std::logic_error("GaussPoints: the Gauss points are not stored in their block order");
}

template <int Dim>
double GaussPointStore<Dim>::place_clipped(std::size_t first, const GaussRule& rule, double a, double b, double lo,
                                           double hi, double* w) {
  const double a_in = std::max(a, lo), b_in = std::min(b, hi);
  // the part inside the body gets the whole rule (its points stay in [a, b], inside one cell: the binning holds)
  const bool inside = b_in > a_in;
  for (std::size_t j = 0; j < rule.x.size(); ++j) {
    x[0][first + j] = inside ? a_in + rule.x[j] * (b_in - a_in) : a + rule.x[j] * (b - a);
    w[j] = inside ? rule.w[j] * (b_in - a_in) : 0.0;
  }
  return inside ? b_in - a_in : 0.0;
}

template <int Dim>
GaussView<Dim> GaussPointStore<Dim>::view() const {
  GaussView<Dim> v;
  for (int d = 0; d < Dim; ++d) {
    v.x[d] = x[d].data();
    v.q[d] = q[d].data();
    v.fb[d] = fb[d].data();
  }
  v.m = m.data();
  for (int c = 0; c < sym_components<Dim>; ++c) v.s[c] = s[c].data();
  return v;
}

template struct GaussPointStore<1>;
template struct GaussPointStore<2>;

}  // namespace mpm
