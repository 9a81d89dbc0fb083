// The TLS rebuild of the Gauss-point path (engine/gauss_points.hpp): the single-cell bins it reads, the storage
// order of the Gauss points, rebuilds of some of the fields against a rebuild of all, and the momentum-only
// rebuild of MUSL's second P2G against a full rebuild of the same particles.
#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>

#include "engine/cell_bins.hpp"
#include "engine/gauss_points.hpp"
#include "engine/problem.hpp"
#include "engine/scene.hpp"

using namespace mpm;

namespace {

/// Particle columns on [0, 1]² with F = diag(stretch, 1) (J = stretch), as a ParticleView.
struct ParticleColumns {
  std::array<std::vector<double>, 2> x, v;
  std::array<std::vector<double>, 4> F;
  std::array<std::vector<double>, 3> s;
  std::vector<double> m, V0;

  void add(std::array<double, 2> at, std::array<double, 2> velocity, double stretch, std::array<double, 3> stress,
           double mass, double volume) {
    for (int d = 0; d < 2; ++d) {
      x[d].push_back(at[d]);
      v[d].push_back(velocity[d]);
    }
    const std::array<double, 4> f{stretch, 0.0, 0.0, 1.0};
    for (int c = 0; c < 4; ++c) F[c].push_back(f[c]);
    for (int c = 0; c < 3; ++c) s[c].push_back(stress[c]);
    m.push_back(mass);
    V0.push_back(volume);
  }
  std::size_t size() const { return m.size(); }
  ParticleView<2> view() {
    ParticleView<2> p;
    for (int d = 0; d < 2; ++d) {
      p.x[d] = x[d].data();
      p.v[d] = v[d].data();
    }
    for (int c = 0; c < 4; ++c) p.F[c] = F[c].data();
    for (int c = 0; c < 3; ++c) p.s[c] = s[c].data();
    p.m = m.data();
    p.V0 = V0.data();
    return p;
  }
  std::array<const double*, 2> positions() const { return {x[0].data(), x[1].data()}; }
};

/// Random particles on [0, 1]² of a grid of `cells`: 0 to 9 per cell (sparse cells need their neighbours).
struct RandomParticles : ParticleColumns {
  RandomParticles(std::array<int, 2> cells, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int j = 0; j < cells[1]; ++j)
      for (int i = 0; i < cells[0]; ++i) {
        const int count = (i * 7 + j * 3) % 10;
        for (int k = 0; k < count; ++k) {
          const double x0 = (i + u(rng)) / cells[0], x1 = (j + u(rng)) / cells[1];
          const double v0 = u(rng) - 0.5, v1 = u(rng) - 0.5;
          const double stretch = 0.8 + 0.4 * u(rng);
          const double s0 = 1e5 * (u(rng) - 0.5), s1 = 1e5 * (u(rng) - 0.5), s2 = 1e5 * (u(rng) - 0.5);
          add({x0, x1}, {v0, v1}, stretch, {s0, s1, s2}, 0.5 + u(rng), 1.0 / (cells[0] * cells[1] * 9.0));
        }
      }
  }
};

/// Particles binned as a simulation bins them: blocks of 5 cells (the layout of the particle columns) and single
/// cells ranked in the layout's block order.
struct BinnedParticles {
  ParticleColumns particles;
  CellBins<2> layout, by_cell;
  BinnedParticles(std::array<int, 2> cells, ParticleColumns columns)
      : particles(std::move(columns)),
        layout(cells, {1.0, 1.0}, 5),
        by_cell(CellBins<2>::single_cells_in_order_of(layout)) {
    layout.bin(particles.positions(), particles.size());
    by_cell.bin(particles.positions(), particles.size());
  }
};

/// Cells visited by CellBins::for_each_cell_by_block, with how often each was visited.
template <int Dim>
std::vector<int> visits(const CellBins<Dim>& bins, std::size_t ncells) {
  std::vector<int> seen(ncells, 0);
  bins.for_each_cell_by_block([&](std::size_t c) { ++seen[c]; });  // distinct cells: no two writes race
  return seen;
}

}  // namespace

