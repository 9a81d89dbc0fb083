#include "engine/mesh_simulation.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <random>
#include <type_traits>

#include <tbb/enumerable_thread_specific.h>

#include "engine/deterministic_sum.hpp"
#include "engine/parallel_over.hpp"
#include "engine/triangle_tls.hpp"

namespace mpm {

namespace {

constexpr std::size_t particle_grain = 2048;  // particles per task of the gather loops
constexpr std::size_t element_grain = 16;     // triangles per task of a colour's scatter

/// Points of a triangle with corners (0,0), (1,0), (0,1) in reference coordinates, N = k², 3k² or 6k² of them, each
/// the centroid of one of N congruent (within each part) sub-triangles of equal area: the triangle is split into 1,
/// 3 (at the centroid) or 6 (along the medians) parts of equal area, each refined regularly into k² triangles.
std::vector<std::array<double, 2>> uniform_points_in_triangle(int n) {
  int parts = 0, k = 0;
  for (int s : {1, 3, 6}) {
    const int r = static_cast<int>(std::lround(std::sqrt(static_cast<double>(n) / s)));
    if (s * r * r == n) {
      parts = s;
      k = r;
      break;
    }
  }
  using P = std::array<double, 2>;
  const P c{1.0 / 3, 1.0 / 3}, v[3] = {{0, 0}, {1, 0}, {0, 1}};
  std::vector<std::array<P, 3>> pieces;
  if (parts == 1) pieces.push_back({v[0], v[1], v[2]});
  for (int j = 0; j < 3 && parts > 1; ++j) {
    const P &a = v[j], &b = v[(j + 1) % 3];
    const P mid{(a[0] + b[0]) / 2, (a[1] + b[1]) / 2};
    if (parts == 3) pieces.push_back({c, a, b});
    else pieces.insert(pieces.end(), {{c, a, mid}, {c, mid, b}});
  }
  std::vector<P> out;
  for (const auto& piece : pieces) {
    const auto at = [&](double u, double w) { return point_at(piece[0], piece[1], piece[2], u, w); };
    for (int j = 0; j < k; ++j)
      for (int i = 0; i + j < k; ++i) {
        out.push_back(at((i + 1.0 / 3) / k, (j + 1.0 / 3) / k));                      // upward sub-triangle
        if (i + j < k - 1) out.push_back(at((i + 2.0 / 3) / k, (j + 2.0 / 3) / k));  // downward
      }
  }
  return out;
}

/// The parts of triangle e that particles fill uniformly: the triangle itself, or for Powell–Sabin splines the six
/// sub-triangles of its split. The splines are quadratic on each sub-triangle only: particles spread over the whole
/// triangle integrate the gradients of the spline with an error that grows as 1/h (the interior force of a constant
/// stress does not vanish); with the particles of each sub-triangle at its sub-centroids it is exact at the start.
template <class B>
std::vector<std::array<Point2, 3>> parts_of(const B& basis, const TriangleMesh& mesh, std::size_t e) {
  if constexpr (std::is_same_v<B, PowellSabinBasis>) {
    const auto six = basis.split(e);
    return {six.begin(), six.end()};
  } else {
    const auto& t = mesh.triangle(e);
    return {{mesh.nodes()[t[0]], mesh.nodes()[t[1]], mesh.nodes()[t[2]]}};
  }
}

/// Particles of every body, `particles.per_cell[0]` per triangle, shared equally by its parts (parts_of): uniform
/// sub-triangle centroids, or random with the scene's seed; kept where they fall inside a body's box.
template <class B>
Seeds<2> seed_triangles(const Scene& scene, const TriangleMesh& mesh, const B& basis, const Problem<2>& problem) {
  Seeds<2> s;
  const int parts = std::is_same_v<B, PowellSabinBasis> ? 6 : 1;
  const int n = scene.particles.per_cell[0] / parts;
  const bool random = scene.particles.layout == Layout::random;
  const auto pattern = random ? std::vector<std::array<double, 2>>{} : uniform_points_in_triangle(n);
  std::mt19937_64 rng(scene.particles.seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const auto bodies = problem.bodies();
  for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
    for (const auto& [a, b, c] : parts_of(basis, mesh, e)) {
      const double V = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) / n;
      for (int k = 0; k < n; ++k) {
        std::array<double, 2> r;
        if (random) {
          r = {u01(rng), u01(rng)};
          if (r[0] + r[1] > 1) r = {1 - r[0], 1 - r[1]};  // the square's upper half folded onto the triangle
        } else {
          r = pattern[k];
        }
        const Point2 x = point_at(a, b, c, r[0], r[1]);
        for (const auto& body : bodies)
          if (x[0] >= body.lo[0] && x[0] < body.hi[0] && x[1] >= body.lo[1] && x[1] < body.hi[1]) {
            s.x.push_back(x);
            s.V0.push_back(V);
            s.m.push_back(V * body.material.density);
            s.v.push_back(body.velocity(x));
            break;
          }
      }
    }
  return s;
}

}  // namespace

MeshSimulation::MeshSimulation(const Scene& scene)
    : scene_(scene),
      problem_(make_problem<2>(scene)),
      material_(make_material(scene.material)),
      basis_(scene.grid.basis == Basis::powell_sabin
                 ? std::variant<TriangleP1, PowellSabinBasis>(std::in_place_type<PowellSabinBasis>, mesh())
                 : std::variant<TriangleP1, PowellSabinBasis>(std::in_place_type<TriangleP1>, mesh())),
      store_(0, FieldSet{}) {
  check_body_materials<2>(scene, problem_->bodies());
  const Seeds<2> seeds =
      std::visit([&](const auto& basis) { return seed_triangles(scene, mesh(), basis, *problem_); }, basis_);
  store_ = store_from_seeds(seeds, *problem_, scene.algorithm.update);
  particle_mass_ = deterministic_sum(seeds.m.size(), [&](std::size_t p) { return seeds.m[p]; });
  empty_mass_ = 1e-12 * *std::min_element(seeds.m.begin(), seeds.m.end());
  dt_ = time_step_for(scene, critical_step());
  steps_total_ = count_steps(scene, dt_);
  if (scene.time.start == TimeStart::staggered) start_staggered(store_, *problem_, dt_);

  const std::size_t functions = std::visit([](const auto& b) { return b.function_count(); }, basis_);
  grid_.m.assign(functions, 0.0);
  for (int d = 0; d < 2; ++d) {
    for (auto* a : {&grid_.q[d], &grid_.f[d], &grid_.v[d], &grid_.a[d]}) a->assign(functions, 0.0);
    grid_.fixed[d].assign(functions, 0);
  }
  if (scene.algorithm.mass != MassMatrix::lumped) {
    std::visit([&](const auto& b) { mass_matrix_.emplace(mesh(), b); }, basis_);
    mass_solver_.emplace(static_cast<int>(functions));
  }
  for (int side : scene.fixed_sides)
    for (std::size_t f = 0; f < functions; ++f)
      if (std::visit([&](const auto& b) { return b.touches_side(f, side); }, basis_)) grid_.fixed[side / 2][f] = 1;

  const bool tls = scene.algorithm.mapping == Mapping::tls;
  const std::string rebuild = tls ? "tls-rebuild+" : "";
  const std::string force = rebuild + (problem_->has_body_force() ? "p2g-force+body-force" : "p2g-force");
  if (scene.algorithm.update == Update::usl)
    pipeline_ = {"locate", rebuild + "p2g-mass-momentum", force, "grid-acceleration", "grid-velocity",
                 "g2p-velocity-position-deformation", "stress"};
  else
    pipeline_ = {"locate", rebuild + "p2g-mass", force, "grid-acceleration", "g2p-velocity",
                 rebuild + "p2g-momentum", "grid-velocity", "g2p-position-deformation", "stress"};
  element_.assign(store_.size(), -1);
}

MeshSimulation::~MeshSimulation() = default;

CriticalStep MeshSimulation::critical_step() const {
  // the consistent mass: P1's factor, the smallest of consistent_mass_step_factor (Powell–Sabin's is not derived)
  const double kappa = scene_.algorithm.mass == MassMatrix::consistent ? consistent_mass_step_factor(Basis::linear, 2) : 1.0;
  return critical_step_of(store_, material_, mesh().min_height(), kappa);
}

void MeshSimulation::load_state(const SimulationState& state) {
  load_particle_columns(store_, state, *problem_);
  step_ = state.step;
  time_ = state.time;
  conservation_ = state.conservation;
}

double MeshSimulation::external_power() const {
  return body_force_power<2>(store_, *problem_, time_);
}

/// Each particle's triangle (the mesh's bucket grid), then the particles of each triangle in index order.
void MeshSimulation::locate_particles() {
  const auto x = store_.column(Field::position, 0), y = store_.column(Field::position, 1);
  const std::size_t n = store_.size();
  parallel_over(n, particle_grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) element_[p] = mesh().locate({x[p], y[p]}, element_[p]);
  });
  const auto lost = std::find(element_.begin(), element_.end(), -1);
  if (lost != element_.end())
    raise_unstable_particle(store_, lost - element_.begin(), step_ + 1, time_ + dt_, "locate", true, "mesh");
  element_start_.assign(mesh().triangle_count() + 1, 0);
  for (int e : element_) ++element_start_[e + 1];
  for (std::size_t e = 0; e < mesh().triangle_count(); ++e) element_start_[e + 1] += element_start_[e];
  by_element_.resize(n);
  std::vector<int> next(element_start_.begin(), element_start_.end() - 1);
  for (std::size_t p = 0; p < n; ++p) by_element_[next[element_[p]]++] = static_cast<int>(p);
}

