#pragma once
// One explicit MPM run: particle store, grid, and the step sequence of the chosen update scheme (thesis
// Algorithm 1: USL, Algorithm 2: MUSL, and USF), assembled once from the scene so that a run carries only the
// stages and particle columns it needs.
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "engine/cell_bins.hpp"
#include "engine/consistent_mass.hpp"
#include "engine/gauss_points.hpp"
#include "engine/material.hpp"
#include "engine/particle_measures.hpp"
#include "engine/particle_store.hpp"
#include "engine/problem.hpp"
#include "engine/scene.hpp"
#include "kernels/dual_domain.hpp"
#include "kernels/max_ent.hpp"
#include "kernels/stencil.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

/// Every basis the engine can run, resolved once per step.
template <int Dim>
using AnyBasis = std::variant<TensorBasis<Dim, UniformAxis<2>>, TensorBasis<Dim, UniformAxis<3>>,
                              TensorBasis<Dim, CoxDeBoorAxis<2>>, TensorBasis<Dim, CoxDeBoorAxis<3>>,
                              TensorBasis<Dim, CoxDeBoorAxis<4>>, TensorBasis<Dim, DualDomainAxis>,
                              TensorBasis<Dim, StencilCached<MaxEntAxis>>>;

/// The basis of a grid; DDMPM's axes also carry the force sub-points per particle (algorithm.ddmpm_subpoints).
template <int Dim>
AnyBasis<Dim> make_basis(const GridSpec& grid, int ddmpm_subpoints = 1);

/// Grid arrays, one entry per DOF (tensor-product basis function).
template <int Dim>
struct GridState {
  int stride1 = 0, dofs = 0;
  std::vector<double> m;
  std::array<std::vector<double>, Dim> q, f, v, a;
  std::array<std::vector<unsigned char>, Dim> fixed;  ///< normal component fixed (1) per DOF and axis
  GridView<Dim> view();
};

template <int Dim>
class Simulation {
 public:
  static constexpr int dim = Dim;
  /// Builds the particles and grid of a validated scene. Throws SceneError for a scene it cannot run.
  explicit Simulation(const Scene& scene);
  ~Simulation();

  /// Advances one time step. Throws UnstableRun if a particle's state became invalid.
  void step();

  bool finished() const { return step_ >= steps_total_; }
  /// Whether the next step bins the particles afresh. Between binnings the blocks a particle scatters in depend on
  /// where it was at the last binning, so only a state saved here resumes bitwise like the uninterrupted run.
  bool next_step_bins() const;
  long steps_done() const { return step_; }
  long steps_total() const { return steps_total_; }
  double time() const { return time_; }
  double dt() const { return dt_; }

  const Scene& scene() const { return scene_; }
  ParticleStore<Dim>& particles() { return store_; }
  const ParticleStore<Dim>& particles() const { return store_; }
  const GridState<Dim>& grid() const { return grid_; }
  /// Stage names of one step, in order.
  const std::vector<std::string>& pipeline() const { return pipeline_; }

  const Conservation& conservation() const { return conservation_; }
  bool has_exact() const { return problem_->has_exact(); }
  RunErrors errors() const;
  Energy energy() const;
  /// The largest stable time step for the current state: h_min / max_p (c(J_p) + |v_p|), with c the tangent
  /// P-wave speed of the material at the particle's J (neo-Hookean stiffens under compression).
  CriticalStep critical_step() const;
  /// Power of the external (body) forces on the particles now, Σ_p m_p b_p(t)·v_p, W; 0 without a body force.
  double external_power() const;
  /// USL and MUSL: whether a step's last gather pass may also scatter the next step's P2G when the next step keeps
  /// the bins (Step::gather_and_scatter_ahead). The results are the same to the bit either way. Off by default: at
  /// 1e6 particles it ran at 0.88–1.05× the separate passes, at 1e7 at 0.81–1.16× (docs/PERFORMANCE.md).
  void allow_scatter_ahead(bool allow) { scatter_ahead_allowed_ = allow; }
  /// How many steps found their P2G done by the previous step's gather pass.
  long steps_scattered_ahead() const { return steps_scattered_ahead_; }
  /// Reconstruction fallbacks so far (all zero for direct mapping).
  FallbackCounts fallbacks() const { return gauss_ ? gauss_->fallbacks() : FallbackCounts{}; }
  /// CG iterations of the consistent-mass solves in the last step (0 for lumped mass).
  int last_cg_iterations() const { return cg_iterations_; }

  /// A copy of the state (step, time, conservation, every particle column).
  SimulationState save_state() const;
  /// Restores a state of this scene; throws std::invalid_argument if its columns do not match this run's.
  void load_state(const SimulationState& state);

 private:
  template <class B, class M, class F>
  class Step;
  /// The step with one basis, for the run's material and body force; returns the largest distance a particle moved
  /// along an axis, in cells. `scatter_ahead_budget_cells`: the cells the particles may still move in this step for
  /// the next to keep the bins, if its P2G may be scattered ahead (Step::gather_and_scatter_ahead); 0 if not.
  /// Instantiated per basis, so that the bases' kernels can compile in separate translation units
  /// (simulation_2d.cpp, simulation_2d_generic.cpp).
  template <class B>
  double step_with(const B& basis, const BodyForce<Dim>& body, double dt, double scatter_ahead_budget_cells);
  void clear_grid(bool mass, bool momentum, bool force);
  void check_mass();
  void check_momentum(const MomentumTotals<Dim>& particles);
  void raise_unstable(std::size_t particle, const char* stage) const;
  /// With DDMPM sub-points: every particle shorter than two cells, so its sub-points stay within a cell of it.
  void check_subpoint_reach() const;
  /// The columns the basis is evaluated at: the positions, or the reference positions for a basis that moves with
  /// the body.
  Field basis_field() const;
  /// Fills the max-ent basis' stencil cache for this step's particle positions (no-op for other bases); with
  /// `fill` false, empties it.
  void cache_stencils(bool fill);

  Scene scene_;
  std::unique_ptr<Problem<Dim>> problem_;
  Material material_;
  AnyBasis<Dim> basis_;
  std::vector<Stencil<Dim, MaxEntAxis::width>> stencil_cache_;  ///< per particle, during a step (cache_stencils)
  ParticleStore<Dim> store_;
  GridState<Dim> grid_;
  CellBins<Dim> bins_;
  std::vector<std::string> pipeline_;
  Conservation conservation_;
  double particle_mass_ = 0.0;
  double empty_mass_ = 0.0;  ///< nodal mass at or below which a DOF counts as empty
  double dt_ = 0.0, time_ = 0.0;
  long step_ = 0, steps_total_ = 0;
  double moved_cells_ = std::numeric_limits<double>::infinity();  ///< bound on any particle's move since binning
  /// USL and MUSL: whether the run's step may scatter ahead (a direct mapping, no point loads, no DDMPM sub-points,
  /// no cached max-ent stencils) and the user allows it; whether the grid holds the next step's P2G.
  bool scatter_ahead_possible_ = false, scatter_ahead_allowed_ = false;
  bool grid_scattered_ahead_ = false;
  long steps_scattered_ahead_ = 0;
  int cg_iterations_ = 0;
  std::optional<ConsistentMassSolver<Dim>> mass_solver_;  ///< projection and consistent mass only
  std::vector<MomentumTotals<Dim>> block_momentum_;
  std::optional<GaussPoints<Dim>> gauss_;      ///< reconstructed mappings only
  std::optional<CellBins<Dim>> particle_cells_;  ///< particles by single cell, for the per-cell fits
};

extern template class Simulation<1>;
extern template class Simulation<2>;

}  // namespace mpm
