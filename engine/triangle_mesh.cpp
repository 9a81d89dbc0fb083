#include "engine/triangle_mesh.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <utility>

#include "engine/scene.hpp"

namespace mpm {

namespace {

double signed_area(const Point2& a, const Point2& b, const Point2& c) {
  return 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
}

[[noreturn]] void refuse(const std::string& origin, std::size_t element, const std::string& what) {
  throw SceneError(origin + ": triangle " + std::to_string(element) + " " + what);
}

}  // namespace

TriangleMesh::TriangleMesh(std::vector<Point2> nodes, std::vector<std::array<int, 3>> triangles, Point2 box,
                           const std::string& origin)
    : nodes_(std::move(nodes)), triangles_(std::move(triangles)), box_(box), origin_(origin) {
  if (triangles_.empty()) throw SceneError(origin_ + ": the mesh has no triangles");
  if (!(box_[0] > 0 && box_[1] > 0)) throw SceneError(origin_ + ": the domain box (grid.length) must be positive");
  const double size = std::max(box_[0], box_[1]), tol = 1e-9 * size;
  side_bits_.assign(nodes_.size(), 0);
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    const Point2& x = nodes_[i];
    if (!std::isfinite(x[0]) || !std::isfinite(x[1]) || x[0] < -tol || x[0] > box_[0] + tol || x[1] < -tol ||
        x[1] > box_[1] + tol)
      throw SceneError(origin_ + ": node " + std::to_string(i) + " at (" + std::to_string(x[0]) + ", " +
                       std::to_string(x[1]) + ") lies outside the domain box (grid.length)");
    for (int d = 0; d < 2; ++d) {
      if (std::abs(x[d]) <= tol) side_bits_[i] |= 1u << (2 * d);
      if (std::abs(x[d] - box_[d]) <= tol) side_bits_[i] |= 1u << (2 * d + 1);
    }
  }
  // geometry: orientation, size, altitudes
  areas_.resize(triangles_.size());
  min_height_ = size;
  const double min_area = 1e-12 * box_[0] * box_[1];
  for (std::size_t e = 0; e < triangles_.size(); ++e) {
    for (int v : triangles_[e])
      if (v < 0 || static_cast<std::size_t>(v) >= nodes_.size())
        refuse(origin_, e, "names node " + std::to_string(v) + ", but the mesh has " + std::to_string(nodes_.size()));
    const auto& t = triangles_[e];
    const double a = signed_area(nodes_[t[0]], nodes_[t[1]], nodes_[t[2]]);
    if (a < -min_area) refuse(origin_, e, "is inverted (clockwise; area " + std::to_string(a) + ")");
    if (a <= min_area) refuse(origin_, e, "is degenerate (area " + std::to_string(a) + ")");
    areas_[e] = a;
    for (int k = 0; k < 3; ++k) {
      const Point2 &p = nodes_[t[(k + 1) % 3]], &q = nodes_[t[(k + 2) % 3]];
      min_height_ = std::min(min_height_, 2 * a / std::hypot(q[0] - p[0], q[1] - p[1]));
    }
  }
  // neighbours across edges: an edge (lower node, higher node) met at most twice
  neighbours_.assign(triangles_.size(), {-1, -1, -1});
  std::map<std::pair<int, int>, std::pair<int, int>> edges;  // edge → (triangle, local vertex opposite)
  for (std::size_t e = 0; e < triangles_.size(); ++e)
    for (int k = 0; k < 3; ++k) {
      const int a = triangles_[e][(k + 1) % 3], b = triangles_[e][(k + 2) % 3];
      const auto key = std::minmax(a, b);
      auto [it, fresh] = edges.try_emplace({key.first, key.second}, static_cast<int>(e), k);
      if (fresh) continue;
      const auto [f, j] = it->second;
      if (f < 0) refuse(origin_, e, "shares the edge of nodes " + std::to_string(a) + "–" + std::to_string(b) +
                                        " with two other triangles (the mesh is not manifold)");
      neighbours_[e][k] = f;
      neighbours_[f][j] = static_cast<int>(e);
      it->second = {-1, -1};  // seen twice: a third triangle on this edge is an error
    }
  // bucket grid: about two triangles per bucket
  const double cells = std::max(1.0, std::sqrt(triangles_.size() / 2.0));
  buckets_x_ = std::max(1, static_cast<int>(std::ceil(cells * std::sqrt(box_[0] / box_[1]))));
  buckets_y_ = std::max(1, static_cast<int>(std::ceil(cells * std::sqrt(box_[1] / box_[0]))));
  std::vector<std::array<int, 4>> ranges(triangles_.size());  // bucket index range of each triangle's bounding box
  bucket_starts_.assign(static_cast<std::size_t>(buckets_x_) * buckets_y_ + 1, 0);
  const auto bucket_of = [&](double x, int d) {
    const int n = d == 0 ? buckets_x_ : buckets_y_;
    return std::clamp(static_cast<int>(std::floor(x / box_[d] * n)), 0, n - 1);
  };
  for (std::size_t e = 0; e < triangles_.size(); ++e) {
    std::array<double, 4> bb{box_[0], 0, box_[1], 0};
    for (int v : triangles_[e])
      for (int d = 0; d < 2; ++d) {
        bb[2 * d] = std::min(bb[2 * d], nodes_[v][d]);
        bb[2 * d + 1] = std::max(bb[2 * d + 1], nodes_[v][d]);
      }
    ranges[e] = {bucket_of(bb[0], 0), bucket_of(bb[1], 0), bucket_of(bb[2], 1), bucket_of(bb[3], 1)};
    for (int by = ranges[e][2]; by <= ranges[e][3]; ++by)
      for (int bx = ranges[e][0]; bx <= ranges[e][1]; ++bx) ++bucket_starts_[by * buckets_x_ + bx + 1];
  }
  for (std::size_t b = 1; b < bucket_starts_.size(); ++b) bucket_starts_[b] += bucket_starts_[b - 1];
  bucket_items_.resize(bucket_starts_.back());
  std::vector<int> fill(bucket_starts_.begin(), bucket_starts_.end() - 1);
  for (std::size_t e = 0; e < triangles_.size(); ++e)
    for (int by = ranges[e][2]; by <= ranges[e][3]; ++by)
      for (int bx = ranges[e][0]; bx <= ranges[e][1]; ++bx) bucket_items_[fill[by * buckets_x_ + bx]++] = static_cast<int>(e);
  // greedy colouring: the lowest colour not used by a triangle sharing a node
  std::vector<std::vector<int>> at_node(nodes_.size());
  for (std::size_t e = 0; e < triangles_.size(); ++e)
    for (int v : triangles_[e]) at_node[v].push_back(static_cast<int>(e));
  std::vector<int> colour(triangles_.size(), -1);
  int colours = 0;
  for (std::size_t e = 0; e < triangles_.size(); ++e) {
    std::vector<bool> used(colours + 1, false);
    for (int v : triangles_[e])
      for (int f : at_node[v])
        if (colour[f] >= 0) used[colour[f]] = true;
    colour[e] = static_cast<int>(std::find(used.begin(), used.end(), false) - used.begin());
    colours = std::max(colours, colour[e] + 1);
  }
  colour_starts_.assign(colours + 1, 0);
  for (int c : colour) ++colour_starts_[c + 1];
  for (int c = 0; c < colours; ++c) colour_starts_[c + 1] += colour_starts_[c];
  by_colour_.resize(triangles_.size());
  std::vector<int> next(colour_starts_.begin(), colour_starts_.end() - 1);
  for (std::size_t e = 0; e < triangles_.size(); ++e) by_colour_[next[colour[e]]++] = static_cast<int>(e);
}

