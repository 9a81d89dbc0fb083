// The P2G of the 2D quadratic fast path by cell moments (scatter_p2g with CellMomentScatter, kernels/cell_moments.hpp)
// against the P2G by stencil rows of every particle (scatter_rows), for every combination of grid sums a scheme
// scatters, with and without a body force, particles in every span class (first, interior, last cell, a grid of one
// cell), on the grid's boundary and outside it, in runs of one cell and interleaved across cells; and MUSL's fused
// velocity and momentum pass of AVX2 code (rows as GCC vectors) against the same pass by stencil rows.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "kernels/transfer.hpp"

using namespace mpm;

namespace {

/// A body force per unit mass that differs per particle: b = (1 + i, 2 − i / 10).
struct IndexBodyForce {
  static constexpr bool active = true;
  template <int Dim, Isa = Isa::baseline>
  void at_batch(const unsigned* index, std::size_t count, std::array<double, Dim>* out) const {
    for (std::size_t k = 0; k < count; ++k) out[k] = {1.0 + index[k], 2.0 - 0.1 * index[k]};
  }
};

struct ScatterCase {
  static constexpr int S = 3;
  std::array<int, 2> cells;
  std::array<double, 2> length{1.5, 0.75};
  TensorBasis<2, UniformAxis<S>> basis;
  int stride;
  std::vector<double> columns[14];  // x0, x1, v0, v1, F00, F01, F10, F11, s00, s01, s11, m, V0, unused
  std::vector<unsigned> order;

  ScatterCase(std::array<int, 2> cells_, bool interleaved)
      : cells(cells_),
        basis{{UniformAxis<S>(cells_[0], length[0]), UniformAxis<S>(cells_[1], length[1])},
              {cells_[0] + 2, cells_[1] + 2}},
        stride(grid_stride(cells_[0] + 2, S)) {
    std::mt19937 random(11);
    std::uniform_real_distribution<double> unit(-1.0, 1.0), inside(0.0, 1.0);
    const double h[2] = {length[0] / cells[0], length[1] / cells[1]};
    // five particles per cell, cell by cell, then points on and past the boundary
    for (int j = 0; j < cells[1]; ++j)
      for (int i = 0; i < cells[0]; ++i)
        for (int k = 0; k < 5; ++k) add({(i + inside(random)) * h[0], (j + inside(random)) * h[1]}, random);
    for (const double x : {0.0, length[0], length[0] * (1 + 1e-3), -1e-3 * h[0]})
      for (const double y : {0.0, 0.4 * length[1], length[1], -2e-3 * h[1]}) add({x, y}, random);
    order.resize(columns[0].size());
    std::iota(order.begin(), order.end(), 0u);
    if (interleaved) std::shuffle(order.begin(), order.end(), random);
  }

  void add(std::array<double, 2> x, std::mt19937& random) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    const double values[14] = {x[0],         x[1],         unit(random),     unit(random), 1 + 0.1 * unit(random),
                               0.1 * unit(random), 0.1 * unit(random), 1 + 0.1 * unit(random), unit(random),
                               unit(random), unit(random), 1 + 0.5 * unit(random), 1 + 0.5 * unit(random), 0};
    for (int c = 0; c < 14; ++c) columns[c].push_back(values[c]);
  }

  ParticleView<2> particles() {
    ParticleView<2> p;
    for (int d = 0; d < 2; ++d) {
      p.x[d] = columns[d].data();
      p.v[d] = columns[2 + d].data();
    }
    for (int c = 0; c < 4; ++c) p.F[c] = columns[4 + c].data();
    for (int c = 0; c < 3; ++c) p.s[c] = columns[8 + c].data();
    p.m = columns[11].data();
    p.V0 = columns[12].data();
    return p;
  }

  /// Grid sums m, q0, q1, f0, f1 (stride × (cells1 + 2) each) of scatter_p2g.
  template <ScatterFields Fields, class Body>
  std::array<std::vector<double>, 5> scatter(const Body& body) {
    std::array<std::vector<double>, 5> grid;
    for (auto& g : grid) g.assign(static_cast<std::size_t>(stride) * (cells[1] + 2), 0.0);
    // Isa::avx2_fma: the moments' code, here compiled for the test's own instruction set
    scatter_p2g<Fields, 2, S, Isa::avx2_fma>(basis, particles(), view(grid), order.data(), 0, order.size(), body);
    return grid;
  }

  /// The same sums by the stencil rows of every particle, in the same order.
  template <ScatterFields Fields, class Body>
  std::array<std::vector<double>, 5> scatter_by_rows(const Body& body) {
    std::array<std::vector<double>, 5> grid;
    for (auto& g : grid) g.assign(static_cast<std::size_t>(stride) * (cells[1] + 2), 0.0);
    const ParticleView<2> p = particles();
    for (const unsigned ip : order) {
      std::array<double, 2> b{};
      if constexpr (Body::active) body.template at_batch<2>(&ip, 1, &b);
      const double J = p.F[0][ip] * p.F[3][ip] - p.F[1][ip] * p.F[2][ip], V = J * p.V0[ip];
      const double mv[2] = {p.m[ip] * p.v[0][ip], p.m[ip] * p.v[1][ip]};
      const double Vsig[2][2] = {{V * p.s[0][ip], V * p.s[1][ip]}, {V * p.s[1][ip], V * p.s[2][ip]}};
      const double mb[2] = {p.m[ip] * b[0], p.m[ip] * b[1]};
      scatter_rows<Fields>(stencil_of<2, S>(basis, p.x, ip), view(grid), p.m[ip], mv, Vsig, mb);
    }
    return grid;
  }

