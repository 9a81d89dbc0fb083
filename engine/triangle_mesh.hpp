#pragma once
// A triangular background mesh in 2D (thesis §3.3, §6.1.2): nodes, counter-clockwise triangles, edge neighbours,
// the nodes on each side of the domain box, a bucket grid that locates a point in its triangle without a scan,
// and a colouring of the triangles for the lock-free scatter (no two triangles of one colour share a node).
#include <array>
#include <cstddef>
#include <string>
#include <vector>

namespace mpm {

using Point2 = std::array<double, 2>;

/// The point at reference coordinates (s, t) of the triangle (a, b, c): a + s (b − a) + t (c − a) (thesis eq. 6.14
/// inverted).
inline Point2 point_at(const Point2& a, const Point2& b, const Point2& c, double s, double t) {
  return {a[0] + s * (b[0] - a[0]) + t * (c[0] - a[0]), a[1] + s * (b[1] - a[1]) + t * (c[1] - a[1])};
}

class TriangleMesh {
 public:
  /// Checks and builds a mesh of the box [0, box₀] × [0, box₁]; `origin` (a file name) heads every error message.
  /// Throws SceneError naming the origin and the element for: no triangles, a node index out of range, an
  /// inverted (clockwise) or degenerate triangle (area ≤ 1e-12 × the box's area), an edge shared by more than two
  /// triangles (non-manifold), a node outside the box (beyond 1e-9 of its size).
  TriangleMesh(std::vector<Point2> nodes, std::vector<std::array<int, 3>> triangles, Point2 box,
               const std::string& origin);

  std::size_t node_count() const { return nodes_.size(); }
  std::size_t triangle_count() const { return triangles_.size(); }
  const std::vector<Point2>& nodes() const { return nodes_; }
  const std::vector<std::array<int, 3>>& triangles() const { return triangles_; }
  const std::array<int, 3>& triangle(std::size_t e) const { return triangles_[e]; }
  /// The triangle across the edge opposite vertex k of triangle e, or −1 on the boundary.
  int neighbour(std::size_t e, int k) const { return neighbours_[e][k]; }
  double area(std::size_t e) const { return areas_[e]; }
  /// Smallest altitude over all triangles: the length h of the explicit step's bound.
  double min_height() const { return min_height_; }
  const Point2& box() const { return box_; }
  const std::string& origin() const { return origin_; }

  /// Whether node i lies on side s of the box (0: x = 0, 1: x = box₀, 2: y = 0, 3: y = box₁), within 1e-9 of its size.
  bool on_side(std::size_t i, int side) const { return (side_bits_[i] >> side) & 1u; }

  /// The triangle that contains x (on an edge: the lowest-numbered of the triangles that share it), or −1.
  int locate(const Point2& x) const;
  /// As locate(x), first trying triangle `hint` (a particle's triangle at the last step: it rarely moves on). The
  /// hint is taken only for a point well inside it, where no other triangle contains the point, so the answer is
  /// locate(x)'s whatever the hint.
  int locate(const Point2& x, int hint) const;
  /// Barycentric coordinates of x in triangle e (λ_k belongs to vertex k; they sum to 1).
  std::array<double, 3> barycentric(std::size_t e, const Point2& x) const;

  /// The triangles grouped by colour: colour c is elements_by_colour()[colour_start(c) .. colour_start(c + 1)).
  /// No two triangles of one colour share a node. Greedy, in triangle order: the same for every run.
  int colours() const { return static_cast<int>(colour_starts_.size()) - 1; }
  int colour_start(int c) const { return colour_starts_[c]; }
  const std::vector<int>& elements_by_colour() const { return by_colour_; }

 private:
  std::vector<Point2> nodes_;
  std::vector<std::array<int, 3>> triangles_;
  std::vector<std::array<int, 3>> neighbours_;
  std::vector<double> areas_;
  std::vector<unsigned char> side_bits_;
  Point2 box_;
  std::string origin_;
  double min_height_ = 0.0;
  // bucket grid over the box: triangles whose bounding box meets bucket b are bucket_items_[bucket_starts_[b] ..)
  int buckets_x_ = 1, buckets_y_ = 1;
  std::vector<int> bucket_starts_, bucket_items_;
  std::vector<int> colour_starts_, by_colour_;
};

/// Reads a Gmsh mesh file (format 2.2 ASCII, and 4.1 ASCII) into a mesh of the box. Points (type 15) and lines
/// (type 1) are Gmsh's boundary entities and are skipped; any other element that is not a 3-node triangle (type 2) is
/// refused. Throws SceneError naming the file (and the element, by its Gmsh number, or the line) for a missing or
/// unreadable file, a syntax error, an unsupported element, and everything the TriangleMesh constructor refuses.
TriangleMesh read_gmsh(const std::string& path, Point2 box);

/// A mesh of the box made at run time: nx × ny rectangles, each split into two triangles along alternating
/// diagonals, with the interior nodes moved by up to `jitter` of a cell in each direction (seeded, reproducible).
/// Used by tests and benchmarks that need meshes of many sizes.
TriangleMesh make_jittered_mesh(Point2 box, int nx, int ny, double jitter, unsigned seed);

}  // namespace mpm
