#pragma once
// The definitions of Simulation<Dim>, included by simulation_1d.cpp, simulation_2d.cpp and simulation_2d_generic.cpp,
// which instantiate one dimension, or one group of 2D bases, each: every combination of basis, material and body
// force instantiates the step kernels (three instruction-set copies in the portable build), and split, the units
// compile in parallel. Not a public header.
#include "engine/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "engine/deterministic_sum.hpp"
#include "engine/parallel_over.hpp"
#include "engine/point_load.hpp"
#include "kernels/isa.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

namespace {

constexpr std::size_t particle_grain = 2048;  // particles per task of the gather loops
constexpr int reorder_every = 16;              // steps between permutations of the particles into block order
// The particles are binned again once they may have moved this many cells since the last binning (or at a
// reordering); the blocks are wide enough for that (CellBins::block_width_for). Binning was 8–11 % of a step.
constexpr int bin_slack_cells = 1;

/// Local coordinates in [0, 1) of the particles of one cell, per axis, and their volume fractions.
struct CellLayout {
  std::vector<std::vector<double>> coords;  ///< per particle: Dim coordinates
  std::vector<double> fraction;             ///< per particle: share of the cell volume
};

CellLayout cell_layout(const ParticleSpec& spec, int dim, std::mt19937_64* rng) {
  CellLayout out;
  if (spec.layout == Layout::random) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const int n = spec.per_cell[0];
    for (int k = 0; k < n; ++k) {
      std::vector<double> c(dim);
      for (auto& x : c) x = u(*rng);
      out.coords.push_back(c);
      out.fraction.push_back(1.0 / n);
    }
    return out;
  }
  std::vector<GaussRule> rules(dim);
  for (int d = 0; d < dim; ++d) {
    const int n = spec.per_cell[d];
    if (spec.layout == Layout::gauss) {
      rules[d] = gauss_legendre(n);
    } else {
      for (int k = 0; k < n; ++k) {
        rules[d].x.push_back((k + 0.5) / n);  // cell sub-centres
        rules[d].w.push_back(1.0 / n);
      }
    }
  }
  const int n0 = spec.per_cell[0], n1 = dim > 1 ? spec.per_cell[1] : 1;
  for (int j = 0; j < n1; ++j)
    for (int i = 0; i < n0; ++i) {
      std::vector<double> c{rules[0].x[i]};
      double w = rules[0].w[i];
      if (dim > 1) {
        c.push_back(rules[1].x[j]);
        w *= rules[1].w[j];
      }
      out.coords.push_back(c);
      out.fraction.push_back(w);
    }
  return out;
}

template <int Dim>
Seeds<Dim> seed_particles(const Scene& scene, const Problem<Dim>& problem) {
  Seeds<Dim> s;
  std::mt19937_64 rng(scene.particles.seed);
  std::array<double, Dim> h;
  double cell_volume = 1.0;
  for (int d = 0; d < Dim; ++d) {
    h[d] = scene.grid.length[d] / scene.grid.cells[d];
    cell_volume *= h[d];
  }
  const bool random = scene.particles.layout == Layout::random;
  const CellLayout fixed_layout = random ? CellLayout{} : cell_layout(scene.particles, Dim, nullptr);
  for (const auto& body : problem.bodies()) {
    std::array<int, Dim> c0, c1;
    for (int d = 0; d < Dim; ++d) {
      c0[d] = std::max(0, static_cast<int>(std::floor(body.lo[d] / h[d] + 1e-9)));
      c1[d] = std::min(scene.grid.cells[d], static_cast<int>(std::ceil(body.hi[d] / h[d] - 1e-9)));
    }
    const int n1 = Dim > 1 ? c1[Dim - 1] - c0[Dim - 1] : 1;
    for (int j = 0; j < n1; ++j)
      for (int i = c0[0]; i < c1[0]; ++i) {
        const CellLayout layout = random ? cell_layout(scene.particles, Dim, &rng) : CellLayout{};
        const CellLayout& cl = random ? layout : fixed_layout;
        for (std::size_t k = 0; k < cl.fraction.size(); ++k) {
          std::array<double, Dim> x;
          bool inside = true;
          for (int d = 0; d < Dim; ++d) {
            const int cell = d == 0 ? i : c0[1] + j;
            x[d] = (cell + cl.coords[k][d]) * h[d];
            inside = inside && x[d] >= body.lo[d] && x[d] < body.hi[d];
          }
          if (!inside) continue;
          const double V = cl.fraction[k] * cell_volume;
          s.x.push_back(x);
          s.V0.push_back(V);
          s.m.push_back(V * body.material.density);
          s.v.push_back(body.velocity(x));
        }
      }
  }
  return s;
}

