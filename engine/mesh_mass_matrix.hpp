#pragma once
// The consistent mass of a basis on a triangle mesh, M_ab = Σ_p m_p φ_a(x_p) φ_b(x_p) (thesis eq. 3.9), in
// compressed rows with the pattern of the functions that share a triangle. Each triangle knows where its K × K
// block lands, so the assembly runs over the mesh's colouring like the scatter (rows of one colour are disjoint:
// lock-free and the same sums in the same order on any thread count); the product is a parallel loop over rows.
#include <algorithm>
#include <array>
#include <cstddef>
#include <vector>

#include "engine/parallel_over.hpp"
#include "engine/triangle_mesh.hpp"

namespace mpm {

class MeshMassMatrix {
 public:
  /// The pattern of `basis` (TriangleP1 or PowellSabinBasis) on `mesh`.
  template <class B>
  MeshMassMatrix(const TriangleMesh& mesh, const B& basis) {
    constexpr int K = B::per_element;
    const std::size_t n = basis.function_count();
    std::vector<std::array<int, K>> functions(mesh.triangle_count());
    std::vector<std::vector<int>> rows(n);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      std::array<double, K> w;
      std::array<Point2, K> g;
      const auto& t = mesh.triangle(e);
      Point2 centroid{0, 0};
      for (int v : t)
        for (int d = 0; d < 2; ++d) centroid[d] += mesh.nodes()[v][d] / 3;
      basis.evaluate(e, centroid, functions[e], w, g);  // the functions of e, in evaluate's order
      for (int a : functions[e]) rows[a].insert(rows[a].end(), functions[e].begin(), functions[e].end());
    }
    row_start_.assign(n + 1, 0);
    for (std::size_t a = 0; a < n; ++a) {
      std::sort(rows[a].begin(), rows[a].end());
      rows[a].erase(std::unique(rows[a].begin(), rows[a].end()), rows[a].end());
      row_start_[a + 1] = row_start_[a] + static_cast<int>(rows[a].size());
      columns_.insert(columns_.end(), rows[a].begin(), rows[a].end());
    }
    values_.assign(columns_.size(), 0.0);
    slots_.resize(mesh.triangle_count() * K * K);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < K; ++k)
        for (int l = 0; l < K; ++l) {
          const int a = functions[e][k];
          const auto row = columns_.begin() + row_start_[a], end = columns_.begin() + row_start_[a + 1];
          slots_[(e * K + k) * K + l] = static_cast<int>(std::lower_bound(row, end, functions[e][l]) - columns_.begin());
        }
  }

  void clear() { std::fill(values_.begin(), values_.end(), 0.0); }

  /// Adds m φ_k φ_l of one carrier in triangle e (`w` the values of e's functions, in evaluate's order).
  template <std::size_t K>
  void add(std::size_t e, const std::array<double, K>& w, double m) {
    const int* slot = slots_.data() + e * K * K;
    for (std::size_t k = 0; k < K; ++k)
      for (std::size_t l = 0; l < K; ++l) values_[slot[k * K + l]] += m * w[k] * w[l];
  }

  /// y = M x, both components.
  void multiply(const std::array<std::vector<double>, 2>& x, std::array<std::vector<double>, 2>& y) const {
    parallel_over(row_start_.size() - 1, 1024, [&](std::size_t b, std::size_t e) {
      for (std::size_t a = b; a < e; ++a) {
        double sum[2] = {0, 0};
        for (int j = row_start_[a]; j < row_start_[a + 1]; ++j)
          for (int d = 0; d < 2; ++d) sum[d] += values_[j] * x[d][columns_[j]];
        for (int d = 0; d < 2; ++d) y[d][a] = sum[d];
      }
    });
  }

 private:
  std::vector<int> row_start_, columns_;
  std::vector<double> values_;
  std::vector<int> slots_;  ///< per triangle, K × K positions in values_
};

}  // namespace mpm
