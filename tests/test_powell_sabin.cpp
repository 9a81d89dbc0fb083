// Quadratic C¹ Powell–Sabin splines (engine/powell_sabin.hpp) on a hand-made mesh and on jittered unstructured
// meshes: partition of unity, non-negativity, reproduction of quadratics, C¹ across the mesh's edges and inside the
// 6-split, exact gradients, and the functions that vanish on each side of the box.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "engine/powell_sabin.hpp"
#include "engine/triangle_mesh.hpp"

using namespace mpm;

namespace {

constexpr int per_element = PowellSabinBasis::per_element;

struct Evaluation {
  std::array<int, per_element> index;
  std::array<double, per_element> value;
  std::array<Point2, per_element> gradient;

  /// Position of global function f among the nine, or −1 (then the function is zero on the triangle).
  int position(int f) const {
    const auto it = std::find(index.begin(), index.end(), f);
    return it == index.end() ? -1 : static_cast<int>(it - index.begin());
  }
};

Evaluation evaluate(const PowellSabinBasis& basis, std::size_t e, const Point2& x) {
  Evaluation r;
  basis.evaluate(e, x, r.index, r.value, r.gradient);
  return r;
}

/// A unit square with one interior node, a node in the middle of the bottom side, and a corner (node 2) in only one
/// triangle.
TriangleMesh hand_made_mesh() {
  std::vector<Point2> nodes{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.4, 0.55}, {0.5, 0}};
  std::vector<std::array<int, 3>> triangles{{0, 5, 4}, {5, 1, 4}, {1, 3, 4}, {1, 2, 3}, {3, 0, 4}};
  return TriangleMesh(std::move(nodes), std::move(triangles), {1, 1}, "hand-made mesh");
}

std::vector<TriangleMesh> test_meshes() {
  std::vector<TriangleMesh> meshes{hand_made_mesh()};
  for (unsigned seed : {1u, 2u, 3u}) meshes.push_back(make_jittered_mesh({1, 1}, 6, 5, 0.25, seed));
  return meshes;
}

Point2 combination(const std::array<Point2, 3>& v, const std::array<double, 3>& w) {
  return {w[0] * v[0][0] + w[1] * v[1][0] + w[2] * v[2][0], w[0] * v[0][1] + w[1] * v[1][1] + w[2] * v[2][1]};
}

std::array<Point2, 3> corners(const TriangleMesh& mesh, std::size_t e) {
  const auto& t = mesh.triangle(e);
  return {mesh.nodes()[t[0]], mesh.nodes()[t[1]], mesh.nodes()[t[2]]};
}

/// Uniformly random barycentric coordinates, each at least `margin`.
std::array<double, 3> random_weights(std::mt19937_64& rng, double margin) {
  std::uniform_real_distribution<double> u(0, 1);
  double a = u(rng), b = u(rng);
  if (a + b > 1) a = 1 - a, b = 1 - b;
  const double scale = 1 - 3 * margin;
  return {margin + scale * a, margin + scale * b, margin + scale * (1 - a - b)};
}

// The 6-split, computed here independently of the basis: the incentre Z of each triangle, and on each edge the
// crossing of Z_e Z_f (interior) or the midpoint (boundary).
Point2 incentre(const TriangleMesh& mesh, std::size_t e) {
  const auto v = corners(mesh, e);
  std::array<double, 3> w;
  for (int m = 0; m < 3; ++m)
    w[m] = std::hypot(v[(m + 1) % 3][0] - v[(m + 2) % 3][0], v[(m + 1) % 3][1] - v[(m + 2) % 3][1]);
  const double sum = w[0] + w[1] + w[2];
  return combination(v, {w[0] / sum, w[1] / sum, w[2] / sum});
}

/// The split point of the edge opposite vertex k of triangle e.
Point2 edge_split(const TriangleMesh& mesh, std::size_t e, int k) {
  const auto v = corners(mesh, e);
  const Point2 &a = v[(k + 1) % 3], &b = v[(k + 2) % 3];
  const int f = mesh.neighbour(e, k);
  if (f < 0) return {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2};
  // solve a + t (b − a) = z + s (w − z) for t
  const Point2 z = incentre(mesh, e), w = incentre(mesh, f);
  const Point2 d{b[0] - a[0], b[1] - a[1]}, g{w[0] - z[0], w[1] - z[1]}, h{z[0] - a[0], z[1] - a[1]};
  const double t = (h[0] * g[1] - h[1] * g[0]) / (d[0] * g[1] - d[1] * g[0]);
  return {a[0] + t * d[0], a[1] + t * d[1]};
}