/// The stage names of one step of the scene's scheme.
template <int Dim>
std::vector<std::string> scheme_stages(const Scene& scene, bool body_force) {
  const bool consistent_v = scene.algorithm.mass != MassMatrix::lumped;
  const bool consistent_a = scene.algorithm.mass == MassMatrix::consistent;
  const std::string p2g_force = body_force ? "p2g-force+body-force" : "p2g-force";
  const std::string accel = consistent_a ? "grid-acceleration-cg" : "grid-acceleration";
  const std::string vel = consistent_v ? "grid-velocity-cg" : "grid-velocity";
  switch (scene.algorithm.update) {
    case Update::usl:
    case Update::unified:
      return {"bin", "p2g-mass-momentum", p2g_force, accel, vel, "g2p-velocity-position-deformation", "stress"};
    case Update::otm:
      return {"bin", "p2g-mass-momentum", p2g_force, accel, vel, "g2p-position-velocity-deformation", "stress"};
    case Update::musl:
      return {"bin", "p2g-mass", p2g_force, accel, "g2p-velocity+p2g-momentum", vel, "g2p-position-deformation",
              "stress"};
    case Update::usf:
      return {"bin", "p2g-mass-momentum", vel, "g2p-deformation", "stress", p2g_force, accel,
              "g2p-velocity-position"};
  }
  return {};
}

/// The stage names of one step: the scheme's, DDMPM's force sub-points and a point load with every force
/// scatter, and the rebuild of the reconstruction `rebuild` (null for direct mapping) before every scatter, which
/// reads the Gauss points.
template <int Dim>
std::vector<std::string> assemble_pipeline(const Scene& scene, bool body_force, bool point_loads,
                                           const char* rebuild_name) {
  std::vector<std::string> pipeline = scheme_stages<Dim>(scene, body_force);
  for (auto& st : pipeline)
    if (st.rfind("p2g-force", 0) == 0) {
      if (scene.algorithm.ddmpm_subpoints > 1) st += "+subpoints";
      if (point_loads) st += "+point-load";
    }
  if (!rebuild_name) return pipeline;
  const std::string rebuild = std::string(rebuild_name) + "-rebuild+";
  std::vector<std::string> stages;
  for (const auto& st : pipeline) {
    if (st == "g2p-velocity+p2g-momentum") {
      stages.insert(stages.end(), {"g2p-velocity", rebuild + "p2g-momentum"});
    } else {
      stages.push_back(st.rfind("p2g", 0) == 0 ? rebuild + st : st);
    }
  }
  return stages;
}

/// The grid arrays of the scene: DOF = i0 + stride1 · i1, with ghost columns for the kernels' padding lanes
/// (stencil.hpp), which stay empty; the fixed sides marked.
template <int Dim>
GridState<Dim> make_grid(const Scene& scene) {
  GridState<Dim> grid;
  const Basis basis = scene.grid.basis;
  grid.stride1 = grid_stride(functions_per_axis(basis, scene.grid.cells[0]), stencil_width_of(basis));
  grid.dofs = Dim == 1 ? grid.stride1 : grid.stride1 * functions_per_axis(basis, scene.grid.cells[Dim - 1]);
  grid.m.assign(grid.dofs, 0.0);
  for (int d = 0; d < Dim; ++d) {
    for (auto* a : {&grid.q[d], &grid.f[d], &grid.v[d], &grid.a[d]}) a->assign(grid.dofs, 0.0);
    grid.fixed[d].assign(grid.dofs, 0);
  }
  // fixed sides: the first or last function along the side's normal axis carries the boundary value
  for (int side : scene.fixed_sides) {
    const int axis = side / 2;
    if (axis >= Dim) continue;
    const int index = boundary_function(basis, scene.grid.cells[axis], side % 2);
    for (int dof = 0; dof < grid.dofs; ++dof) {
      const int along = axis == 0 ? dof % grid.stride1 : dof / grid.stride1;
      if (along == index) grid.fixed[axis][dof] = 1;
    }
  }
  return grid;
}

}  // namespace

template <int Dim>
GridView<Dim> GridState<Dim>::view() {
  GridView<Dim> g;
  g.stride1 = stride1;
  g.dofs = dofs;
  g.m = m.data();
  for (int d = 0; d < Dim; ++d) {
    g.q[d] = q[d].data();
    g.f[d] = f[d].data();
    g.v[d] = v[d].data();
    g.a[d] = a[d].data();
  }
  return g;
}

