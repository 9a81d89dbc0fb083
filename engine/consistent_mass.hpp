#pragma once
// The consistent-mass solve M x = b on the free DOFs (thesis eqs 3.9–3.10), per component, by conjugate gradients
// with the lumped mass as (Jacobi) preconditioner. M is assembled once per solve into band storage from its
// carriers (assemble_consistent_mass: particles, or the Gauss points of a reconstruction), in coloured blocks;
// every vector loop is a parallel loop over DOFs and every dot product a deterministic_sum, so the result is
// bitwise the same for any thread count.
//
// Measured on tools/scenes/plate.json with algorithm.mass = projection (docs/ARCHITECTURE.md): applying M
// matrix-free — a gather to every carrier and a scatter back, once per CG iteration — made the step 15× the
// lumped step; the banded product per iteration touches 25 numbers per DOF instead of every carrier.
#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "engine/cell_bins.hpp"
#include "engine/deterministic_sum.hpp"
#include "engine/parallel_over.hpp"
#include "kernels/transfer.hpp"

namespace mpm {

template <int Dim>
class ConsistentMassSolver {
 public:
  static constexpr double tolerance = 1e-14;  ///< relative residual per component
  static constexpr int max_iterations = 1000;

  /// Work arrays for `dofs` DOFs.
  explicit ConsistentMassSolver(int dofs) : dofs_(dofs) {
    for (int d = 0; d < Dim; ++d)
      for (auto* a : {&r_[d], &z_[d], &p_[d], &Ap_[d]}) a->assign(dofs, 0.0);
  }

  /// M from `carriers` binned by `bins`, for the solves that follow (the carriers do not move within a step).
  template <class B>
  void assemble(const B& basis, MassCarriers<Dim> carriers, const CellBins<Dim>& bins, int stride1) {
    constexpr int S = B::width;
    band_.assign(static_cast<std::size_t>(dofs_) * mass_band<Dim, S>, 0.0);
    const unsigned* order = bins.order().data();
    bins.for_each_block_coloured([&](std::size_t b, std::size_t e) {
      assemble_consistent_mass<Dim, S>(basis, carriers, stride1, band_.data(), order, b, e);
    });
  }

  /// x = M⁻¹ rhs on the DOFs where free(d, i), 0 elsewhere, with the M last assembled for stencils of width S;
  /// `lumped` its row sums. Returns the CG iterations.
  template <int S, class Free>
  int solve(int stride1, const std::vector<double>& lumped, const Free& free, std::array<std::vector<double>, Dim>& x,
            const std::array<std::vector<double>, Dim>& rhs) {
    return solve_with([&](const auto& in, auto& out) { multiply<S>(stride1, in, out); }, lumped, free, x, rhs);
  }

  /// x = M⁻¹ rhs as solve does, for an M that `apply_mass(x, y)` applies (y = M x, all components), e.g. a mesh's
  /// sparse M (MeshSimulation).
  template <class Multiply, class Free>
  int solve_with(const Multiply& apply_mass, const std::vector<double>& lumped, const Free& free,
                 std::array<std::vector<double>, Dim>& x, const std::array<std::vector<double>, Dim>& rhs) {
    const double* m = lumped.data();
    // start from the lumped solution, masked
    for_each_dof([&](int d, std::size_t i) { x[d][i] = free(d, i) ? rhs[d][i] / m[i] : 0.0; });
    apply_mass(x, Ap_);
    for_each_dof([&](int d, std::size_t i) {
      const bool f = free(d, i);
      r_[d][i] = f ? rhs[d][i] - Ap_[d][i] : 0.0;
      z_[d][i] = f ? r_[d][i] / m[i] : 0.0;
      p_[d][i] = z_[d][i];
    });
    std::array<double, Dim> rz, norm_b;
    std::array<bool, Dim> done{};
    for (int d = 0; d < Dim; ++d) {
      rz[d] = dot(r_[d], z_[d]);
      norm_b[d] = std::sqrt(deterministic_sum(dofs_, [&](std::size_t i) { return free(d, i) ? rhs[d][i] * rhs[d][i] : 0.0; }));
    }
    int it = 0;
    for (; it < max_iterations; ++it) {
      bool all_done = true;
      for (int d = 0; d < Dim; ++d) {
        done[d] = std::sqrt(dot(r_[d], r_[d])) <= tolerance * norm_b[d];
        all_done = all_done && done[d];
      }
      if (all_done) break;
      apply_mass(p_, Ap_);
      for (int d = 0; d < Dim; ++d)
        if (!done[d]) rz[d] = iterate(d, free, m, rz[d], x[d]);
    }
    return it;
  }