/// The six sub-triangles of triangle e: (V_{k+1}, R_k, Z) and (R_k, V_{k+2}, Z).
std::array<std::array<Point2, 3>, 6> sub_triangles(const TriangleMesh& mesh, std::size_t e) {
  const auto v = corners(mesh, e);
  const Point2 z = incentre(mesh, e);
  std::array<std::array<Point2, 3>, 6> subs;
  for (int k = 0; k < 3; ++k) {
    const Point2 r = edge_split(mesh, e, k);
    subs[2 * k] = {v[(k + 1) % 3], r, z};
    subs[2 * k + 1] = {r, v[(k + 2) % 3], z};
  }
  return subs;
}

double norm(const Point2& a) { return std::hypot(a[0], a[1]); }

/// Solves the 3 × 3 system m c = rhs by Cramer's rule.
std::array<double, 3> solve3(const std::array<std::array<double, 3>, 3>& m, const std::array<double, 3>& rhs) {
  const auto det = [](const std::array<std::array<double, 3>, 3>& a) {
    return a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
           a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  };
  const double d = det(m);
  std::array<double, 3> c;
  for (int col = 0; col < 3; ++col) {
    auto a = m;
    for (int row = 0; row < 3; ++row) a[row][col] = rhs[row];
    c[col] = det(a) / d;
  }
  return c;
}

struct Quadratic {
  double c, x, y, xx, xy, yy;  // c + x·x + y·y + xx·x² + xy·xy + yy·y²
  double value(const Point2& p) const {
    return c + x * p[0] + y * p[1] + xx * p[0] * p[0] + xy * p[0] * p[1] + yy * p[1] * p[1];
  }
  Point2 gradient(const Point2& p) const { return {x + 2 * xx * p[0] + xy * p[1], y + xy * p[0] + 2 * yy * p[1]}; }
};

}  // namespace

TEST_CASE("Powell-Sabin basis: three functions per node, indexed by the triangle's vertices", "[powell-sabin]") {
  const TriangleMesh mesh = hand_made_mesh();
  const PowellSabinBasis basis(mesh);
  CHECK(basis.function_count() == 3 * mesh.node_count());
  for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
    const auto r = evaluate(basis, e, incentre(mesh, e));
    for (int k = 0; k < 3; ++k)
      for (int j = 0; j < 3; ++j) CHECK(r.index[3 * k + j] == 3 * mesh.triangle(e)[k] + j);
  }
}

TEST_CASE("Powell-Sabin basis is a non-negative partition of unity", "[powell-sabin]") {
  std::mt19937_64 rng(5);
  double worst_sum = 0, worst_gradient_sum = 0, most_negative = 0;
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      std::vector<Point2> points;
      for (int p = 0; p < 200; ++p) points.push_back(combination(corners(mesh, e), random_weights(rng, 0)));
      for (const auto& sub : sub_triangles(mesh, e))
        for (const Point2& x : sub) points.push_back(x);  // vertices, split points, incentre
      for (const Point2& x : points) {
        const auto r = evaluate(basis, e, x);
        double sum = 0;
        Point2 gradient_sum{0, 0};
        for (int f = 0; f < per_element; ++f) {
          sum += r.value[f];
          gradient_sum[0] += r.gradient[f][0];
          gradient_sum[1] += r.gradient[f][1];
          most_negative = std::min(most_negative, r.value[f]);
        }
        worst_sum = std::max(worst_sum, std::abs(sum - 1));
        worst_gradient_sum = std::max(worst_gradient_sum, norm(gradient_sum));
      }
    }
  }
  CHECK(worst_sum <= 1e-13);
  CHECK(worst_gradient_sum <= 1e-11);
  CHECK(most_negative >= -1e-14);
}

