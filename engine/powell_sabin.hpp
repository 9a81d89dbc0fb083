#pragma once
// Quadratic C¹ Powell–Sabin splines on the Powell–Sabin 6-split of a triangulation (thesis §3.3; Powell & Sabin
// 1977, Dierckx 1997 "On calculating normalized Powell–Sabin B-splines"): three basis functions per mesh node,
// non-negative, a partition of unity, reproducing quadratics.
#include <array>
#include <cstddef>
#include <vector>

#include "engine/triangle_mesh.hpp"

namespace mpm {

class PowellSabinBasis {
 public:
  /// Functions non-zero on one triangle: the three of each of its vertices.
  static constexpr int per_element = 9;

  explicit PowellSabinBasis(const TriangleMesh& mesh);

  /// 3 × the mesh's nodes; function 3 i + j is the j-th function of node i.
  std::size_t function_count() const;

  /// Values and gradients at x (a point of triangle e) of the nine functions of e's vertices, in the order
  /// 3 × (vertex k of e) + j: index[3k + j] = 3 × triangle(e)[k] + j.
  void evaluate(std::size_t e, const Point2& x, std::array<int, per_element>& index,
                std::array<double, per_element>& value, std::array<Point2, per_element>& gradient) const;

  /// Whether function f is non-zero somewhere on side s of the domain box (0: x = 0, 1: x = box₀, 2: y = 0,
  /// 3: y = box₁). Fixing the normal component of these functions' coefficients fixes it along the whole side.
  bool touches_side(std::size_t f, int side) const;

  /// The six sub-triangles of triangle e's Powell–Sabin split, counter-clockwise: 2k is (V_{k+1}, R_k, Z) and
  /// 2k + 1 is (R_k, V_{k+2}, Z). On each the functions are quadratics, so a rule exact per sub-triangle
  /// integrates their gradients exactly, where one over the whole triangle does not (MeshSimulation's seeding).
  std::array<std::array<Point2, 3>, 6> split(std::size_t e) const;

 private:
  /// One triangle's Powell–Sabin 6-split and its nine functions. Sub-triangle 2k is (V_{k+1}, R_k, Z) and 2k + 1 is
  /// (R_k, V_{k+2}, Z), where Z is the split point inside and R_k the split point of the edge opposite vertex k
  /// (local vertex numbers mod 3). A function of vertex k is stored by its Bézier ordinates at the four PS points of
  /// V_k in this triangle (V_k and the midpoints of V_k Z, V_k R_{k+2}, V_k R_{k+1}); its other ordinates follow
  /// from C¹ (powell_sabin.cpp, spread).
  struct Element {
    Point2 origin;                                     // vertex 0: coordinates relative to it keep λ accurate
    std::array<std::array<double, 3>, 3> barycentric;  // λ_m(x) = [m][0] y₀ + [m][1] y₁ + [m][2], y = x − origin
    std::array<double, 3> centre;                      // ζ: Z = Σ ζ_m V_m
    std::array<double, 3> edge_split;                  // σ_k: R_k = σ_k V_{k+1} + (1 − σ_k) V_{k+2}
    std::array<std::array<double, 4>, per_element> ring;  // [3k + j][PS point of V_k]
    std::array<int, per_element> index;
  };

  const TriangleMesh* mesh_;
  std::vector<Element> elements_;
  std::vector<unsigned char> touches_;  // per function: bit s set iff it is non-zero somewhere on side s
};

}  // namespace mpm