void MeshSimulation::check_mass() {
  const double grid_mass = deterministic_sum(grid_.m.size(), [&](std::size_t i) { return grid_.m[i]; });
  conservation_.mass_rel_max = std::max(conservation_.mass_rel_max, std::abs(grid_mass - particle_mass_) / particle_mass_);
}

void MeshSimulation::check_momentum() {
  const auto m = store_.column(Field::mass);
  const auto v0 = store_.column(Field::velocity, 0), v1 = store_.column(Field::velocity, 1);
  const double m_abs_v = deterministic_sum(store_.size(), [&](std::size_t p) { return m[p] * std::hypot(v0[p], v1[p]); });
  if (m_abs_v == 0.0) return;
  double worst = 0.0;
  for (int d = 0; d < 2; ++d) {
    const auto v = d == 0 ? v0 : v1;
    const double particles = deterministic_sum(store_.size(), [&](std::size_t p) { return m[p] * v[p]; });
    const double grid = deterministic_sum(grid_.q[d].size(), [&](std::size_t i) { return grid_.q[d][i]; });
    worst = std::max(worst, std::abs(grid - particles) / m_abs_v);
  }
  conservation_.momentum_rel_max = std::max(conservation_.momentum_rel_max, worst);
}

/// One step's kernels for one basis, material and body force (thesis Algorithms 1 and 2 on the mesh).
template <class B, class M, class F>
class MeshSimulation::Step {
 public:
  static constexpr int K = B::per_element;