template <int Dim>
AnyBasis<Dim> make_basis(const GridSpec& grid, int ddmpm_subpoints) {
  const int p = degree_of(grid.basis);
  auto build = [&](auto axis_of) {
    using Axis = decltype(axis_of(0));
    std::array<int, Dim> functions;
    for (int d = 0; d < Dim; ++d) functions[d] = functions_per_axis(grid.basis, grid.cells[d]);
    if constexpr (Dim == 1) return AnyBasis<Dim>(TensorBasis<Dim, Axis>{{axis_of(0)}, functions});
    else return AnyBasis<Dim>(TensorBasis<Dim, Axis>{{axis_of(0), axis_of(1)}, functions});
  };
  auto knots = [&](int d) { return KnotVector::open_uniform(p, grid.cells[d], grid.length[d]); };
  if (grid.basis == Basis::maxent)
    return build([&](int d) { return StencilCached<MaxEntAxis>(grid.cells[d], grid.length[d], grid.maxent_dmax); });
  if (grid.basis == Basis::ddmpm)
    return build([&](int d) { return DualDomainAxis(grid.cells[d], grid.length[d], ddmpm_subpoints); });
  if (grid.path == BasisPath::fast && p <= 2) {
    if (p == 1) return build([&](int d) { return UniformAxis<2>(grid.cells[d], grid.length[d]); });
    return build([&](int d) { return UniformAxis<3>(grid.cells[d], grid.length[d]); });
  }
  if (p == 1) return build([&](int d) { return CoxDeBoorAxis<2>{knots(d)}; });
  if (p == 2) return build([&](int d) { return CoxDeBoorAxis<3>{knots(d)}; });
  return build([&](int d) { return CoxDeBoorAxis<4>{knots(d)}; });
}

template <int Dim>
Simulation<Dim>::Simulation(const Scene& scene)
    : scene_(scene),
      problem_(make_problem<Dim>(scene)),
      material_(make_material(scene.material)),
      basis_(make_basis<Dim>(scene.grid, scene.algorithm.ddmpm_subpoints)),
      store_(0, FieldSet{}),
      bins_([&] {
        std::array<int, Dim> c;
        std::array<double, Dim> l;
        for (int d = 0; d < Dim; ++d) {
          c[d] = scene.grid.cells[d];
          l[d] = scene.grid.length[d];
        }
        const int reach = stencil_reach(stencil_width_of(scene.grid.basis));
        // DDMPM's force sub-points lie up to a cell beyond their particle (check_subpoint_reach)
        const int slack = bin_slack_cells + (scene.algorithm.ddmpm_subpoints > 1 ? 1 : 0);
        return CellBins<Dim>(c, l, CellBins<Dim>::block_width_for(reach, slack));
      }()) {
  if (scene.dimension != Dim) throw std::logic_error("Simulation: scene dimension does not match");

  check_body_materials<Dim>(scene, problem_->bodies());
  const Seeds<Dim> seeds = seed_particles(scene, *problem_);
  store_ = store_from_seeds(seeds, *problem_, scene.algorithm.update);
  particle_mass_ = deterministic_sum(seeds.m.size(), [&](std::size_t p) { return seeds.m[p]; });

  dt_ = time_step_for(scene, critical_step());
  steps_total_ = count_steps(scene, dt_);
  if (scene.time.start == TimeStart::staggered) start_staggered(store_, *problem_, dt_);
  empty_mass_ = 1e-12 * *std::min_element(seeds.m.begin(), seeds.m.end());

  grid_ = make_grid<Dim>(scene);
  if (scene.algorithm.mass != MassMatrix::lumped) mass_solver_.emplace(grid_.dofs);

  if (scene.algorithm.mapping != Mapping::direct) {
    gauss_.emplace(scene, bins_.block_width());
    particle_cells_.emplace(CellBins<Dim>::single_cells_in_order_of(bins_));
  }
  pipeline_ = assemble_pipeline<Dim>(scene, problem_->has_body_force(), problem_->has_point_loads(),
                                     gauss_ ? gauss_->name() : nullptr);
  scatter_ahead_possible_ = (scene.algorithm.update == Update::usl || scene.algorithm.update == Update::musl) &&
                            !gauss_ && !problem_->has_point_loads() && scene.algorithm.ddmpm_subpoints == 1 &&
                            !std::holds_alternative<TensorBasis<Dim, StencilCached<MaxEntAxis>>>(basis_);
  // initial stress from F = I is zero for both laws
}

template <int Dim>
Simulation<Dim>::~Simulation() = default;

template <int Dim>
SimulationState Simulation<Dim>::save_state() const {
  return save_particle_state(store_, step_, time_, conservation_);
}

template <int Dim>
void Simulation<Dim>::load_state(const SimulationState& st) {
  load_particle_columns(store_, st, *problem_);
  step_ = st.step;
  time_ = st.time;
  conservation_ = st.conservation;
  moved_cells_ = std::numeric_limits<double>::infinity();  // the particles moved: bin them before the next scatter
  grid_scattered_ahead_ = false;
}

template <int Dim>
bool Simulation<Dim>::next_step_bins() const {
  return step_ % reorder_every == 0 || moved_cells_ >= bin_slack_cells;
}

