#pragma once
// Plain views of the particle columns and grid arrays a kernel reads or writes: pointers only, no ownership.
// A pointer a scene does not need is null, and the kernels that would read it are not instantiated.
// Kernels take views by value: a copy whose address never escapes keeps its pointers in registers. Through a
// reference GCC reloaded them after every SIMD store (which may alias anything) and every libm call.
#include <array>
#include <atomic>
#include <cstddef>
#include <limits>

namespace mpm {

/// Number of independent Cauchy stress components stored per particle (symmetric tensor).
template <int Dim>
inline constexpr int sym_components = Dim * (Dim + 1) / 2;

/// Index of σ_ab in the packed symmetric storage: 1D s00; 2D s00, s01, s11.
template <int Dim>
constexpr int sym_index(int a, int b) {
  if constexpr (Dim == 1) return 0;
  else return a == b ? (a == 0 ? 0 : 2) : 1;
}

/// Points that carry mass, the integration points of the consistent mass M_ij = Σ φ_i m φ_j (thesis eq. 3.9):
/// the particles, or the Gauss points of a reconstructed mapping.
template <int Dim>
struct MassCarriers {
  std::array<const double*, Dim> x{};
  const double* m = nullptr;
};

template <int Dim>
struct ParticleView {
  std::array<double*, Dim> x{};               ///< current position
  std::array<const double*, Dim> X{};         ///< reference position (only with body force or exact solution)
  std::array<double*, Dim> v{};               ///< velocity
  std::array<double*, Dim * Dim> F{};         ///< deformation gradient, row-major F_ab
  std::array<double*, sym_components<Dim>> s{};  ///< Cauchy stress, packed symmetric
  const double* m = nullptr;                  ///< mass (constant)
  const double* V0 = nullptr;                 ///< initial volume
  /// The particles as mass carriers, at their current positions or (`reference`) their reference positions.
  MassCarriers<Dim> carriers(bool reference = false) const {
    MassCarriers<Dim> c;
    for (int d = 0; d < Dim; ++d) c.x[d] = reference ? X[d] : x[d];
    c.m = m;
    return c;
  }
};

template <int Dim>
struct GridView {
  int stride1 = 0;  ///< number of functions along axis 0
  int dofs = 0;
  double* m = nullptr;                 ///< lumped (row-sum) mass
  std::array<double*, Dim> q{};        ///< momentum
  std::array<double*, Dim> f{};        ///< force
  std::array<double*, Dim> v{};        ///< velocity
  std::array<double*, Dim> a{};        ///< acceleration
};

/// What the gathers report about the particles they moved: the first particle (lowest index) whose state became
/// invalid — non-finite values, J ≤ 0, or a position outside the grid — and the largest move along an axis, in
/// cells (when to bin the particles again). Both are order-independent (a minimum, a maximum), so they do not
/// depend on the thread count; flagging is rare and the maximum is merged once per range, so the compare-and-swap
/// loops cost nothing in practice.
struct ParticleGuard {
  static constexpr std::size_t none = std::numeric_limits<std::size_t>::max();
  std::array<double, 3> hi{};     ///< the grid is [0, hi] per axis
  std::array<double, 3> inv_h{};  ///< cells per unit length, per axis
  std::atomic<std::size_t> first_bad{none};
  std::atomic<double> max_move_cells{0.0};
  void flag(std::size_t p) {
    std::size_t cur = first_bad.load(std::memory_order_relaxed);
    while (p < cur && !first_bad.compare_exchange_weak(cur, p, std::memory_order_relaxed)) {
    }
  }
  void moved(double cells) {
    double cur = max_move_cells.load(std::memory_order_relaxed);
    while (cells > cur && !max_move_cells.compare_exchange_weak(cur, cells, std::memory_order_relaxed)) {
    }
  }
};

}  // namespace mpm