  Step(MeshSimulation& sim, const B& basis, const M& material, const F& body, double dt)
      : sim_(sim), basis_(basis), material_(material), body_(body), dt_(dt), pv_(sim.store_.view()) {}

  /// Thesis Algorithm 1 (USL).
  void usl() {
    clear(true, true, true);
    scatter(true, true, true);
    sim_.check_mass();
    sim_.check_momentum();
    grid_update(true, true);
    gather(true, true);
  }

  /// Thesis Algorithm 2 (MUSL): the velocities mapped back from the updated particle momenta.
  void musl() {
    clear(true, false, true);
    scatter(true, false, true);
    sim_.check_mass();
    grid_update(true, false);
    gather(true, false);
    clear(false, true, false);
    scatter(false, true, false);
    sim_.check_momentum();
    grid_update(false, true);
    gather(false, true);
  }

 private:
  void clear(bool mass, bool momentum, bool force) {
    MeshGrid& g = sim_.grid_;
    if (mass) std::fill(g.m.begin(), g.m.end(), 0.0);
    for (int d = 0; d < 2; ++d) {
      if (momentum) std::fill(g.q[d].begin(), g.q[d].end(), 0.0);
      if (force) std::fill(g.f[d].begin(), g.f[d].end(), 0.0);
    }
  }

