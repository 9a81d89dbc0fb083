#pragma once
// The piecewise-linear (P1) basis of a triangle mesh: on triangle e, φ_k = λ_k, the barycentric coordinate of its
// vertex k, with a gradient constant over the triangle. The same interface as PowellSabinBasis, so the mesh kernels
// take either.
#include <array>
#include <cstddef>
#include <vector>

#include "engine/triangle_mesh.hpp"

namespace mpm {

class TriangleP1 {
 public:
  static constexpr int per_element = 3;

  explicit TriangleP1(const TriangleMesh& mesh) : mesh_(&mesh), gradients_(mesh.triangle_count()) {
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      const auto& t = mesh.triangle(e);
      const double inv2a = 0.5 / mesh.area(e);
      for (int k = 0; k < 3; ++k) {
        // ∇λ_k is the inward normal of the opposite edge over twice the area
        const Point2 &p = mesh.nodes()[t[(k + 1) % 3]], &q = mesh.nodes()[t[(k + 2) % 3]];
        gradients_[e][k] = {(p[1] - q[1]) * inv2a, (q[0] - p[0]) * inv2a};
      }
    }
  }

  std::size_t function_count() const { return mesh_->node_count(); }

  void evaluate(std::size_t e, const Point2& x, std::array<int, per_element>& index,
                std::array<double, per_element>& value, std::array<Point2, per_element>& gradient) const {
    value = mesh_->barycentric(e, x);
    index = mesh_->triangle(e);
    gradient = gradients_[e];
  }

  bool touches_side(std::size_t f, int side) const { return mesh_->on_side(f, side); }

 private:
  const TriangleMesh* mesh_;
  std::vector<std::array<Point2, 3>> gradients_;
};

}  // namespace mpm