  GridView<2> view(std::array<std::vector<double>, 5>& grid) const {
    GridView<2> g;
    g.stride1 = stride;
    g.dofs = static_cast<int>(grid[0].size());
    g.m = grid[0].data();
    for (int d = 0; d < 2; ++d) {
      g.q[d] = grid[1 + d].data();
      g.f[d] = grid[3 + d].data();
    }
    return g;
  }
};

/// The largest difference of two fields, and the largest magnitude of the second.
std::pair<double, double> largest_difference(const std::vector<double>& a, const std::vector<double>& b) {
  double worst = 0.0, scale = 0.0;
  for (std::size_t i = 0; i < b.size(); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
    scale = std::max(scale, std::abs(b[i]));
  }
  return {worst, scale};
}

template <ScatterFields Fields, class Body>
void check_moments_equal_rows(const char* name, const Body& body) {
  for (const std::array<int, 2> cells : {std::array<int, 2>{7, 5}, std::array<int, 2>{1, 4}})
    for (const bool interleaved : {false, true}) {
      ScatterCase c(cells, interleaved);
      const auto moments = c.scatter<Fields>(body), rows = c.scatter_by_rows<Fields>(body);
      for (int field = 0; field < 5; ++field) {
        INFO(name << ", " << cells[0] << " x " << cells[1] << " cells, " << (interleaved ? "interleaved" : "by cell")
                  << ", grid field " << field);
        const auto [worst, scale] = largest_difference(moments[field], rows[field]);
        const bool scattered = field == 0 ? Fields.mass : field < 3 ? Fields.momentum : Fields.force;
        CHECK((scale > 0.0) == scattered);  // the field is scattered or left alone by both
        INFO("largest difference, relative to the field's magnitude: " << worst / scale);
        CHECK(worst <= 1e-14 * scale);
      }
    }
}

}  // namespace

TEST_CASE("the scatter by cell moments equals the scatter by stencil rows to round-off", "[transfer][moments]") {
  const NoBodyForce none;
  const IndexBodyForce body;
  check_moments_equal_rows<ScatterFields{.mass = true, .momentum = true, .force = true}>("USL", none);
  check_moments_equal_rows<ScatterFields{.mass = true, .momentum = true, .force = true}>("USL, body force", body);
  check_moments_equal_rows<ScatterFields{.mass = true, .momentum = false, .force = true}>("MUSL", none);
  check_moments_equal_rows<ScatterFields{.mass = true, .momentum = false, .force = true}>("MUSL, body force", body);
  check_moments_equal_rows<ScatterFields{.mass = false, .momentum = true, .force = false}>("momentum", none);
  check_moments_equal_rows<ScatterFields{.mass = true, .momentum = true, .force = false}>("USF", none);
  check_moments_equal_rows<ScatterFields{.mass = false, .momentum = false, .force = true}>("force", body);
}

TEST_CASE("MUSL's fused velocity and momentum pass of AVX2 code equals the pass by stencil rows",
          "[transfer][moments]") {
  for (const std::array<int, 2> cells : {std::array<int, 2>{7, 5}, std::array<int, 2>{1, 4}})
    for (const bool interleaved : {false, true}) {
      INFO(cells[0] << " x " << cells[1] << " cells, " << (interleaved ? "interleaved" : "by cell"));
      ScatterCase vector(cells, interleaved), rows(cells, interleaved);
      std::mt19937 random(5);
      std::uniform_real_distribution<double> unit(-1.0, 1.0);
      std::vector<double> a[2];
      for (auto& ad : a) {
        ad.resize(static_cast<std::size_t>(vector.stride) * (cells[1] + 2));
        for (double& value : ad) value = unit(random);
      }
      // the grid's momenta and the totals; the particles' velocities change in place
      const auto run = [&](ScatterCase& c, auto isa) {
        std::array<std::vector<double>, 5> grid;
        for (auto& g : grid) g.assign(a[0].size(), 0.0);
        GridView<2> g = c.view(grid);
        g.a = {a[0].data(), a[1].data()};
        const auto totals = advance_velocity_scatter_momentum<2, ScatterCase::S, decltype(isa)::value>(
            c.basis, c.particles(), g, c.order.data(), 0, c.order.size(), 0.25);
        return std::pair{grid, totals};
      };
      // Isa::avx2_fma: the vector rows' code, here compiled for the test's own instruction set
      const auto [grid_vector, totals_vector] = run(vector, IsaTag<Isa::avx2_fma>{});
      const auto [grid_rows, totals_rows] = run(rows, IsaTag<Isa::baseline>{});
      for (int d = 0; d < 2; ++d) {
        INFO("axis " << d);
        const auto [v_worst, v_scale] = largest_difference(vector.columns[2 + d], rows.columns[2 + d]);
        CHECK(v_worst <= 1e-14 * v_scale);
        const auto [q_worst, q_scale] = largest_difference(grid_vector[1 + d], grid_rows[1 + d]);
        CHECK(q_scale > 0.0);
        CHECK(q_worst <= 1e-14 * q_scale);
        CHECK(totals_vector.mv[d] == Approx(totals_rows.mv[d]).epsilon(1e-14));
      }
      CHECK(totals_vector.m_abs_v == Approx(totals_rows.m_abs_v).epsilon(1e-14));
      for (const int field : {0, 3, 4}) CHECK(largest_difference(grid_vector[field], grid_rows[field]).second == 0.0);
    }
}