  /// g(triangle) for every triangle, colour by colour: the triangles of one colour share no function, so g may add
  /// to their functions' entries without locks, and every sum is formed in the same order on any thread count.
  template <class G>
  void for_each_triangle_coloured(G&& g) const {
    const TriangleMesh& mesh = sim_.mesh();
    for (int c = 0; c < mesh.colours(); ++c) {
      const int first = mesh.colour_start(c), last = mesh.colour_start(c + 1);
      parallel_over(last - first, element_grain, [&](std::size_t b, std::size_t e) {
        for (std::size_t k = first + b; k < first + e; ++k) g(mesh.elements_by_colour()[k]);
      });
    }
  }

  /// P2G, triangle by triangle over the colouring.
  void scatter(bool mass, bool momentum, bool force) {
    const bool tls = sim_.scene_.algorithm.mapping == Mapping::tls;
    tbb::enumerable_thread_specific<FallbackCounts> counts;
    for_each_triangle_coloured([&](int element) {
      if (tls) {
        if constexpr (std::is_same_v<B, TriangleP1>) scatter_tls(element, mass, momentum, force, counts.local());
        if (force && F::active) scatter_direct(element, false, false, true, false);
      } else {
        scatter_direct(element, mass, momentum, force);
      }
    });
    if (mass || force)  // each fit is counted once per step, at the step's first scatter
      for (const auto& c : counts) {
        sim_.fallbacks_.neighbour += c.neighbour;
        sim_.fallbacks_.degree += c.degree;
        sim_.fallbacks_.constant += c.constant;
      }
  }

  template <class G>
  void for_particles_of(int element, G&& g) const {
    for (int k = sim_.element_start_[element]; k < sim_.element_start_[element + 1]; ++k) g(sim_.by_element_[k]);
  }

  /// The particles as integration points (thesis eqs 2.30–2.33); without `internal`, of the force only the body
  /// force, which stays at the particles with the TLS mapping.
  void scatter_direct(int element, bool mass, bool momentum, bool force, bool internal = true) {
    MeshGrid& g = sim_.grid_;
    std::array<int, K> idx;
    std::array<double, K> w;
    std::array<Point2, K> grad;
    for_particles_of(element, [&](std::size_t p) {
      basis_.evaluate(element, {pv_.x[0][p], pv_.x[1][p]}, idx, w, grad);
      const double m = pv_.m[p];
      const double J = pv_.F[0][p] * pv_.F[3][p] - pv_.F[1][p] * pv_.F[2][p];
      const double V = J * pv_.V0[p];
      const double s00 = internal ? pv_.s[0][p] : 0.0, s01 = internal ? pv_.s[1][p] : 0.0,
                   s11 = internal ? pv_.s[2][p] : 0.0;
      std::array<double, 2> b{};
      if constexpr (F::active)
        if (force) b = body_.template at<2>(p);
      for (int k = 0; k < K; ++k) {
        const int i = idx[k];
        if (mass) g.m[i] += w[k] * m;
        if (momentum)
          for (int d = 0; d < 2; ++d) g.q[d][i] += w[k] * m * pv_.v[d][p];
        if (force) {
          g.f[0][i] += -V * (s00 * grad[k][0] + s01 * grad[k][1]) + w[k] * m * b[0];
          g.f[1][i] += -V * (s01 * grad[k][0] + s11 * grad[k][1]) + w[k] * m * b[1];
        }
      }
    });
  }