TEST_CASE("single cells in the layout's block order hold the same particles in the same order as colour-major ones",
          "[tls][bins]") {
  const std::array<int, 2> cells{13, 11};  // not a multiple of the block width: partial blocks at the far edges
  RandomParticles particles(cells, 7);
  const std::array<double, 2> length{1.0, 1.0};
  CellBins<2> layout(cells, length, 5);
  CellBins<2> coloured(cells, length, 1);
  CellBins<2> ordered = CellBins<2>::single_cells_in_order_of(layout);
  for (auto* b : {&layout, &coloured, &ordered}) b->bin(particles.positions(), particles.size());

  const std::size_t ncells = 13 * 11;
  std::size_t total = 0;
  for (std::size_t c = 0; c < ncells; ++c) {
    const auto [b0, e0] = coloured.block_range(c);
    const auto [b1, e1] = ordered.block_range(c);
    REQUIRE(e1 - b1 == e0 - b0);
    for (std::size_t k = 0; k < e0 - b0; ++k) CHECK(ordered.order()[b1 + k] == coloured.order()[b0 + k]);
    total += e0 - b0;
  }
  CHECK(total == particles.size());
  const std::vector<int> seen = visits(layout, ncells);
  CHECK(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
  // the visit order is the ordered bins' rank order: visited serially, their ranges follow each other
  std::size_t next = 0;
  std::vector<std::size_t> order_of_visit;
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  layout.for_each_cell_by_block([&](std::size_t c) { order_of_visit.push_back(c); });
  for (const std::size_t c : order_of_visit) {
    const auto [b, e] = ordered.block_range(c);
    CHECK(b == next);
    next = e;
  }
  CHECK(next == particles.size());
  const std::vector<unsigned> by_block = layout.cells_by_block();
  CHECK(std::equal(by_block.begin(), by_block.end(), order_of_visit.begin(), order_of_visit.end()));
  CHECK_THROWS_AS(ordered.for_each_block_coloured([](std::size_t, std::size_t) {}), std::logic_error);
}

namespace {

/// A 2D MUSL-TLS scene on [0, 1]² with `cells` and Taylor degree `degree`.
Scene tls_scene(std::array<int, 2> cells, int degree, const char* basis = "bspline2",
                std::array<int, 2> gauss_per_cell = {2, 2}) {
  const nlohmann::json j = {
      {"dimension", 2},
      {"grid", {{"length", {1.0, 1.0}}, {"cells", {cells[0], cells[1]}}, {"basis", basis}}},
      {"particles", {{"per_cell", {3, 3}}}},
      {"bodies", {{{"box", {{0.0, 0.0}, {1.0, 1.0}}}}}},
      {"material", {{"model", "neo-hookean"}, {"E", 1e6}, {"nu", 0.3}, {"density", 1000.0}}},
      {"algorithm",
       {{"update", "musl"},
        {"mapping", "tls"},
        {"tls_degree", degree},
        {"gauss_per_cell", {gauss_per_cell[0], gauss_per_cell[1]}}}},
      {"time", {{"dt", 1e-5}, {"end", 1e-4}}}};
  return parse_scene(j);
}

/// max |a[g] − b[g]| and max |b[g]| over n values.
struct Difference {
  double diff = 0.0, scale = 0.0;
  void add(const double* a, const double* b, std::size_t n) {
    for (std::size_t g = 0; g < n; ++g) {
      scale = std::max(scale, std::abs(b[g]));
      diff = std::max(diff, std::abs(a[g] - b[g]));
    }
  }
};

}  // namespace

TEST_CASE("Gauss points are stored in the order the coloured scatter visits them", "[tls][bins]") {
  const Scene scene = tls_scene({13, 11}, 1);
  for (const int width : {3, 5, 6}) {  // 3: the narrowest for quadratic B-splines; 5: the particles' bins
    const GaussPoints<2> gauss(scene, width);
    const auto order = gauss.bins().order();
    REQUIRE(order.size() == 13u * 11u * 4u);
    std::size_t out_of_place = 0;
    for (std::size_t k = 0; k < order.size(); ++k) out_of_place += order[k] != k;
    INFO("block width " << width);
    CHECK(out_of_place == 0);
  }
  CHECK(GaussPoints<2>(scene).bins().block_width() == 3);
  CHECK_THROWS_AS(GaussPoints<2>(scene, 2), std::logic_error);  // blocks of one colour would share DOFs
}

TEST_CASE("TLS rebuild of the stress alone, or of the velocity alone, equals a rebuild of both", "[tls][reconstruction]") {
  for (int degree : {1, 2}) {
    const std::array<int, 2> cells{9, 8};
    const Scene scene = tls_scene(cells, degree);
    BinnedParticles binned(cells, RandomParticles(cells, 3 + degree));
    ParticleColumns& particles = binned.particles;
    const CellBins<2>& layout = binned.layout;
    const CellBins<2>& by_cell = binned.by_cell;
    const ParticleView<2> p = particles.view();
    const NoBodyForce body;

    GaussPoints<2> both(scene), stress(scene), velocity(scene);
    const auto t_both = both.rebuild(p, by_cell, layout, body, true, true);       // USL
    const auto t_stress = stress.rebuild(p, by_cell, layout, body, true, false);  // MUSL's first P2G
    const auto t_velocity = velocity.rebuild(p, by_cell, layout, body, false, true);
    CHECK(t_stress.m_abs_v == 0.0);  // no momentum reconstructed: none reported
    for (int d = 0; d < 2; ++d) CHECK(t_velocity.mv[d] == t_both.mv[d]);
    // one density fit and one joint fit per cell against one density fit and one fit of the stress (velocity)
    CHECK(stress.fallbacks() == both.fallbacks());
    CHECK(velocity.fallbacks() == both.fallbacks());
    CHECK(both.fallbacks().neighbour > 0);  // sparse cells were completed from their neighbourhood

    // the columns of a least-squares fit do not depend on each other: equal up to round-off
    const GaussView<2> a = both.view(), s = stress.view(), v = velocity.view();
    const std::size_t n = static_cast<std::size_t>(cells[0]) * cells[1] * 4;  // 2×2 Gauss points per cell
    Difference m, sigma, q;
    m.add(s.m, a.m, n);
    m.add(v.m, a.m, n);
    for (int k = 0; k < 3; ++k) sigma.add(s.s[k], a.s[k], n);
    for (int d = 0; d < 2; ++d) q.add(v.q[d], a.q[d], n);
    INFO("degree " << degree << ": max |Δ ρ̂ω| " << m.diff << " of " << m.scale << ", |Δ σ̂ω| " << sigma.diff
                   << " of " << sigma.scale << ", |Δ ρv̂ω| " << q.diff << " of " << q.scale);
    REQUIRE(m.scale > 0.0);
    REQUIRE(sigma.scale > 0.0);
    REQUIRE(q.scale > 0.0);
    CHECK(m.diff <= 1e-14 * m.scale);
    CHECK(sigma.diff <= 1e-14 * sigma.scale);
    CHECK(q.diff <= 1e-14 * q.scale);
  }
}

TEST_CASE("TLS momentum-only rebuild after a velocity change equals a full rebuild", "[tls][reconstruction]") {
  for (int degree : {1, 2}) {
    const std::array<int, 2> cells{9, 8};
    const Scene scene = tls_scene(cells, degree);
    BinnedParticles binned(cells, RandomParticles(cells, 11 + degree));
    ParticleColumns& particles = binned.particles;
    const CellBins<2>& layout = binned.layout;
    const CellBins<2>& by_cell = binned.by_cell;
    const ParticleView<2> p = particles.view();
    const NoBodyForce body;

    GaussPoints<2> reused(scene), fresh(scene);
    reused.rebuild(p, by_cell, layout, body, true, false);  // MUSL's first P2G: stress, no momentum
    const FallbackCounts first = reused.fallbacks();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (auto& c : particles.v)
      for (double& v : c) v += u(rng);  // g2p-velocity: only the velocities change
    const auto t_reused = reused.rebuild_momentum(p, by_cell, layout, body);
    const auto t_fresh = fresh.rebuild(p, by_cell, layout, body, false, true);

    for (int d = 0; d < 2; ++d) CHECK(t_reused.mv[d] == t_fresh.mv[d]);  // the same sums in the same order
    CHECK(t_reused.m_abs_v == t_fresh.m_abs_v);
    FallbackCounts second = reused.fallbacks();
    second.neighbour -= first.neighbour;
    second.degree -= first.degree;
    second.constant -= first.constant;
    second.empty -= first.empty;
    CHECK(second == fresh.fallbacks());
    CHECK(fresh.fallbacks().neighbour > 0);  // the sparse cells were completed: the kept matrices were used

    // The same operations on the same data, the density from the first rebuild: equal up to round-off.
    const GaussView<2> a = reused.view(), b = fresh.view();
    const std::size_t n = static_cast<std::size_t>(cells[0]) * cells[1] * 4;  // 2×2 Gauss points per cell
    Difference m, q;
    m.add(a.m, b.m, n);
    for (int d = 0; d < 2; ++d) q.add(a.q[d], b.q[d], n);
    INFO("degree " << degree << ": max |Δ ρ̂ω| " << m.diff << " of " << m.scale << ", max |Δ ρv̂ω| " << q.diff
                   << " of " << q.scale);
    REQUIRE(m.scale > 0.0);
    CHECK(m.diff <= 1e-14 * m.scale);
    CHECK(q.diff <= 1e-14 * q.scale);
  }
}

TEST_CASE("TLS rebuild completes a cell whose own fit fails on its conditioning alone from its neighbours' sums",
          "[tls][reconstruction]") {
  // 5×5 cells of 3×3 particles, except the centre cell's 9 on its diagonal: enough of them, but collinear. No
  // cell is sparse, so pass 1 keeps no sums; the centre's neighbourhood fit reads the sums pass 1b takes.
  // Linear fields are reproduced by every fit; with uniform ρ the Gauss points carry σ̂ω / ρ̂ω = σ(x_g) / ρ and
  // ρv̂ω / ρ̂ω = v(x_g), within the bounds of the cell's particles (the limiter does not act).
  const std::array<int, 2> cells{5, 5};
  const double h = 0.2, rho = 1000.0, volume = h * h / 9.0;
  auto stress = [](double x, double y) { return std::array<double, 3>{1e5 * (x + y), -3e4 * (x + y), 5e3 + 2e4 * (x + y)}; };
  auto velocity = [](double x, double y, double scale) {
    return std::array<double, 2>{scale * (0.3 + x + y), scale * (-0.2 - 2.0 * (x + y))};
  };
  ParticleColumns columns;
  for (int j = 0; j < cells[1]; ++j)
    for (int i = 0; i < cells[0]; ++i)
      for (int k = 0; k < 9; ++k) {
        const bool centre = i == 2 && j == 2;
        const double a = centre ? 0.05 + 0.1125 * k : (1 + 2 * (k % 3)) / 6.0;
        const double b = centre ? a : (1 + 2 * (k / 3)) / 6.0;
        const double x = (i + a) * h, y = (j + b) * h;
        columns.add({x, y}, velocity(x, y, 1.0), 1.0, stress(x, y), rho * volume, volume);
      }
  for (int degree : {1, 2}) {
    INFO("degree " << degree);
    BinnedParticles binned(cells, columns);
    const ParticleView<2> p = binned.particles.view();
    const NoBodyForce body;
    GaussPoints<2> gauss(tls_scene(cells, degree), binned.layout.block_width());
    const std::size_t n = 25 * 4;  // 2×2 Gauss points per cell

    gauss.rebuild(p, binned.by_cell, binned.layout, body, true, false);  // MUSL's first P2G: ρ and σ
    // the centre's stress from its neighbourhood, at either degree: the other cells' 9 particles are at least one
    // more than the 3 (degree 1) or 6 (degree 2) Taylor functions, and well spread
    const std::size_t neighbourhood_fits = 1;
    CHECK(gauss.fallbacks().neighbour == neighbourhood_fits);
    CHECK(gauss.fallbacks().constant == 1);  // the centre's density: collinear particles fix no slope
    GaussView<2> g = gauss.view();
    double worst = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const auto exact = stress(g.x[0][k], g.x[1][k]);
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(g.s[c][k] / g.m[k] * rho - exact[c]) / 1e5);
    }
    CHECK(worst < 1e-10);

    // MUSL's second P2G: new velocities, the kept matrices
    for (std::size_t ip = 0; ip < binned.particles.size(); ++ip) {
      const auto v = velocity(binned.particles.x[0][ip], binned.particles.x[1][ip], -2.0);
      for (int d = 0; d < 2; ++d) binned.particles.v[d][ip] = v[d];
    }
    gauss.rebuild_momentum(p, binned.by_cell, binned.layout, body);
    CHECK(gauss.fallbacks().neighbour == 2 * neighbourhood_fits);
    g = gauss.view();
    worst = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const auto exact = velocity(g.x[0][k], g.x[1][k], -2.0);
      for (int d = 0; d < 2; ++d) worst = std::max(worst, std::abs(g.q[d][k] / g.m[k] - exact[d]));
    }
    CHECK(worst < 1e-10);
  }
}