template <int Dim>
void Simulation<Dim>::step() {
  const double dt = step_ + 1 == steps_total_ ? scene_.time.end - dt_ * step_ : dt_;
  // bin first: the periodic reordering moves the columns, so every pointer into them is taken after it
  const bool reorder = step_ % reorder_every == 0;
  if (next_step_bins()) {
    std::array<const double*, Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = store_.column(basis_field(), d).data();
    bins_.bin(x, store_.size(), reorder);  // the reordered columns hold each cell's particles together
    moved_cells_ = 0.0;
  }
  if (reorder) {
    store_.permute(bins_.order());
    bins_.adopt_order();
  }
  const BodyForce<Dim> body = problem_->body_force(time_, body_constants_of(store_));
  // a step that throws has moved the particles by an unknown amount: until it returns, bin before the next scatter
  const double moved_before = moved_cells_;
  moved_cells_ = std::numeric_limits<double>::infinity();
  // the next step keeps these bins if it does not reorder and the particles move less than the slack left: then
  // its P2G, scattered ahead in this step's last gather pass, runs in the order its own scatter would
  // (Step::gather_and_scatter_ahead)
  const bool next_keeps_order =
      step_ + 1 < steps_total_ && (step_ + 1) % reorder_every != 0 && bins_.order_is_identity();
  const double scatter_ahead_budget_cells =
      scatter_ahead_possible_ && scatter_ahead_allowed_ && next_keeps_order ? bin_slack_cells - moved_before : 0.0;
  cache_stencils(true);
  std::visit(
      [&](const auto& basis) {
        moved_cells_ = moved_before + step_with(basis, body, dt, scatter_ahead_budget_cells);
      },
      basis_);
  cache_stencils(false);
  ++step_;
  time_ = step_ == steps_total_ ? scene_.time.end : dt_ * step_;
}

template <int Dim>
Field Simulation<Dim>::basis_field() const {
  // a basis that moves with the body is evaluated at the reference positions, which never leave their cells
  return basis_moves_with_body(scene_.algorithm.update) ? Field::reference : Field::position;
}

template <int Dim>
void Simulation<Dim>::cache_stencils(bool fill) {
  auto* basis = std::get_if<TensorBasis<Dim, StencilCached<MaxEntAxis>>>(&basis_);
  if (!basis) return;
  auto& cache = basis->axis[0];
  cache.cached_x0 = nullptr;  // from here on stencil_of evaluates the axis
  if (!fill) return;
  std::array<const double*, Dim> x;
  for (int d = 0; d < Dim; ++d) x[d] = store_.column(basis_field(), d).data();
  stencil_cache_.resize(store_.size());
  parallel_over(store_.size(), particle_grain, [&](std::size_t b, std::size_t e) {
    for (std::size_t p = b; p < e; ++p) stencil_cache_[p] = stencil_of<Dim, MaxEntAxis::width>(*basis, x, p);
  });
  cache.stencils = stencil_cache_.data();
  cache.cached_x0 = x[0];
}

template <int Dim>
void Simulation<Dim>::clear_grid(bool mass, bool momentum, bool force) {
  parallel_over(grid_.dofs, 4096, [&](std::size_t b, std::size_t e) {
    if (mass) std::fill(grid_.m.begin() + b, grid_.m.begin() + e, 0.0);
    for (int d = 0; d < Dim; ++d) {
      if (momentum) std::fill(grid_.q[d].begin() + b, grid_.q[d].begin() + e, 0.0);
      if (force) std::fill(grid_.f[d].begin() + b, grid_.f[d].begin() + e, 0.0);
    }
  });
}

template <int Dim>
void Simulation<Dim>::check_mass() {
  const double grid_mass = deterministic_sum(grid_.dofs, [&](std::size_t i) { return grid_.m[i]; });
  conservation_.mass_rel_max =
      std::max(conservation_.mass_rel_max, std::abs(grid_mass - particle_mass_) / particle_mass_);
}

template <int Dim>
void Simulation<Dim>::check_momentum(const MomentumTotals<Dim>& particles) {
  if (particles.m_abs_v == 0.0) return;
  double worst = 0.0;
  for (int d = 0; d < Dim; ++d) {
    const double grid = deterministic_sum(grid_.dofs, [&](std::size_t i) { return grid_.q[d][i]; });
    worst = std::max(worst, std::abs(grid - particles.mv[d]) / particles.m_abs_v);
  }
  conservation_.momentum_rel_max = std::max(conservation_.momentum_rel_max, worst);
}

template <int Dim>
void Simulation<Dim>::raise_unstable(std::size_t p, const char* stage) const {
  bool outside = false;
  for (int d = 0; d < Dim; ++d) {
    const double x = store_.column(Field::position, d)[p];
    outside = outside || !(x >= 0.0 && x <= scene_.grid.length[d]);
  }
  raise_unstable_particle(store_, p, step_ + 1, time_ + dt_, stage, outside, "grid");
}

template <int Dim>
void Simulation<Dim>::check_subpoint_reach() const {
  const auto x = store_.column(Field::position, 0), F = store_.column(Field::deformation, 0),
             V0 = store_.column(Field::volume0);
  const double h = scene_.grid.length[0] / scene_.grid.cells[0];
  for (std::size_t p = 0; p < store_.size(); ++p)
    if (!(F[p] * V0[p] < 2.0 * h)) {
      std::ostringstream msg;
      msg.precision(6);
      msg << "unstable at step " << step_ + 1 << " (t = " << time_ + dt_ << " s), p2g-force: particle " << p
          << " at x = " << x[p] << " is " << F[p] * V0[p] << " m long, two cells or more (h = " << h
          << " m): its algorithm.ddmpm_subpoints would reach beyond the coloured scatter's blocks";
      throw UnstableRun(msg.str());
    }
}