  /// The TLS fits of the triangle (triangle_tls.hpp), integrated by its Gauss rule (thesis eqs 6.19–6.20).
  void scatter_tls(int element, bool mass, bool momentum, bool force, FallbackCounts& counts) {
    const TriangleMesh& mesh = sim_.mesh();
    std::vector<TriangleSample>& own = own_.local();
    std::vector<TriangleSample>& near = near_.local();
    own.clear();
    near.clear();
    std::array<double, 3> totals{};
    const auto sample = [&](std::size_t p) {
      const auto l = mesh.barycentric(element, {pv_.x[0][p], pv_.x[1][p]});
      const double J = pv_.F[0][p] * pv_.F[3][p] - pv_.F[1][p] * pv_.F[2][p];
      const double rho = pv_.m[p] / (J * pv_.V0[p]);
      return TriangleSample{l[1], l[2], {rho, rho * pv_.v[0][p], rho * pv_.v[1][p], pv_.s[0][p], pv_.s[1][p], pv_.s[2][p]}};
    };
    for_particles_of(element, [&](std::size_t p) {
      own.push_back(sample(p));
      totals[0] += pv_.m[p];
      totals[1] += pv_.m[p] * pv_.v[0][p];
      totals[2] += pv_.m[p] * pv_.v[1][p];
    });
    if (own.empty()) return;
    for (int k = 0; k < 3; ++k)
      if (const int f = mesh.neighbour(element, k); f >= 0) for_particles_of(f, [&](std::size_t p) { near.push_back(sample(p)); });
    const TriangleFields fit = fit_triangle(own, near, totals, mesh.area(element), sim_.scene_.algorithm.tls_degree, counts);
    MeshGrid& g = sim_.grid_;
    std::array<int, K> idx;
    std::array<double, K> w;
    std::array<Point2, K> grad;
    const double area = mesh.area(element);
    for (int q = 0; q < TriangleGauss::points; ++q) {
      const auto& t = mesh.triangle(element);
      const Point2 x = point_at(mesh.nodes()[t[0]], mesh.nodes()[t[1]], mesh.nodes()[t[2]], TriangleGauss::xi[q][0],
                                TriangleGauss::xi[q][1]);
      basis_.evaluate(element, x, idx, w, grad);
      const double wq = TriangleGauss::w[q] * area;
      const auto& f = fit.at;
      for (int k = 0; k < K; ++k) {
        const int i = idx[k];
        if (mass) g.m[i] += wq * w[k] * f[0][q];
        if (momentum)
          for (int d = 0; d < 2; ++d) g.q[d][i] += wq * w[k] * f[1 + d][q];
        if (force) {
          g.f[0][i] -= wq * (f[3][q] * grad[k][0] + f[4][q] * grad[k][1]);
          g.f[1][i] -= wq * (f[4][q] * grad[k][0] + f[5][q] * grad[k][1]);
        }
      }
    }
  }

  bool free_dof(int d, std::size_t i) const { return sim_.grid_.m[i] > sim_.empty_mass_ && !sim_.grid_.fixed[d][i]; }

