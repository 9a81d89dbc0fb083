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
    : mapping_(scene.algorithm.mapping),
      tls_degree_(scene.algorithm.tls_degree),
      mls_support_(scene.algorithm.mls_support),
      cells_(first_n<Dim>(scene.grid.cells)),
      bins_(cells_, first_n<Dim>(scene.grid.length), 2 * std::max(2, degree_of(scene.grid.basis))) {
  std::size_t ncells = 1;
  for (int d = 0; d < Dim; ++d) {
    h_[d] = scene.grid.length[d] / cells_[d];
    ncells *= cells_[d];
  }
  // tensor-product Gauss–Legendre rule of the unit cell (paper eqs 22–25, thesis eq. 3.3)
  std::array<GaussRule, Dim> rules;
  for (int d = 0; d < Dim; ++d) rules[d] = gauss_legendre(scene.algorithm.gauss_per_cell[d]);
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
  per_cell_ = static_cast<int>(local_.size());
  const std::size_t n = ncells * per_cell_;
  m_.assign(n, 0.0);
  for (int d = 0; d < Dim; ++d) {
    x_[d].assign(n, 0.0);
    q_[d].assign(n, 0.0);
    fb_[d].assign(n, 0.0);
  }
  for (auto& col : s_) col.assign(n, 0.0);
  for (std::size_t c = 0; c < ncells; ++c) {
    const CellBox<Dim> box = cell_box(c);
    for (int g = 0; g < per_cell_; ++g)
      for (int d = 0; d < Dim; ++d) x_[d][c * per_cell_ + g] = box.lo[d] + local_[g][d] * h_[d];
  }
  std::array<const double*, Dim> x;
  for (int d = 0; d < Dim; ++d) x[d] = x_[d].data();
  bins_.bin(x, n);  // Gauss points never move: binned once
}

template <int Dim>
CellBox<Dim> GaussPoints<Dim>::cell_box(std::size_t c) const {
  CellBox<Dim> box;
  for (int d = 0; d < Dim; ++d) {
    const int i = static_cast<int>(c % cells_[d]);
    c /= cells_[d];
    box.lo[d] = i * h_[d];
    box.hi[d] = (i + 1) * h_[d];
  }
  return box;
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