/// One step's kernels for one basis, material and body force: the transfers and grid updates that the step
/// sequences (usl, musl, usf) are built from.
template <int Dim>
template <class B, class M, class F>
class Simulation<Dim>::Step {
 public:
  static constexpr int S = B::width;

  Step(Simulation& sim, const B& basis, const M& material, const F& body, double dt, double scatter_ahead_budget_cells)
      : sim_(sim), basis_(basis), material_(material), body_(body), dt_(dt),
        scatter_ahead_budget_cells_(scatter_ahead_budget_cells), pv_(sim.store_.view()), gv_(sim.grid_.view()),
        np_(sim.store_.size()) {
    for (int d = 0; d < Dim; ++d) {
      guard_.hi[d] = sim.scene_.grid.length[d];
      guard_.inv_h[d] = sim.scene_.grid.cells[d] / sim.scene_.grid.length[d];
    }
    sim.block_momentum_.assign(sim.bins_.blocks(), MomentumTotals<Dim>{});
    if (sim.particle_cells_) {
      std::array<const double*, Dim> x;
      for (int d = 0; d < Dim; ++d) x[d] = pv_.x[d];
      sim.particle_cells_->bin(x, np_);
    }
  }

  /// The largest distance a particle moved along an axis, in cells.
  double max_move() const { return guard_.max_move_cells.load(); }

  /// Thesis Algorithm 1. With `reference`, the basis moves with the body (each particle keeps its place in the
  /// mesh: φ_i at its reference position, ∇φ_i pulled back by F): with the consistent mass, the unified approach
  /// (thesis Algorithm 4); with the velocity from the position increment as well, OTM (Algorithm 3, eq. 4.53).
  /// With allow_scatter_ahead, plain USL's gather pass scatters the next step's P2G as well when the next step
  /// keeps the bins (gather_and_scatter_ahead); the next step then finds it done.
  template <bool reference = false, bool velocity_from_position = false>
  void usl() {
    constexpr ScatterFields p2g{.mass = true, .momentum = true, .force = true, .reference = reference};
    constexpr GatherFields g2p{.velocity = !velocity_from_position,
                               .position = true,
                               .deformation = true,
                               .reference = reference,
                               .velocity_from_position = velocity_from_position};
    if (!scattered_ahead()) {
      sim_.clear_grid(true, true, true);
      scatter<p2g>();
    }
    accelerations_and_velocities();
    if constexpr (!reference && !velocity_from_position)
      if (may_scatter_ahead()) return gather_and_scatter_ahead<g2p, p2g>("g2p");
    gather<g2p>("g2p");
  }

  /// Thesis Algorithm 2.
  void musl() {
    constexpr ScatterFields p2g{.mass = true, .momentum = false, .force = true};
    if (!scattered_ahead()) {
      sim_.clear_grid(true, false, true);
      scatter<p2g>();
    }
    accelerations();
    sim_.clear_grid(false, true, false);
    if (sim_.gauss_) {
      gather<GatherFields{.velocity = true, .position = false, .deformation = false}>("g2p-velocity");
      scatter<ScatterFields{.mass = false, .momentum = true, .force = false}>(true);
    } else {
      const unsigned* order = sim_.bins_.order().data();
      sim_.bins_.for_each_block_coloured([&](std::size_t block, std::size_t b, std::size_t e) {
        with_active_isa([&](auto isa) {
          sim_.block_momentum_[block] =
              advance_velocity_scatter_momentum<Dim, S, isa>(basis_, pv_, gv_, order, b, e, dt_);
        });
      });
      sim_.check_momentum(sum_totals(sim_.block_momentum_));
    }
    velocities();
    constexpr GatherFields g2p{.velocity = false, .position = true, .deformation = true};
    if (may_scatter_ahead()) return gather_and_scatter_ahead<g2p, p2g>("g2p-position-deformation");
    gather<g2p>("g2p-position-deformation");
  }

  /// Stress first, from the velocities mapped at the start of the step.
  void usf() {
    sim_.clear_grid(true, true, true);
    scatter<ScatterFields{.mass = true, .momentum = true, .force = false}>();
    velocities();
    gather<GatherFields{.velocity = false, .position = false, .deformation = true}>("g2p-deformation");
    scatter<ScatterFields{.mass = false, .momentum = false, .force = true}>();
    accelerations();
    advance_velocities();
    gather<GatherFields{.velocity = true, .position = true, .deformation = false}>("g2p-velocity-position");
  }

