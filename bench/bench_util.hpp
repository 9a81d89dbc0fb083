#pragma once
// Shared set-up for the benchmark programs (bench/ only; not engine code): thread limits, a 2D particle set
// binned like the engine bins it, and a plain grid. Everything here runs outside the timed loops.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "engine/cell_bins.hpp"
#include "engine/particle_store.hpp"
#include "kernels/stencil.hpp"
#include "kernels/views.hpp"

namespace mpm_bench {

/// Limits TBB to `n` threads for the lifetime of the returned object (use as `auto gc = limit_threads(n);`).
inline tbb::global_control limit_threads(int n) {
  return tbb::global_control(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(n));
}

/// Cells per axis for a nominal particle count: `per_axis` x `per_axis` particles per cell (default 2x2) on an
/// n x n grid.
inline int cells_for_2d(std::int64_t particles, int per_axis = 2) {
  const double per_cell = static_cast<double>(per_axis) * per_axis;
  return std::max(1, static_cast<int>(std::lround(std::sqrt(static_cast<double>(particles) / per_cell))));
}

/// Grid arrays of one 2D field set (the GridState of the engine without the fixed flags).
struct Grid2D {
  int stride1 = 0, dofs = 0;
  std::vector<double> m;
  std::array<std::vector<double>, 2> q, f, v, a;

  /// Quadratic B-splines: rows carry the ghost column of the kernels' padding lane (kernels/stencil.hpp).
  explicit Grid2D(int functions_per_axis)
      : stride1(mpm::grid_stride(functions_per_axis, 3)), dofs(stride1 * functions_per_axis) {
    m.assign(dofs, 0.0);
    for (int d = 0; d < 2; ++d)
      for (auto* x : {&q[d], &f[d], &v[d], &a[d]}) x->assign(dofs, 0.0);
  }
  mpm::GridView<2> view() {
    mpm::GridView<2> g;
    g.stride1 = stride1;
    g.dofs = dofs;
    g.m = m.data();
    for (int d = 0; d < 2; ++d) {
      g.q[d] = q[d].data();
      g.f[d] = f[d].data();
      g.v[d] = v[d].data();
      g.a[d] = a[d].data();
    }
    return g;
  }
  /// The arrays a P2G of mass, momentum and force writes.
  std::array<std::vector<double>*, 5> scatter_targets() { return {&m, &q[0], &q[1], &f[0], &f[1]}; }
};

/// A 2D particle set on [0,1]^2 with `cells` x `cells` cells, 2x2 particles per cell (sub-cell centres with a
/// small jitter), random small velocities, F near identity and a non-zero stress; sorted into block order once
/// (as Simulation::step does every 16 steps), so particle index order is block order.
struct ParticleSet2D {
  int cells;
  std::size_t n;
  mpm::ParticleStore<2> store;
  mpm::CellBins<2> bins;
  mpm::TensorBasis<2, mpm::UniformAxis<3>> basis;

  static mpm::FieldSet fields() {
    mpm::FieldSet f;
    using mpm::Field;
    f.add(Field::position).add(Field::velocity).add(Field::deformation).add(Field::stress);
    f.add(Field::mass).add(Field::volume0);
    return f;
  }

  explicit ParticleSet2D(int cells_)
      : cells(cells_),
        n(static_cast<std::size_t>(4) * cells_ * cells_),
        store(n, fields()),
        bins({cells_, cells_}, {1.0, 1.0}, mpm::CellBins<2>::block_width_for(4, 1)),  // the engine's, quadratic
        basis{{mpm::UniformAxis<3>(cells_, 1.0), mpm::UniformAxis<3>(cells_, 1.0)}, {cells_ + 2, cells_ + 2}} {
    using mpm::Field;
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> jitter(-0.1, 0.1), u(-1.0, 1.0);
    const double h = 1.0 / cells;
    auto x0 = store.column(Field::position, 0), x1 = store.column(Field::position, 1);
    std::size_t p = 0;
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i)
        for (int b = 0; b < 2; ++b)
          for (int a = 0; a < 2; ++a, ++p) {
            x0[p] = (i + 0.25 + 0.5 * a + jitter(rng) * 0.5) * h;
            x1[p] = (j + 0.25 + 0.5 * b + jitter(rng) * 0.5) * h;
          }
    // seeded row-major; bin_and_sort() below puts them into the engine's colour-major block order
    for (int d = 0; d < 2; ++d)
      for (auto& v : store.column(Field::velocity, d)) v = 0.1 * u(rng);
    auto F = [&](int c) { return store.column(Field::deformation, c); };
    for (std::size_t k = 0; k < n; ++k) {
      F(0)[k] = 1.0 + 0.01 * u(rng);
      F(1)[k] = 0.01 * u(rng);
      F(2)[k] = 0.01 * u(rng);
      F(3)[k] = 1.0 + 0.01 * u(rng);
    }
    for (int c = 0; c < 3; ++c)
      for (auto& s : store.column(Field::stress, c)) s = 1e3 * u(rng);
    const double V = h * h / 4.0;
    for (auto& m : store.column(Field::mass)) m = 1000.0 * V;
    for (auto& v : store.column(Field::volume0)) v = V;
    bin_and_sort();
  }

  void bin_and_sort() {
    std::array<const double*, 2> x{store.column(mpm::Field::position, 0).data(),
                                   store.column(mpm::Field::position, 1).data()};
    bins.bin(x, n);
    store.permute(bins.order());
    bins.adopt_order();
  }
  int functions() const { return cells + 2; }
};

/// Largest |a - b| over the arrays, relative to the largest |b|.
inline double max_rel_diff(const std::vector<double>& a, const std::vector<double>& b) {
  double diff = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    diff = std::max(diff, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return scale > 0 ? diff / scale : diff;
}

}  // namespace mpm_bench
