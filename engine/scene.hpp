#pragma once
// The typed, validated form of a scene file (DESIGN.md, "Scene file" contract).
// Every field has been range-checked by parse_scene(); the engine never sees raw JSON.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace mpm {

class TriangleMesh;

/// A scene that cannot be run: the message names the key (dotted path), the value and what was expected.
struct SceneError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

enum class Basis { linear, bspline2, bspline3, ddmpm, maxent, powell_sabin };
enum class BasisPath { fast, generic };
enum class Layout { uniform, gauss, random };
enum class MaterialModel { linear_elastic, neo_hookean };
enum class Update { usl, musl, usf, otm, unified };
enum class MassMatrix { lumped, projection, consistent };
enum class Mapping { direct, mls, tls, cubic_spline };
/// When the particle velocity is taken to live. The explicit update is leapfrog: a step from t to t + h computes the
/// grid velocity of t + h/2 and moves the particles with it, so the velocity a particle carries after the step is
/// v(t + h/2). `collocated` (the papers') starts from v(0) and reports the velocity as v(t); `staggered` starts
/// from the exact v(-dt/2) and compares with v(t - h/2), h the last step (RESULTS.md §6 measures the difference).
enum class TimeStart { collocated, staggered };
enum class ProblemName { none, vibrating_bar, vibrating_plate, column_compaction, vibrating_bar_traction };

/// OTM (thesis Algorithm 3) and the unified approach (Algorithm 4) carry their basis with the body: each particle
/// evaluates it at its reference position, and gradients are pulled back by F (simulation_impl.hpp, Step::usl).
constexpr bool basis_moves_with_body(Update u) { return u == Update::otm || u == Update::unified; }

/// Polynomial degree of a basis choice (DDMPM: its piecewise-linear values; max-ent: linear completeness).
constexpr int degree_of(Basis b) {
  return b == Basis::bspline2 || b == Basis::powell_sabin ? 2 : b == Basis::bspline3 ? 3 : 1;
}

/// DDMPM and max-ent number their functions with a ghost at each end of an axis (kernels/dual_domain.hpp).
constexpr bool has_ghost_ends(Basis b) { return b == Basis::ddmpm || b == Basis::maxent; }

/// Functions non-zero at a point, per axis: degree + 1 for B-splines; DDMPM's smoothed gradients and max-ent's
/// priors (d_max ≤ 2 cells) reach one node beyond each side of the cell.
constexpr int stencil_width_of(Basis b) { return has_ghost_ends(b) ? 4 : degree_of(b) + 1; }

/// Basis functions along an axis of `cells` cells: cells + degree on the open knot vector; the cells + 1 nodes
/// and a ghost function at each end for DDMPM and max-ent.
constexpr int functions_per_axis(Basis b, int cells) { return has_ghost_ends(b) ? cells + 3 : cells + degree_of(b); }

/// The function that carries the boundary value at the lower or upper end of an axis (the interpolatory end
/// function of the open knot vector; the end node, next to its ghost).
constexpr int boundary_function(Basis b, int cells, bool upper) {
  const int ghost = has_ghost_ends(b) ? 1 : 0;
  return upper ? functions_per_axis(b, cells) - 1 - ghost : ghost;
}

struct GridSpec {
  std::array<double, 3> length{1, 1, 1};  ///< domain [0, length] per axis, m
  std::array<int, 3> cells{1, 1, 1};      ///< knot spans per axis
  Basis basis = Basis::bspline2;
  BasisPath path = BasisPath::fast;
  double maxent_dmax = 2.0;  ///< max-ent prior support radius in cells (thesis eq. 4.47, d_max; 1 < d_max ≤ 2)
  std::string mesh;          ///< a triangle mesh file (2D) instead of `cells`; empty: the rectangular grid
  std::shared_ptr<const TriangleMesh> triangles;  ///< that mesh, read and checked by parse_scene
};

struct ParticleSpec {
  std::array<int, 3> per_cell{2, 2, 2};  ///< particles per cell and axis (uniform, gauss); total per cell (random: [0])
  Layout layout = Layout::uniform;
  std::uint64_t seed = 1;
};