 private:
  /// P2G, direct (particles as integration points) or from the Gauss points of the reconstruction, which is
  /// rebuilt from the particles first (with stress and body force when the force is scattered);
  /// `only_velocities_changed` since the last scatter (MUSL's second P2G): the reconstruction reuses its work.
  template <ScatterFields Fields>
  void scatter(bool only_velocities_changed = false) {
    if constexpr (Fields.force)
      if (sim_.scene_.algorithm.ddmpm_subpoints > 1) sim_.check_subpoint_reach();
    if (sim_.gauss_) {
      GaussPoints<Dim>& gauss = *sim_.gauss_;
      const MomentumTotals<Dim> totals =
          only_velocities_changed ? gauss.rebuild_momentum(pv_, *sim_.particle_cells_, sim_.bins_, body_)
                                  : gauss.rebuild(pv_, *sim_.particle_cells_, sim_.bins_, body_, Fields.force, Fields.momentum);
      gauss.template scatter<Fields, F::active, S>(basis_, gv_);
      if constexpr (Fields.momentum) sim_.check_momentum(totals);
    } else {
      sim_.bins_.for_each_block_coloured([&](std::size_t block, std::size_t b, std::size_t e) {
        const auto totals = scatter_range<Fields>(b, e, body_);
        if constexpr (Fields.momentum) sim_.block_momentum_[block] = totals;
      });
      if constexpr (Fields.momentum) sim_.check_momentum(sum_totals(sim_.block_momentum_));
    }
    if constexpr (Fields.force)
      if (sim_.problem_->has_point_loads())
        add_point_loads<Dim, S>(basis_, gv_, sim_.problem_->point_loads(sim_.time_, pv_, np_, Fields.reference));
    if constexpr (Fields.mass) sim_.check_mass();
  }

  template <GatherFields Fields>
  void gather(const char* stage) {
    parallel_over(np_, particle_grain, [&](std::size_t b, std::size_t e) { gather_range<Fields>(b, e); });
    const std::size_t bad = guard_.first_bad.load();
    if (bad != ParticleGuard::none) sim_.raise_unstable(bad, stage);
  }

  /// The direct P2G of the particles order[b..e) with the body force `body`; their momentum.
  template <ScatterFields Fields>
  MomentumTotals<Dim> scatter_range(std::size_t b, std::size_t e, const F& body) {
    MomentumTotals<Dim> totals;
    with_active_isa([&](auto isa) {
      totals = scatter_p2g<Fields, Dim, S, isa>(basis_, pv_, gv_, sim_.bins_.order().data(), b, e, body);
    });
    return totals;
  }

  /// The G2P of particles [b, e).
  template <GatherFields Fields>
  void gather_range(std::size_t b, std::size_t e) {
    with_active_isa([&](auto isa) {
      const auto stress = [&](const double* Fp, double* s) { material_.template stress<Dim, isa>(Fp, s); };
      gather_g2p<Fields, Dim, S, isa>(basis_, pv_, gv_, b, e, dt_, stress, guard_);
    });
  }