 private:
  /// One CG update of component d: x += α p, r −= α Ap, z = r / m, p = z + β p. Returns the new r·z.
  template <class Free>
  double iterate(int d, const Free& free, const double* m, double rz, std::vector<double>& x) {
    double* r = r_[d].data();
    double* z = z_[d].data();
    double* p = p_[d].data();
    const double* Ap = Ap_[d].data();
    const double alpha = rz / deterministic_sum(dofs_, [&](std::size_t i) { return free(d, i) ? p[i] * Ap[i] : 0.0; });
    parallel_over(dofs_, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        if (!free(d, i)) continue;
        x[i] += alpha * p[i];
        r[i] -= alpha * Ap[i];
        z[i] = r[i] / m[i];
      }
    });
    const double rz_new = dot(r_[d], z_[d]);
    const double beta = rz_new / rz;
    parallel_over(dofs_, 4096, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) p[i] = free(d, i) ? z[i] + beta * p[i] : 0.0;
    });
    return rz_new;
  }

  /// y = M x, all components, a row per DOF. Rows whose band lies inside [0, dofs) skip the bounds test.
  template <int S>
  void multiply(int stride1, const std::array<std::vector<double>, Dim>& x, std::array<std::vector<double>, Dim>& y) {
    constexpr int W = 2 * S - 1, rows = Dim == 1 ? 1 : W;
    const long n = dofs_, row_step = Dim == 1 ? 0 : stride1;
    const long reach = (S - 1) * (1 + row_step);  // the farthest |j − i| in the band
    parallel_over(dofs_, 1024, [&](std::size_t b, std::size_t e) {
      std::array<const double*, Dim> xs;
      for (int d = 0; d < Dim; ++d) xs[d] = x[d].data();
      for (std::size_t i = b; i < e; ++i) {
        const double* row = band_.data() + i * mass_band<Dim, S>;
        const long li = static_cast<long>(i);
        const bool inside = li >= reach && li + reach < n;
        double sum[Dim] = {};
        for (int o1 = 0; o1 < rows; ++o1) {
          const long first = li - (S - 1) + row_step * (o1 - (S - 1));
          for (int o0 = 0; o0 < W; ++o0) {
            const long j = first + o0;
            if (!inside && (j < 0 || j >= n)) continue;  // no function there, and no entry in the band
            for (int d = 0; d < Dim; ++d) sum[d] += row[o1 * W + o0] * xs[d][j];
          }
        }
        for (int d = 0; d < Dim; ++d) y[d][i] = sum[d];
      }
    });
  }

  double dot(const std::vector<double>& a, const std::vector<double>& b) const {
    return deterministic_sum(dofs_, [&](std::size_t i) { return a[i] * b[i]; });
  }

  template <class F>
  void for_each_dof(F&& f) const {
    parallel_over(dofs_, 4096, [&](std::size_t b, std::size_t e) {
      for (int d = 0; d < Dim; ++d)
        for (std::size_t i = b; i < e; ++i) f(d, i);
    });
  }

  int dofs_;
  std::vector<double> band_;  ///< M, mass_band entries per DOF (assemble_consistent_mass)
  std::array<std::vector<double>, Dim> r_, z_, p_, Ap_;
};

}  // namespace mpm
