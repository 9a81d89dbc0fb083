#include "engine/gauss_points.hpp"

#include <algorithm>

namespace mpm {

namespace {

template <int Dim>
std::array<int, Dim> first_n(const std::array<int, 3>& a) {
  std::array<int, Dim> r;
  std::copy_n(a.begin(), Dim, r.begin());
  return r;
}

template <int Dim>
std::array<double, Dim> first_n(const std::array<double, 3>& a) {
  std::array<double, Dim> r;
  std::copy_n(a.begin(), Dim, r.begin());
  return r;
}

}  // namespace

template <int Dim>
GaussPoints<Dim>::GaussPoints(const Scene& scene)
    : GaussPoints(scene, CellBins<Dim>::block_width_for(stencil_reach(stencil_width_of(scene.grid.basis)), 0)) {}

template <int Dim>
GaussPoints<Dim>::GaussPoints(const Scene& scene, int block_width)
    : mapping_(scene.algorithm.mapping),
      tls_degree_(scene.algorithm.tls_degree),
      mls_support_(scene.algorithm.mls_support),
      cells_(first_n<Dim>(scene.grid.cells)),
      bins_(cells_, first_n<Dim>(scene.grid.length), block_width) {
  const int narrowest = CellBins<Dim>::block_width_for(stencil_reach(stencil_width_of(scene.grid.basis)), 0);
  if (block_width < narrowest)
    throw std::logic_error("GaussPoints: blocks of " + std::to_string(block_width) + " cells, at least " +
                           std::to_string(narrowest) + " needed for the scene's basis");
  std::size_t ncells = 1;
  for (int d = 0; d < Dim; ++d) {
    h_[d] = scene.grid.length[d] / cells_[d];
    ncells *= cells_[d];
  }
  if (mapping_ == Mapping::cubic_spline) {
    // Gauss points in each half of the knot span (thesis §3.2.3, Fig. 3.4): 2 per half integrate a cubic
    // exactly on each half, whatever the spline's knots (the particles) do inside the span
    half_rule_ = gauss_legendre(scene.algorithm.gauss_per_cell[0]);
    for (int half = 0; half < 2; ++half)
      for (std::size_t j = 0; j < half_rule_.x.size(); ++j) {
        std::array<double, Dim> xi{};
        xi[0] = 0.5 * (half + half_rule_.x[j]);
        local_.push_back(xi);
        local_w_.push_back(0.5 * half_rule_.w[j]);
      }
  } else {
    // tensor-product Gauss–Legendre rule of the unit cell (paper eqs 22–25, thesis eq. 3.3)
    std::array<GaussRule, Dim> rules;
    for (int d = 0; d < Dim; ++d) {
      rules[d] = gauss_legendre(scene.algorithm.gauss_per_cell[d]);
      axis_points_[d] = rules[d].x;
    }
    cell_rule_ = rules[0];
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
        local_.push_back(xi);
        local_w_.push_back(w);
      }
  }
  per_cell_ = static_cast<int>(local_.size());
  if (per_cell_ > max_per_cell)  // the scene caps gauss_per_cell at 10 per axis
    throw std::logic_error("GaussPoints: " + std::to_string(per_cell_) + " Gauss points per cell, at most " +
                           std::to_string(max_per_cell) + " supported");
  const std::size_t n = ncells * per_cell_;
  m_.assign(n, 0.0);
  for (int d = 0; d < Dim; ++d) {
    x_[d].assign(n, 0.0);
    q_[d].assign(n, 0.0);
    fb_[d].assign(n, 0.0);
  }
  for (auto& col : s_) col.assign(n, 0.0);
  cell_of_slot_ = bins_.cells_by_block();
  slot_.assign(ncells, 0);
  for (std::size_t k = 0; k < ncells; ++k) slot_[cell_of_slot_[k]] = static_cast<unsigned>(k);
  for (std::size_t c = 0; c < ncells; ++c) {
    const CellBox<Dim> box = cell_box(c);
    for (int g = 0; g < per_cell_; ++g)
      for (int d = 0; d < Dim; ++d) x_[d][first_point(c) + g] = box.lo[d] + local_[g][d] * h_[d];
  }
  std::array<const double*, Dim> x;
  for (int d = 0; d < Dim; ++d) x[d] = x_[d].data();
  bins_.bin(x, n);  // Gauss points never move: binned once (in storage order, as they are placed)
  // GaussPoints::scatter reads a block's range of the order as whole cells in storage order
  const auto order = bins_.order();
  for (std::size_t k = 0; k < n; ++k)
    if (order[k] != k) throw std::logic_error("GaussPoints: the Gauss points are not stored in their block order");
}