TEST_CASE("TLS limiter: alpha from the extreme deviations equals the minimum over every Gauss point's bound",
          "[tls][reconstruction]") {
  // The reference is the limiter's definition: α_k = min(1, min over the points with dev > 0 of (hi − mean) / dev,
  // min over those with dev < 0 of (lo − mean) / dev), bounds widened to the mean. limited_values takes only the
  // extreme deviations; division is monotone, so they agree up to the round-off of evaluating the fit again here
  // (the same expression; a compiler may contract it into FMAs differently): 1e-14 on values of order 1, where a
  // wrong α differs by order 1.
  constexpr int K = 3;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<TaylorVector<2, 1>, 4> psi;  // 2×2 Gauss points of the reference cell
  const double g = 1.0 / std::sqrt(3.0);
  for (int i = 0; i < 4; ++i) psi[i] = taylor_basis_ref<2, 1>(Vec<2>(i % 2 ? g : -g, i / 2 ? g : -g));
  int limited = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    TaylorFit<2, 1, K> fit;
    for (int i = 0; i < fit.c.size(); ++i) fit.c.data()[i] = u(rng);
    if (trial % 7 == 0) fit.c.row(1).setZero();  // deviations of zero along x
    if (trial % 11 == 0) fit.c.bottomRows(2).setZero();  // a constant: nothing to limit
    Eigen::Matrix<double, K, 1> lo, hi;
    for (int k = 0; k < K; ++k) {
      lo[k] = fit.c(0, k) - 1.5 * std::abs(u(rng));  // sometimes tighter than the fit's range
      hi[k] = fit.c(0, k) + 1.5 * std::abs(u(rng));
      if (trial % 5 == 0) hi[k] = fit.c(0, k) - 0.1;  // the mean outside the samples' bounds
    }
    std::array<Eigen::Matrix<double, K, 1>, 4> values;
    detail::limited_values(fit, lo, hi, std::span<const TaylorVector<2, 1>>(psi), values.data());

    const Eigen::Matrix<double, K, 1> mean = fit.c.row(0).transpose();
    const Eigen::Matrix<double, K, 1> low = lo.cwiseMin(mean), high = hi.cwiseMax(mean);
    for (int k = 0; k < K; ++k) {
      double alpha = 1.0;
      std::array<double, 4> raw;
      for (int p = 0; p < 4; ++p) {
        raw[p] = (fit.c.transpose() * psi[p])[k];
        const double dev = raw[p] - mean[k];
        if (dev > 0) alpha = std::min(alpha, (high[k] - mean[k]) / dev);
        if (dev < 0) alpha = std::min(alpha, (low[k] - mean[k]) / dev);
      }
      limited += alpha < 1.0;
      for (int p = 0; p < 4; ++p) CHECK(std::abs(values[p][k] - (mean[k] + alpha * (raw[p] - mean[k]))) <= 1e-14);
    }
  }
  CHECK(limited > 1000);  // the cases limit often enough to test the bound, not just the identity
}

