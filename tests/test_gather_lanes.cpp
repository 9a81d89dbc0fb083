// The gather with a particle per vector lane (gather_sums_in_lanes, kernels/transfer.hpp) against the gather by
// stencil rows, on grids whose particles sit in every span class of the open knot vector (first, interior, last
// cell, and a grid of one cell), on its boundary, outside it, and at NaN.
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "kernels/transfer.hpp"

using namespace mpm;

namespace {

/// Particles and a grid with random nodal values, and the gather's outputs.
struct GatherCase {
  static constexpr int S = 3;
  std::array<int, 2> cells;
  std::array<double, 2> length{1.5, 0.75};
  TensorBasis<2, UniformAxis<S>> basis;
  int stride;
  std::vector<double> grid[4];  // a0, a1, v0, v1
  std::vector<double> columns[15];  // x0, x1, X0, X1, v0, v1, F00, F01, F10, F11, s00, s01, s11, m, V0
  std::size_t count = 0;
  std::size_t first_bad = ParticleGuard::none;
  double max_move = 0.0;

  explicit GatherCase(std::array<int, 2> cells_)
      : cells(cells_),
        basis{{UniformAxis<S>(cells_[0], length[0]), UniformAxis<S>(cells_[1], length[1])},
              {cells_[0] + 2, cells_[1] + 2}},
        stride(grid_stride(cells_[0] + 2, S)) {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (auto& g : grid) {
      g.resize(static_cast<std::size_t>(stride) * (cells[1] + 2));
      for (double& value : g) value = unit(random);
    }
    // per axis: every cell, its edges, a point past each end of the grid
    std::vector<double> at[2];
    for (int d = 0; d < 2; ++d) {
      const double h = length[d] / cells[d];
      for (int c = 0; c < cells[d]; ++c)
        for (const double xi : {0.0, 0.13, 0.5, 0.87}) at[d].push_back((c + xi) * h);
      at[d].push_back(length[d]);
      at[d].push_back(length[d] * (1 + 1e-3));
      at[d].push_back(-1e-3 * h);
    }
    for (const double y : at[1])
      for (const double x : at[0]) add_particle(x, y, random);
    add_particle(std::numeric_limits<double>::quiet_NaN(), 0.5 * length[1], random);
  }

  void add_particle(double x, double y, std::mt19937& random) {
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    // (a braced list is evaluated left to right)
    const double values[15] = {x,
                               y,
                               x * 0.9,
                               y * 1.1,
                               unit(random),
                               unit(random),
                               1 + 0.1 * unit(random),
                               0.1 * unit(random),
                               0.1 * unit(random),
                               1 + 0.1 * unit(random),
                               0,
                               0,
                               0,
                               1,
                               1};
    for (int c = 0; c < 15; ++c) columns[c].push_back(values[c]);
    ++count;
  }

  /// Runs gather_g2p with the rows (Isa::baseline) or the lanes (Isa::avx2_fma: the lanes' code, here compiled for
  /// the test's own instruction set).
  template <GatherFields Fields, Isa I>
  void gather() {
    ParticleView<2> p;
    for (int d = 0; d < 2; ++d) {
      p.x[d] = columns[d].data();
      p.X[d] = columns[2 + d].data();
      p.v[d] = columns[4 + d].data();
    }
    for (int c = 0; c < 4; ++c) p.F[c] = columns[6 + c].data();
    for (int c = 0; c < 3; ++c) p.s[c] = columns[10 + c].data();
    p.m = columns[13].data();
    p.V0 = columns[14].data();
    GridView<2> g;
    g.stride1 = stride;
    g.dofs = stride * (cells[1] + 2);
    for (int d = 0; d < 2; ++d) {
      g.a[d] = grid[d].data();
      g.v[d] = grid[2 + d].data();
    }
    ParticleGuard guard;
    guard.hi = {length[0], length[1], 0.0};
    guard.inv_h = {cells[0] / length[0], cells[1] / length[1], 0.0};
    const auto stress = [](const double* F, double* s) {
      s[0] = F[0] - 1.0;
      s[1] = F[1] + F[2];
      s[2] = F[3] - 1.0;
    };
    gather_g2p<Fields, 2, S, I>(basis, p, g, 0, count, 1e-2, stress, guard);
    first_bad = guard.first_bad.load();
    max_move = guard.max_move_cells.load();
  }
};

/// The largest difference of two cases' particle columns, relative to the column's largest finite magnitude; NaN
/// where one is NaN and the other not.
double largest_difference(const GatherCase& a, const GatherCase& b) {
  double worst = 0.0;
  for (int c = 0; c < 15; ++c) {
    double scale = 0.0;
    for (const double value : a.columns[c])
      if (std::isfinite(value)) scale = std::max(scale, std::abs(value));
    for (std::size_t i = 0; i < a.count; ++i) {
      const double x = a.columns[c][i], y = b.columns[c][i];
      if (std::isnan(x) || std::isnan(y)) {
        if (std::isnan(x) != std::isnan(y)) return std::numeric_limits<double>::quiet_NaN();
        continue;
      }
      worst = std::max(worst, std::abs(x - y) / scale);
    }
  }
  return worst;
}

template <GatherFields Fields>
void check_lanes_equal_rows(const char* name) {
  for (const std::array<int, 2> cells : {std::array<int, 2>{7, 5}, std::array<int, 2>{1, 4}}) {
    GatherCase rows(cells), lanes(cells);
    rows.gather<Fields, Isa::baseline>();
    lanes.gather<Fields, Isa::avx2_fma>();
    INFO(name << ", " << cells[0] << " x " << cells[1] << " cells, " << rows.count << " particles");
    const double worst = largest_difference(rows, lanes);
    INFO("largest difference, relative to the column's magnitude: " << worst);
    CHECK(worst <= 1e-14);
    CHECK(lanes.first_bad == rows.first_bad);
    CHECK(lanes.max_move == Approx(rows.max_move).epsilon(1e-14));
    if constexpr (Fields.position || Fields.velocity) CHECK(rows.first_bad != ParticleGuard::none);
  }
}

}  // namespace

TEST_CASE("the gather in vector lanes equals the gather by rows to round-off", "[transfer][lanes]") {
  check_lanes_equal_rows<GatherFields{.velocity = true, .position = true, .deformation = true}>("USL");
  check_lanes_equal_rows<GatherFields{.velocity = false, .position = true, .deformation = true}>("MUSL");
  check_lanes_equal_rows<GatherFields{.velocity = true, .position = false, .deformation = false}>("velocity");
  check_lanes_equal_rows<GatherFields{.velocity = true, .position = true, .deformation = false}>("velocity, position");
  check_lanes_equal_rows<GatherFields{.velocity = false, .position = false, .deformation = true}>("deformation");
  check_lanes_equal_rows<GatherFields{
      .velocity = false, .position = true, .deformation = true, .reference = true}>("reference basis");
  check_lanes_equal_rows<GatherFields{
      .velocity = false, .position = true, .deformation = false, .velocity_from_position = true}>("OTM");
}