template <int Dim>
MomentumTotals<Dim> GaussPoints<Dim>::sort_by_position(const ParticleView<Dim>& p, const CellBins<Dim>& cells) {
  // cell by cell (the bins are colour-major, so their order is not the cells'), then an insertion sort by x
  // within: particles of a 1D body keep their order almost always, so this is O(n) in practice and stable
  const unsigned* order = cells.order().data();
  sorted_.clear();
  cell_totals_.assign(cells_[0], MomentumTotals<Dim>{});
  for (std::size_t c = 0; c < static_cast<std::size_t>(cells_[0]); ++c) {
    const auto [b, e] = cells.block_range(c);
    for (std::size_t k = b; k < e; ++k) {
      const unsigned ip = order[k];
      double v[Dim];
      for (int d = 0; d < Dim; ++d) v[d] = p.v[d][ip];
      cell_totals_[c].add(p.m[ip], v);
      std::size_t i = sorted_.size();
      sorted_.push_back(ip);
      for (; i > 0 && p.x[0][sorted_[i - 1]] > p.x[0][ip]; --i) sorted_[i] = sorted_[i - 1];
      sorted_[i] = ip;
    }
  }
  return sum_totals(cell_totals_);
}

template <int Dim>
void GaussPoints<Dim>::place_half_span(std::size_t c, int half, double lo, double hi, double* w) {
  const double a = cell_box(c).lo[0] + 0.5 * half * h_[0];
  const std::size_t n = half_rule_.x.size();
  place_clipped(first_point(c) + half * n, half_rule_, a, a + 0.5 * h_[0], lo, hi, w);
}

template <int Dim>
double GaussPoints<Dim>::place_clipped(std::size_t first, const GaussRule& rule, double a, double b, double lo,
                                       double hi, double* w) {
  const double a_in = std::max(a, lo), b_in = std::min(b, hi);
  // the part inside the body gets the whole rule (its points stay in [a, b], inside one cell: the binning holds)
  const bool inside = b_in > a_in;
  for (std::size_t j = 0; j < rule.x.size(); ++j) {
    x_[0][first + j] = inside ? a_in + rule.x[j] * (b_in - a_in) : a + rule.x[j] * (b - a);
    w[j] = inside ? rule.w[j] * (b_in - a_in) : 0.0;
  }
  return inside ? b_in - a_in : 0.0;
}

template <int Dim>
GaussView<Dim> GaussPoints<Dim>::view() const {
  GaussView<Dim> v;
  for (int d = 0; d < Dim; ++d) {
    v.x[d] = x_[d].data();
    v.q[d] = q_[d].data();
    v.fb[d] = fb_[d].data();
  }
  v.m = m_.data();
  for (int c = 0; c < sym_components<Dim>; ++c) v.s[c] = s_[c].data();
  return v;
}

template <int Dim>
ParticleView<Dim> GaussPoints<Dim>::mass_view() {
  ParticleView<Dim> v;
  for (int d = 0; d < Dim; ++d) v.x[d] = x_[d].data();
  v.m = m_.data();
  return v;
}

template class GaussPoints<1>;
template class GaussPoints<2>;

}  // namespace mpm