std::array<double, 3> TriangleMesh::barycentric(std::size_t e, const Point2& x) const {
  const auto& t = triangles_[e];
  const Point2 &a = nodes_[t[0]], &b = nodes_[t[1]], &c = nodes_[t[2]];
  const double inv = 0.5 / areas_[e];
  const double l1 = ((c[0] - a[0]) * (x[1] - a[1]) - (x[0] - a[0]) * (c[1] - a[1])) * -inv;
  const double l2 = ((b[0] - a[0]) * (x[1] - a[1]) - (x[0] - a[0]) * (b[1] - a[1])) * inv;
  return {1 - l1 - l2, l1, l2};
}

int TriangleMesh::locate(const Point2& x) const {
  if (!(x[0] >= 0 && x[0] <= box_[0] && x[1] >= 0 && x[1] <= box_[1])) return -1;
  const int bx = std::min(buckets_x_ - 1, static_cast<int>(x[0] / box_[0] * buckets_x_));
  const int by = std::min(buckets_y_ - 1, static_cast<int>(x[1] / box_[1] * buckets_y_));
  const int b = by * buckets_x_ + bx;
  // the candidates are in triangle order, so a point on a shared edge goes to the lowest-numbered triangle
  constexpr double on_edge = -1e-14;
  for (int i = bucket_starts_[b]; i < bucket_starts_[b + 1]; ++i) {
    const int e = bucket_items_[i];
    const auto l = barycentric(e, x);
    if (l[0] >= on_edge && l[1] >= on_edge && l[2] >= on_edge) return e;
  }
  return -1;
}

int TriangleMesh::locate(const Point2& x, int hint) const {
  if (hint >= 0) {
    constexpr double well_inside = 1e-12;  // far beyond locate's edge tolerance of 1e-14
    const auto l = barycentric(hint, x);
    if (l[0] > well_inside && l[1] > well_inside && l[2] > well_inside) return hint;
  }
  return locate(x);
}

TriangleMesh make_jittered_mesh(Point2 box, int nx, int ny, double jitter, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> shift(-jitter, jitter);
  const double hx = box[0] / nx, hy = box[1] / ny;
  std::vector<Point2> nodes;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      Point2 x{i * hx, j * hy};
      const double dx = shift(rng), dy = shift(rng);  // drawn for every node, so a node's shift is its own
      if (i > 0 && i < nx) x[0] += dx * hx;
      if (j > 0 && j < ny) x[1] += dy * hy;
      nodes.push_back(x);
    }
  std::vector<std::array<int, 3>> triangles;
  const auto id = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        triangles.push_back({a, b, c});
        triangles.push_back({a, c, d});
      } else {
        triangles.push_back({a, b, d});
        triangles.push_back({b, c, d});
      }
    }
  return TriangleMesh(std::move(nodes), std::move(triangles), box,
                      "jittered mesh " + std::to_string(nx) + "x" + std::to_string(ny));
}

}  // namespace mpm