  /// A bound on the largest move along an axis, in cells, of the step's last gather: Δt |Σ_i φ_i v_i,d| / h_d ≤
  /// Δt max_i |v_i,d| / h_d, since the weights are non-negative and sum to 1 (B-splines, linear, DDMPM); with a
  /// margin for the round-off of the sum.
  double max_move_bound() const {
    const GridState<Dim>& grid = sim_.grid_;
    const double fastest = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, grid.dofs, 4096), 0.0,
        [&](const tbb::blocked_range<std::size_t>& r, double m) {
          for (std::size_t i = r.begin(); i < r.end(); ++i)
            for (int d = 0; d < Dim; ++d) m = std::max(m, std::abs(grid.v[d][i]) * guard_.inv_h[d]);
          return m;
        },
        [](double a, double b) { return std::max(a, b); });
    return dt_ * fastest * (1 + 1e-9);
  }

  /// Whether the previous step scattered this step's P2G (gather_and_scatter_ahead); counts it.
  bool scattered_ahead() {
    if (!sim_.grid_scattered_ahead_) return false;
    sim_.grid_scattered_ahead_ = false;
    ++sim_.steps_scattered_ahead_;
    return true;
  }

  /// Whether this step's last gather may scatter the next step's P2G: the next step keeps the bins
  /// (Simulation::step) if the particles move less than the slack left.
  bool may_scatter_ahead() const {
    return scatter_ahead_budget_cells_ > 0 && max_move_bound() < scatter_ahead_budget_cells_;
  }

  /// About how many particles gather_and_scatter_ahead gathers before it scatters them: runs of that many fill the
  /// gather's batches (a block holds ≈ 100 at 2×2 per cell), still fit a core's L2 cache (≈ 100 bytes each) and
  /// leave dozens of runs per colour at 1e6 particles. Runs of 4096 and 8192 measured alike, 16384 slower and
  /// single blocks slower still (docs/PERFORMANCE.md).
  static constexpr std::size_t scatter_ahead_run_particles = 4096;

  /// The step's last G2P (fields G) and the next step's P2G (fields P) in one pass over the particles (USL: its
  /// only G2P; MUSL: the position and deformation update). Run after run of blocks of one colour of the coloured
  /// bins, the run's particles are gathered (reading the grid's v and a) and then, while they are in cache,
  /// scattered block by block into the emptied grid fields of P with the body force at the next step's time: the
  /// particle columns stream from memory once instead of twice. The next step keeps these bins
  /// (Simulation::step: no reordering, the order the identity, so a block's range of the order is its range of
  /// particles, and a move within the slack left), so its own scatter would form the same sums in the same order:
  /// the results are the same to the bit, and so are the guards and the conservation checks, which run here for
  /// the next step.
  template <GatherFields G, ScatterFields P>
  void gather_and_scatter_ahead(const char* stage) {
    const double t_next = sim_.dt_ * (sim_.step_ + 1);
    const F body_next = std::get<F>(sim_.problem_->body_force(t_next, body_constants_of(sim_.store_)));
    sim_.clear_grid(P.mass, P.momentum, P.force);
    const CellBins<Dim>& bins = sim_.bins_;
    const std::size_t run_blocks = scatter_ahead_run_particles * bins.blocks() / std::max<std::size_t>(np_, 1);
    bins.for_each_block_run_coloured(run_blocks, [&](std::size_t first, std::size_t last) {
      gather_range<G>(bins.block_begin(first), bins.block_begin(last));
      bins.for_each_nonempty_block(first, last, [&](std::size_t block, std::size_t b, std::size_t e) {
        const auto totals = scatter_range<P>(b, e, body_next);
        if constexpr (P.momentum) sim_.block_momentum_[block] = totals;
      });
    });
    const std::size_t bad = guard_.first_bad.load();
    if (bad != ParticleGuard::none) sim_.raise_unstable(bad, stage);
    if constexpr (P.momentum) sim_.check_momentum(sum_totals(sim_.block_momentum_));
    if constexpr (P.mass) sim_.check_mass();
    sim_.grid_scattered_ahead_ = true;
  }

  /// Empty and fixed DOFs get no acceleration and no velocity.
  bool free_dof(int d, std::size_t i) const { return sim_.grid_.m[i] > sim_.empty_mass_ && !sim_.grid_.fixed[d][i]; }

  /// x = M⁻¹ rhs with the consistent mass; its carriers are the particles, or the Gauss points (thesis eq. 3.9).
  /// M is assembled at the step's first solve: the carriers stay where they are until the step's last gather, so
  /// a second solve (USL's a and v, USF's v and a) reuses it.
  void solve_consistent(std::array<std::vector<double>, Dim>& x, const std::array<std::vector<double>, Dim>& rhs) {
    if (!mass_assembled_) {
      const MassCarriers<Dim> carriers = sim_.gauss_ ? MassCarriers<Dim>(sim_.gauss_->view())
                                         : pv_.carriers(basis_moves_with_body(sim_.scene_.algorithm.update));
      const CellBins<Dim>& bins = sim_.gauss_ ? sim_.gauss_->bins() : sim_.bins_;
      sim_.mass_solver_->assemble(basis_, carriers, bins, sim_.grid_.stride1);
      mass_assembled_ = true;
    }
    sim_.cg_iterations_ += sim_.mass_solver_->template solve<S>(
        sim_.grid_.stride1, sim_.grid_.m, [&](int d, std::size_t i) { return free_dof(d, i); }, x, rhs);
  }

  /// out = in / m on the free DOFs (the lumped mass), 0 elsewhere.
  void divide_by_lumped_mass(std::array<std::vector<double>, Dim>& out, const std::array<std::vector<double>, Dim>& in) {
    parallel_over(sim_.grid_.dofs, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int d = 0; d < Dim; ++d) out[d][i] = free_dof(d, i) ? in[d][i] / sim_.grid_.m[i] : 0.0;
    });
  }

  /// a = M⁻¹ f (eqs 2.34, 2.46).
  void accelerations() {
    if (sim_.scene_.algorithm.mass == MassMatrix::consistent) solve_consistent(sim_.grid_.a, sim_.grid_.f);
    else divide_by_lumped_mass(sim_.grid_.a, sim_.grid_.f);
  }

  /// v = M⁻¹ q (eqs 2.35, 2.49; with the consistent mass, thesis eq. 3.10).
  void velocities() {
    if (sim_.scene_.algorithm.mass != MassMatrix::lumped) solve_consistent(sim_.grid_.v, sim_.grid_.q);
    else divide_by_lumped_mass(sim_.grid_.v, sim_.grid_.q);
  }

  /// v^{s+1} = v^s + Δt a (eq. 2.36).
  void advance_velocities() {
    GridState<Dim>& grid = sim_.grid_;
    parallel_over(grid.dofs, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int d = 0; d < Dim; ++d) grid.v[d][i] += dt_ * grid.a[d][i];
    });
  }

  /// USL grid update, eqs 2.34–2.36; with the lumped mass in one pass over the grid (same arithmetic).
  void accelerations_and_velocities() {
    if (sim_.scene_.algorithm.mass != MassMatrix::lumped) {
      accelerations();
      velocities();
      advance_velocities();
      return;
    }
    GridState<Dim>& grid = sim_.grid_;
    parallel_over(grid.dofs, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int d = 0; d < Dim; ++d) {
          const bool free = free_dof(d, i);
          grid.a[d][i] = free ? grid.f[d][i] / grid.m[i] : 0.0;
          grid.v[d][i] = free ? grid.q[d][i] / grid.m[i] + dt_ * grid.a[d][i] : 0.0;
        }
    });
  }

  Simulation& sim_;
  const B& basis_;
  const M& material_;
  const F& body_;
  const double dt_;
  /// the cells the particles may still move in this step for the next to keep the bins (may_scatter_ahead)
  const double scatter_ahead_budget_cells_;
  const ParticleView<Dim> pv_;
  const GridView<Dim> gv_;
  const std::size_t np_;
  ParticleGuard guard_;
  bool mass_assembled_ = false;  ///< the consistent mass of this step's carriers is in the solver (solve_consistent)
};