struct MaterialSpec {
  MaterialModel model = MaterialModel::linear_elastic;
  double E = 1.0e6;         ///< Young's modulus, Pa
  double nu = 0.0;          ///< Poisson's ratio
  double density = 1000.0;  ///< reference density, kg/m^3
};

struct AlgorithmSpec {
  Update update = Update::musl;
  MassMatrix mass = MassMatrix::lumped;
  Mapping mapping = Mapping::direct;
  std::array<int, 3> gauss_per_cell{2, 2, 2};
  double mls_support = 2.0;  ///< MLS weight scaling in cells: r = (x - x_p) / (mls_support h); paper eq. 9 prints 2 (support ±3h)
  int tls_degree = 1;        ///< Taylor basis degree for TLS (0, 1, 2)
  int ddmpm_subpoints = 1;   ///< DDMPM (1D): internal-force integration points per particle (Dhakal & Zhang); 1: none
};

struct TimeSpec {
  std::optional<double> dt;   ///< fixed step, s
  std::optional<double> cfl;  ///< fraction of the critical step (replaces dt)
  double end = 0.0;           ///< end time, s
  /// Energy-balance guard (engine/energy_balance.hpp): the run stops (exit 3) when kinetic + strain energy exceeds
  /// E(0) + the work of the body forces by more than this fraction of the largest energy so far. 0.15 is chosen
  /// from the stability suite (docs/STABILITY.md, "Energy balance"): the completed, accurate runs gain at most 0.13
  /// (most below 0.001), the blow-ups 0.5–1.
  double energy_tolerance = 0.15;
  TimeStart start = TimeStart::collocated;
};

struct OutputSpec {
  std::string file;          ///< HDF5 output; empty: none
  int every = 0;             ///< snapshot interval in steps; 0: first and last only
  int checkpoint_every = 0;  ///< full-state interval in steps; 0: none
};

/// A rectangular body of a user-described scene.
struct BodySpec {
  std::array<double, 3> lo{0, 0, 0}, hi{0, 0, 0};
  std::array<double, 3> velocity{0, 0, 0};
  std::optional<MaterialSpec> material;  ///< the scene's material if absent
};

/// Parameters of a built-in problem (PROBLEMS.md); each problem reads the ones it knows.
struct ProblemSpec {
  ProblemName name = ProblemName::none;
  double v0 = 0.28;               ///< vibrating-bar: peak initial velocity, m/s
  double amplitude = 0.1;         ///< vibrating-plate: A, m
  double height = 50.0;           ///< column-compaction: H, m
  double max_body_force = -200.0; ///< column-compaction: b_f, m/s^2
  double ramp_time = 0.5;         ///< column-compaction: t_f, s
};

/// Sides are "x-", "x+", "y-", "y+" (, "z-", "z+"): axis = index / 2, upper = index % 2.
struct Scene {
  int dimension = 1;
  ProblemSpec problem;
  GridSpec grid;
  ParticleSpec particles;
  MaterialSpec material;
  AlgorithmSpec algorithm;
  TimeSpec time;
  OutputSpec output;
  std::vector<BodySpec> bodies;
  std::array<double, 3> gravity{0, 0, 0};
  std::vector<int> fixed_sides;  ///< normal component fixed on these sides (0: x-, 1: x+, 2: y-, ...)
  nlohmann::json source;         ///< the scene as given, after --set overrides and with defaults filled in
};

/// Parses and validates a scene. Throws SceneError naming the key, value and expectation.
Scene parse_scene(const nlohmann::json& j);
/// Reads a file (a JSON syntax error gives line and column) and parses it.
Scene load_scene_file(const std::string& path);
/// Reads a scene file as JSON (a directory or an unreadable file is a SceneError naming the path).
nlohmann::json read_json_file(const std::string& path);
/// Reads JSON text; `origin` names it in error messages. Nesting deeper than any scene needs is refused.
nlohmann::json read_json_text(const std::string& text, const std::string& origin);
/// Applies one `--set KEY=VALUE` override (dotted path, JSON value or bare string) to a raw scene.
void apply_override(nlohmann::json& scene, const std::string& assignment);

}  // namespace mpm
