#pragma once
// One explicit MPM run on a triangular background mesh (thesis §3.3, §6.1.2, §6.3.1): MPM with the P1 basis, with
// or without the TLS reconstruction, and PS-MPM with quadratic Powell–Sabin splines; USL or MUSL with the lumped
// mass, or with the consistent mass for the velocities (projection) or everywhere. The particles are located in their triangles by the mesh's bucket grid every step, and the scatter runs
// over the mesh's colours (no two triangles of a colour share a node): lock-free and, for any thread count,
// bitwise the same. The run's interface is Simulation<2>'s (run.cpp drives either).
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/consistent_mass.hpp"
#include "engine/material.hpp"
#include "engine/mesh_mass_matrix.hpp"
#include "engine/particle_measures.hpp"
#include "engine/particle_store.hpp"
#include "engine/powell_sabin.hpp"
#include "engine/problem.hpp"
#include "engine/scene.hpp"
#include "engine/triangle_mesh.hpp"
#include "engine/triangle_p1.hpp"
#include "kernels/reconstruction.hpp"

namespace mpm {

/// Nodal (P1) or spline-coefficient (PS) arrays of a mesh run, one entry per basis function.
struct MeshGrid {
  std::vector<double> m;
  std::array<std::vector<double>, 2> q, f, v, a;
  std::array<std::vector<unsigned char>, 2> fixed;  ///< the normal component fixed (1) per function and axis
};

class MeshSimulation {
 public:
  static constexpr int dim = 2;

  /// Builds the particles of a validated scene with grid.mesh. Throws SceneError for a scene it cannot run.
  explicit MeshSimulation(const Scene& scene);
  ~MeshSimulation();

  /// Advances one time step. Throws UnstableRun if a particle's state became invalid or it left the mesh.
  void step();

  bool finished() const { return step_ >= steps_total_; }
  /// Every step locates the particles afresh: any step resumes bitwise like the uninterrupted run.
  bool next_step_bins() const { return true; }
  long steps_done() const { return step_; }
  long steps_total() const { return steps_total_; }
  double time() const { return time_; }
  double dt() const { return dt_; }

  const Scene& scene() const { return scene_; }
  const TriangleMesh& mesh() const { return *scene_.grid.triangles; }
  ParticleStore<2>& particles() { return store_; }
  const ParticleStore<2>& particles() const { return store_; }
  const MeshGrid& grid() const { return grid_; }
  const std::vector<std::string>& pipeline() const { return pipeline_; }

  const Conservation& conservation() const { return conservation_; }
  bool has_exact() const { return problem_->has_exact(); }
  RunErrors errors() const {
    return particle_errors(store_, *problem_, time_, velocity_time(scene_.time.start, step_, time_, dt_));
  }
  Energy energy() const { return particle_energy(store_, material_); }
  /// The critical step κ h/(c + |v|) with h the mesh's smallest altitude, κ < 1 with the consistent mass.
  CriticalStep critical_step() const;
  double external_power() const;
  /// TLS fits that fell back to neighbour particles, a lower degree or a constant.
  FallbackCounts fallbacks() const { return fallbacks_; }
  /// CG iterations of the consistent-mass solves in the last step (0 for the lumped mass).
  int last_cg_iterations() const { return cg_iterations_; }

  SimulationState save_state() const { return save_particle_state(store_, step_, time_, conservation_); }
  void load_state(const SimulationState& state);

 private:
  template <class B, class M, class F>
  class Step;
  void locate_particles();
  void check_mass();
  void check_momentum();

  Scene scene_;
  std::unique_ptr<Problem<2>> problem_;
  Material material_;
  std::variant<TriangleP1, PowellSabinBasis> basis_;
  ParticleStore<2> store_;
  MeshGrid grid_;
  std::vector<int> element_;                     ///< per particle: its triangle at this step
  std::vector<int> element_start_, by_element_;  ///< the particles of triangle e: by_element_[start[e] .. start[e+1])
  std::vector<std::string> pipeline_;
  Conservation conservation_;
  FallbackCounts fallbacks_;
  std::optional<MeshMassMatrix> mass_matrix_;            ///< projection and consistent mass only
  std::optional<ConsistentMassSolver<2>> mass_solver_;  ///< its CG
  int cg_iterations_ = 0;
  double particle_mass_ = 0.0, empty_mass_ = 0.0;
  double dt_ = 0.0, time_ = 0.0;
  long step_ = 0, steps_total_ = 0;
};

}  // namespace mpm