  /// out = in / m on the free functions (the lumped mass), 0 elsewhere.
  void divide_by_lumped_mass(std::array<std::vector<double>, 2>& out, const std::array<std::vector<double>, 2>& in) {
    const MeshGrid& g = sim_.grid_;
    parallel_over(g.m.size(), 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int d = 0; d < 2; ++d) out[d][i] = free_dof(d, i) ? in[d][i] / g.m[i] : 0.0;
    });
  }

  /// x = M⁻¹ rhs with the consistent mass of the particles (thesis eqs 3.9–3.10), assembled at the step's first
  /// solve: the particles stay where they are until the step's last gather.
  void solve_consistent(std::array<std::vector<double>, 2>& x, const std::array<std::vector<double>, 2>& rhs) {
    MeshMassMatrix& mass = *sim_.mass_matrix_;
    if (!mass_assembled_) {
      mass.clear();
      for_each_triangle_coloured([&](int element) {
        std::array<int, K> idx;
        std::array<double, K> w;
        std::array<Point2, K> grad;
        for_particles_of(element, [&](std::size_t p) {
          basis_.evaluate(element, {pv_.x[0][p], pv_.x[1][p]}, idx, w, grad);
          mass.add(element, w, pv_.m[p]);
        });
      });
      mass_assembled_ = true;
    }
    sim_.cg_iterations_ += sim_.mass_solver_->solve_with(
        [&](const auto& in, auto& out) { mass.multiply(in, out); }, sim_.grid_.m,
        [&](int d, std::size_t i) { return free_dof(d, i); }, x, rhs);
  }

  /// a = M⁻¹ f (eq. 2.34); v = M⁻¹ q (eqs 2.35, 2.49), advanced by Δt a in USL (eq. 2.36); fixed and empty
  /// functions 0. The lumped M, or the consistent one for the velocities (projection) or both (consistent).
  void grid_update(bool acceleration, bool velocity) {
    MeshGrid& g = sim_.grid_;
    const MassMatrix mass = sim_.scene_.algorithm.mass;
    if (acceleration) {
      if (mass == MassMatrix::consistent) solve_consistent(g.a, g.f);
      else divide_by_lumped_mass(g.a, g.f);
    }
    if (!velocity) return;
    if (mass != MassMatrix::lumped) solve_consistent(g.v, g.q);
    else divide_by_lumped_mass(g.v, g.q);
    if (acceleration)  // USL
      parallel_over(g.m.size(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i)
          for (int d = 0; d < 2; ++d) g.v[d][i] += dt_ * g.a[d][i];
      });
  }

  /// G2P (eqs 2.37–2.41): the particle velocity from the accelerations, the position and F from the velocities,
  /// and the stress of the new F; a non-finite state or J ≤ 0 stops the run naming the particle.
  void gather(bool velocity, bool kinematics) {
    const MeshGrid& g = sim_.grid_;
    std::atomic<std::size_t> first_bad{ParticleGuard::none};
    parallel_over(sim_.store_.size(), particle_grain, [&](std::size_t b, std::size_t e) {
      std::array<int, K> idx;
      std::array<double, K> w;
      std::array<Point2, K> grad;
      for (std::size_t p = b; p < e; ++p) {
        basis_.evaluate(sim_.element_[p], {pv_.x[0][p], pv_.x[1][p]}, idx, w, grad);
        if (velocity)
          for (int k = 0; k < K; ++k)
            for (int d = 0; d < 2; ++d) pv_.v[d][p] += dt_ * w[k] * g.a[d][idx[k]];
        if (!kinematics) continue;
        double L[4] = {0, 0, 0, 0}, dx[2] = {0, 0};
        for (int k = 0; k < K; ++k)
          for (int d = 0; d < 2; ++d) {
            const double vi = g.v[d][idx[k]];
            dx[d] += w[k] * vi;
            L[2 * d] += vi * grad[k][0];
            L[2 * d + 1] += vi * grad[k][1];
          }
        const double f00 = pv_.F[0][p], f01 = pv_.F[1][p], f10 = pv_.F[2][p], f11 = pv_.F[3][p];
        // F ← (I + Δt L) F
        const double Fp[4] = {f00 + dt_ * (L[0] * f00 + L[1] * f10), f01 + dt_ * (L[0] * f01 + L[1] * f11),
                              f10 + dt_ * (L[2] * f00 + L[3] * f10), f11 + dt_ * (L[2] * f01 + L[3] * f11)};
        for (int c = 0; c < 4; ++c) pv_.F[c][p] = Fp[c];
        for (int d = 0; d < 2; ++d) pv_.x[d][p] += dt_ * dx[d];
        double s[3];
        material_.template stress<2>(Fp, s);
        for (int c = 0; c < 3; ++c) pv_.s[c][p] = s[c];
        const double J = Fp[0] * Fp[3] - Fp[1] * Fp[2];
        if (!(J > 0) || !std::isfinite(s[0] + s[1] + s[2] + pv_.x[0][p] + pv_.x[1][p] + pv_.v[0][p] + pv_.v[1][p])) {
          std::size_t cur = first_bad.load();
          while (p < cur && !first_bad.compare_exchange_weak(cur, p)) {
          }
        }
      }
    });
    if (const std::size_t bad = first_bad.load(); bad != ParticleGuard::none)
      raise_unstable_particle(sim_.store_, bad, sim_.step_ + 1, sim_.time_ + dt_, kinematics ? "g2p" : "g2p-velocity",
                              false, "mesh");
  }

  MeshSimulation& sim_;
  const B& basis_;
  const M& material_;
  const F& body_;
  const double dt_;
  const ParticleView<2> pv_;
  tbb::enumerable_thread_specific<std::vector<TriangleSample>> own_, near_;
  bool mass_assembled_ = false;  ///< the consistent mass of this step's particles is in sim_.mass_matrix_
};

void MeshSimulation::step() {
  const double dt = step_ + 1 == steps_total_ ? scene_.time.end - dt_ * step_ : dt_;
  locate_particles();
  cg_iterations_ = 0;
  const BodyForce<2> body = problem_->body_force(time_, body_constants_of(store_));
  std::visit(
      [&](const auto& basis, const auto& material, const auto& force) {
        Step<std::decay_t<decltype(basis)>, std::decay_t<decltype(material)>, std::decay_t<decltype(force)>> s(
            *this, basis, material, force, dt);
        if (scene_.algorithm.update == Update::usl) s.usl();
        else s.musl();
      },
      basis_, material_, body);
  ++step_;
  time_ = step_ == steps_total_ ? scene_.time.end : dt_ * step_;
}

}  // namespace mpm