TEST_CASE("Powell-Sabin splines reproduce quadratics, interpolating their values and gradients at the nodes",
          "[powell-sabin]") {
  // A PS spline is fixed by its values and gradients at the nodes (Powell & Sabin 1977), so the spline with the
  // Hermite data of a quadratic is that quadratic: at node i only its three functions are non-zero or have a
  // non-zero gradient, and their values and gradients there give a 3 × 3 system for the coefficients.
  const std::array<Quadratic, 7> quadratics{{{1, 0, 0, 0, 0, 0},
                                             {0, 1, 0, 0, 0, 0},
                                             {0, 0, 1, 0, 0, 0},
                                             {0, 0, 0, 1, 0, 0},
                                             {0, 0, 0, 0, 1, 0},
                                             {0, 0, 0, 0, 0, 1},
                                             {0.3, -1.2, 0.7, 2.5, -1.5, 0.8}}};
  std::mt19937_64 rng(7);
  double worst_value = 0, worst_gradient = 0, worst_hermite = 0;
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    // the Hermite data of each node's functions, from one triangle at the node
    std::vector<std::array<std::array<double, 3>, 3>> hermite(mesh.node_count());
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < 3; ++k) {
        const int node = mesh.triangle(e)[k];
        const auto r = evaluate(basis, e, mesh.nodes()[node]);
        for (int f = 0; f < per_element; ++f) {
          if (f / 3 == k) {
            hermite[node][0][f % 3] = r.value[f];
            hermite[node][1][f % 3] = r.gradient[f][0];
            hermite[node][2][f % 3] = r.gradient[f][1];
          } else {  // the other vertices' functions vanish at this node with their gradients
            worst_hermite = std::max({worst_hermite, std::abs(r.value[f]), norm(r.gradient[f])});
          }
        }
      }
    for (const Quadratic& q : quadratics) {
      std::vector<double> coefficient(basis.function_count());
      for (std::size_t i = 0; i < mesh.node_count(); ++i) {
        const Point2& x = mesh.nodes()[i];
        const Point2 g = q.gradient(x);
        const auto c = solve3(hermite[i], {q.value(x), g[0], g[1]});
        for (int j = 0; j < 3; ++j) coefficient[3 * i + j] = c[j];
      }
      for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
        for (int p = 0; p < 50; ++p) {
          const Point2 x = combination(corners(mesh, e), random_weights(rng, 0));
          const auto r = evaluate(basis, e, x);
          double value = 0;
          Point2 gradient{0, 0};
          for (int f = 0; f < per_element; ++f) {
            value += coefficient[r.index[f]] * r.value[f];
            gradient[0] += coefficient[r.index[f]] * r.gradient[f][0];
            gradient[1] += coefficient[r.index[f]] * r.gradient[f][1];
          }
          const Point2 exact = q.gradient(x);
          worst_value = std::max(worst_value, std::abs(value - q.value(x)));
          worst_gradient = std::max(worst_gradient, norm({gradient[0] - exact[0], gradient[1] - exact[1]}));
        }
    }
  }
  CHECK(worst_hermite <= 1e-12);
  CHECK(worst_value <= 1e-11);
  CHECK(worst_gradient <= 1e-11);
}

TEST_CASE("Powell-Sabin functions are C1 across every interior edge of the mesh", "[powell-sabin]") {
  // At a point of an edge shared by triangles e and f, the functions of both triangles must agree in value and
  // gradient; a function of only one of them (its opposite vertex's) must vanish there with its gradient.
  double worst = 0;
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    int edges = 0;
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < 3; ++k) {
        const int f = mesh.neighbour(e, k);
        if (f < static_cast<int>(e)) continue;  // boundary, or seen from f
        ++edges;
        const auto v = corners(mesh, e);
        const Point2 &a = v[(k + 1) % 3], &b = v[(k + 2) % 3];
        std::vector<Point2> points{edge_split(mesh, e, k), a, b};
        for (double t : {0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95})
          points.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
        for (const Point2& x : points) {
          const auto from_e = evaluate(basis, e, x), from_f = evaluate(basis, f, x);
          for (const auto& [mine, other] : {std::pair{&from_e, &from_f}, std::pair{&from_f, &from_e}})
            for (int p = 0; p < per_element; ++p) {
              const int q = other->position(mine->index[p]);
              const double value = q < 0 ? 0 : other->value[q];
              const Point2 gradient = q < 0 ? Point2{0, 0} : other->gradient[q];
              worst = std::max({worst, std::abs(mine->value[p] - value),
                                norm({mine->gradient[p][0] - gradient[0], mine->gradient[p][1] - gradient[1]})});
            }
        }
      }
    CHECK(edges > 0);
  }
  CHECK(worst <= 1e-11);
}