template <int Dim>
template <class B>
double Simulation<Dim>::step_with(const B& basis, const BodyForce<Dim>& body, double dt,
                                  double scatter_ahead_budget_cells) {
  return std::visit(
      [&](const auto& material, const auto& force) {
        cg_iterations_ = 0;
        Step<B, std::decay_t<decltype(material)>, std::decay_t<decltype(force)>> step(*this, basis, material, force,
                                                                                      dt, scatter_ahead_budget_cells);
        switch (scene_.algorithm.update) {
          case Update::usl: step.usl(); break;
          case Update::musl: step.musl(); break;
          case Update::usf: step.usf(); break;
          case Update::unified: step.template usl<true>(); break;
          case Update::otm: step.template usl<true, true>(); break;
        }
        return step.max_move();
      },
      material_, body);
}

/// The step of basis I of AnyBasis<Dim> (Simulation::step_with), for an explicit instantiation; with `extern` in
/// front, its declaration.
#define MPM_STEP_OF_BASIS(Dim, I)                                                               \
  template double Simulation<Dim>::step_with(const std::variant_alternative_t<I, AnyBasis<Dim>>&, \
                                             const BodyForce<Dim>&, double, double)
/// The 2D steps simulation_2d_generic.cpp compiles, those of the Cox–de Boor and max-ent bases; simulation_2d.cpp
/// compiles the rest, so that the two halves of the 2D kernels build in parallel. `prefix`: empty or extern.
#define MPM_GENERIC_STEPS_2D(prefix)                                                                              \
  prefix MPM_STEP_OF_BASIS(2, 2);                                                                                 \
  prefix MPM_STEP_OF_BASIS(2, 3);                                                                                 \
  prefix MPM_STEP_OF_BASIS(2, 4);                                                                                 \
  prefix MPM_STEP_OF_BASIS(2, 6)

template <int Dim>
RunErrors Simulation<Dim>::errors() const {
  return particle_errors(store_, *problem_, time_, velocity_time(scene_.time.start, step_, time_, dt_));
}

template <int Dim>
CriticalStep Simulation<Dim>::critical_step() const {
  double h = 1e300;
  for (int d = 0; d < Dim; ++d) h = std::min(h, scene_.grid.length[d] / scene_.grid.cells[d]);
  const double kappa =
      scene_.algorithm.mass == MassMatrix::consistent ? consistent_mass_step_factor(scene_.grid.basis, Dim) : 1.0;
  return critical_step_of(store_, material_, h, kappa);
}

template <int Dim>
double Simulation<Dim>::external_power() const {
  // Point loads (the traction bar): force · the grid velocity at the load point, Σ_i φ_i(x) F · v_i, the power of the
  // nodal forces the load adds (point_load.hpp). Without this term the energy guard saw the traction's work as an
  // energy gain; with the velocity of the particle nearest the load instead, it stopped the unified approach, whose
  // sharp wave front had not yet reached that particle, h/8 inside the end.
  double loads_power = 0.0;
  if (problem_->has_point_loads()) {
    // point_loads only reads the particles; view() is the store's one accessor for them
    const ParticleView<Dim> pv = const_cast<ParticleStore<Dim>&>(store_).view();
    const bool reference = basis_moves_with_body(scene_.algorithm.update);
    for (const auto& load : problem_->point_loads(time_, pv, store_.size(), reference))
      std::visit(
          [&](const auto& basis) {
            const auto st = stencil_at<Dim, std::decay_t<decltype(basis)>::width>(basis, load.x.data());
            for_each_node(st, grid_.stride1, [&](int i, double w, const std::array<double, Dim>&) {
              for (int d = 0; d < Dim; ++d) loads_power += w * load.force[d] * grid_.v[d][i];
            });
          },
          basis_);
  }
  return loads_power + body_force_power<Dim>(store_, *problem_, time_);
}

template <int Dim>
Energy Simulation<Dim>::energy() const {
  return particle_energy(store_, material_);
}

}  // namespace mpm