namespace {

/// The grid sums a scatter writes, sized for a basis of S functions per cell and axis on `cells`.
struct ScatterTargets {
  int stride;
  std::vector<double> m, q0, q1, f0, f1;
  ScatterTargets(std::array<int, 2> cells, int S)
      : stride(grid_stride(cells[0] + S - 1, S)),
        m(static_cast<std::size_t>(stride) * (cells[1] + S), 0.0),
        q0(m),
        q1(m),
        f0(m),
        f1(m) {}
  GridView<2> view() {
    GridView<2> g;
    g.stride1 = stride;
    g.dofs = static_cast<int>(m.size());
    g.m = m.data();
    g.q = {q0.data(), q1.data()};
    g.f = {f0.data(), f1.data()};
    return g;
  }
  std::array<const std::vector<double>*, 5> arrays() const { return {&m, &q0, &q1, &f0, &f1}; }
};

/// GaussPoints::scatter (whole cells, tabulated weights) against scatter_gauss (a stencil per point) after a TLS
/// rebuild of every field, with a body force: every grid sum equal to round-off.
template <int S>
void check_cell_scatter(std::array<int, 2> cells, const char* basis_name, std::array<int, 2> gauss_per_cell) {
  BinnedParticles binned(cells, RandomParticles(cells, 11));
  GaussPoints<2> gauss(tls_scene(cells, 1, basis_name, gauss_per_cell), binned.layout.block_width());
  const UniformBodyForce<2> body{{0.3, -9.81}};
  gauss.rebuild(binned.particles.view(), binned.by_cell, binned.layout, body, true, true);
  const TensorBasis<2, UniformAxis<S>> basis{{UniformAxis<S>(cells[0], 1.0), UniformAxis<S>(cells[1], 1.0)},
                                            {cells[0] + S - 1, cells[1] + S - 1}};
  constexpr ScatterFields all{true, true, true};
  ScatterTargets cell_wise(cells, S), point_wise(cells, S);
  gauss.scatter<all, true, S>(basis, cell_wise.view());
  const unsigned* order = gauss.bins().order().data();
  gauss.bins().for_each_block_serial([&](std::size_t b, std::size_t e) {
    scatter_gauss<all, true, 2, S>(basis, gauss.view(), point_wise.view(), order, b, e);
  });
  for (int k = 0; k < 5; ++k) {
    Difference diff;
    diff.add(cell_wise.arrays()[k]->data(), point_wise.arrays()[k]->data(), point_wise.m.size());
    INFO(basis_name << ", " << cells[0] << "x" << cells[1] << " cells, " << gauss_per_cell[0] << "x"
                    << gauss_per_cell[1] << " Gauss points, grid array " << k);
    CHECK(diff.scale > 0.0);
    CHECK(diff.diff <= 1e-13 * diff.scale);
  }
}

}  // namespace

TEST_CASE("Gauss-point scatter of whole cells from tabulated weights equals a stencil per point", "[tls][scatter]") {
  check_cell_scatter<3>({7, 5}, "bspline2", {2, 2});  // interior and both end span classes
  check_cell_scatter<3>({7, 5}, "bspline2", {3, 2});  // another rule: the run-time point counts
  check_cell_scatter<3>({1, 4}, "bspline2", {2, 3});  // one cell along axis 0: first and last at once
  check_cell_scatter<2>({6, 4}, "linear", {2, 2});
}