TEST_CASE("Powell-Sabin functions are C1 across the edges of the 6-split inside a triangle", "[powell-sabin]") {
  // On each side of a sub-edge Z–V_m or Z–R_k the functions are quadratics; each side's quadratic is extrapolated to
  // points of the sub-edge exactly from three points on a normal line (p(0) = 3 p(ε) − 3 p(2ε) + p(3ε), ∇p(0) =
  // 2 ∇p(ε) − ∇p(2ε)), and the two sides' values and gradients must agree.
  double worst = 0;
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      const Point2 z = incentre(mesh, e);
      const double eps = 1e-6 * std::sqrt(mesh.area(e));
      std::vector<Point2> ends;
      for (int k = 0; k < 3; ++k) {
        ends.push_back(mesh.nodes()[mesh.triangle(e)[k]]);
        ends.push_back(edge_split(mesh, e, k));
      }
      for (const Point2& w : ends) {
        const Point2 along{w[0] - z[0], w[1] - z[1]};
        const Point2 normal{-along[1] / norm(along), along[0] / norm(along)};
        for (double t : {0.2, 0.5, 0.8}) {
          const Point2 x{z[0] + t * along[0], z[1] + t * along[1]};
          std::array<Evaluation, 2> side_limit;
          for (int side = 0; side < 2; ++side) {
            const double sign = side == 0 ? 1 : -1;
            std::array<Evaluation, 3> at;
            for (int j = 0; j < 3; ++j) {
              const double offset = sign * (j + 1) * eps;
              at[j] = evaluate(basis, e, {x[0] + offset * normal[0], x[1] + offset * normal[1]});
            }
            for (int f = 0; f < per_element; ++f) {
              side_limit[side].value[f] = 3 * at[0].value[f] - 3 * at[1].value[f] + at[2].value[f];
              for (int d = 0; d < 2; ++d)
                side_limit[side].gradient[f][d] = 2 * at[0].gradient[f][d] - at[1].gradient[f][d];
            }
          }
          for (int f = 0; f < per_element; ++f) {
            const auto &g0 = side_limit[0].gradient[f], &g1 = side_limit[1].gradient[f];
            worst = std::max({worst, std::abs(side_limit[0].value[f] - side_limit[1].value[f]),
                              norm({g0[0] - g1[0], g0[1] - g1[1]})});
          }
        }
      }
    }
  }
  CHECK(worst <= 1e-11);
}

TEST_CASE("Powell-Sabin gradients equal centred differences of the values inside each sub-triangle",
          "[powell-sabin]") {
  // The functions are quadratic on each sub-triangle, so a centred difference is exact up to rounding.
  std::mt19937_64 rng(9);
  double worst = 0, largest = 0;
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e) {
      const double h = 1e-5 * std::sqrt(mesh.area(e));
      for (const auto& sub : sub_triangles(mesh, e))
        for (int p = 0; p < 5; ++p) {
          const Point2 x = combination(sub, random_weights(rng, 0.15));
          const auto r = evaluate(basis, e, x);
          for (int d = 0; d < 2; ++d) {
            Point2 plus = x, minus = x;
            plus[d] += h;
            minus[d] -= h;
            const auto rp = evaluate(basis, e, plus), rm = evaluate(basis, e, minus);
            for (int f = 0; f < per_element; ++f) {
              worst = std::max(worst, std::abs((rp.value[f] - rm.value[f]) / (2 * h) - r.gradient[f][d]));
              largest = std::max(largest, std::abs(r.gradient[f][d]));
            }
          }
        }
    }
  }
  CHECK(largest > 1);  // the gradients are not trivially zero
  CHECK(worst <= 1e-7);
}

TEST_CASE("Powell-Sabin touches_side: exactly the flagged functions are non-zero on each side of the box",
          "[powell-sabin]") {
  for (const TriangleMesh& mesh : test_meshes()) {
    INFO(mesh.origin());
    const PowellSabinBasis basis(mesh);
    // the largest |value| of each function on each side, sampled along the boundary edges
    std::vector<std::array<double, 4>> largest(basis.function_count(), {0, 0, 0, 0});
    for (std::size_t e = 0; e < mesh.triangle_count(); ++e)
      for (int k = 0; k < 3; ++k) {
        if (mesh.neighbour(e, k) >= 0) continue;
        const int a = mesh.triangle(e)[(k + 1) % 3], b = mesh.triangle(e)[(k + 2) % 3];
        for (int side = 0; side < 4; ++side) {
          if (!mesh.on_side(a, side) || !mesh.on_side(b, side)) continue;
          const Point2 &xa = mesh.nodes()[a], &xb = mesh.nodes()[b];
          for (int p = 0; p <= 20; ++p) {
            const double t = p / 20.0;
            const auto r = evaluate(basis, e, {xa[0] + t * (xb[0] - xa[0]), xa[1] + t * (xb[1] - xa[1])});
            for (int f = 0; f < per_element; ++f)
              largest[r.index[f]][side] = std::max(largest[r.index[f]][side], std::abs(r.value[f]));
          }
        }
      }
    for (std::size_t f = 0; f < basis.function_count(); ++f)
      for (int side = 0; side < 4; ++side) {
        INFO("function " << f << ", side " << side);
        if (basis.touches_side(f, side))
          CHECK(largest[f][side] > 1e-6);
        else
          CHECK(largest[f][side] <= 1e-14);
      }
    // a node on a side has one function that vanishes there (its PS triangle has an edge on the side), the other
    // two do not
    for (std::size_t i = 0; i < mesh.node_count(); ++i)
      for (int side = 0; side < 4; ++side) {
        int touching = 0;
        for (int j = 0; j < 3; ++j) touching += basis.touches_side(3 * i + j, side);
        CHECK(touching == (mesh.on_side(i, side) ? 2 : 0));
      }
  }
}
