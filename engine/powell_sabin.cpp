#include "engine/powell_sabin.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>
#include <vector>

namespace mpm {

// The construction (Dierckx 1997 "On calculating normalized Powell–Sabin B-splines"; Speleers, Manni, Pelosi &
// Sampoli 2012 "Isogeometric analysis with Powell–Sabin splines"):
//  1. the PS 6-split: Z inside each triangle (its incentre), R on each edge (where Z_e Z_f crosses an interior edge,
//     the midpoint of a boundary edge), six sub-triangles (V, R, Z);
//  2. a PS spline is fixed by its value and gradient at the mesh vertices (Powell & Sabin 1977), and on every
//     sub-triangle it is a quadratic Bézier polynomial whose ordinates follow from those data and C¹ (spread);
//  3. B_i^j, j = 0..2, has the Hermite data of the barycentric coordinate λ_j of a "PS triangle" t_i around V_i
//     (Dierckx: B_i^j(V_i) = α_ij = λ_j(V_i), the barycentric coordinates of V_i in t_i, and ∇B_i^j(V_i) =
//     (β_ij, γ_ij) = ∇λ_j) and zero data at the other vertices. Σ_j λ_j = 1 makes the B_i^j a partition of
//     unity; the Bézier ordinates at the PS points of V_i (V_i and the midpoints of the 6-split's edges at V_i) are
//     λ_j there, and every other ordinate is a convex combination of them, so the B_i^j are non-negative iff t_i
//     contains the PS points (Dierckx; Vanraes, Dierckx & Bultheel "On the choice of the PS-triangles").
// Linear functions are reproduced with coefficients their values at the PS triangles' corners, quadratics with the
// linear Taylor polynomial at V_i evaluated at the corners (both from the Hermite data above).

namespace {

constexpr double pi = std::numbers::pi;

Point2 difference(const Point2& a, const Point2& b) { return {a[0] - b[0], a[1] - b[1]}; }
Point2 half_of(const Point2& a) { return {0.5 * a[0], 0.5 * a[1]}; }
double cross(const Point2& a, const Point2& b) { return a[0] * b[1] - a[1] * b[0]; }
double dot(const Point2& a, const Point2& b) { return a[0] * b[0] + a[1] * b[1]; }
Point2 unit(double angle) { return {std::cos(angle), std::sin(angle)}; }

/// An affine function g · y + c of the plane.
struct Affine {
  double gx = 0, gy = 0, c = 0;
  double operator()(const Point2& y) const { return gx * y[0] + gy * y[1] + c; }
};

/// The barycentric coordinate of corner j of triangle q: 1 at q_j, 0 on the opposite edge.
Affine barycentric_coordinate(const std::array<Point2, 3>& q, int j) {
  const Point2 &a = q[(j + 1) % 3], &b = q[(j + 2) % 3];
  const Point2 edge = difference(b, a);
  const double scale = 1.0 / cross(edge, difference(q[j], a));
  // cross(edge, y − a) = edge_x (y_y − a_y) − edge_y (y_x − a_x)
  return {-edge[1] * scale, edge[0] * scale, (edge[1] * a[0] - edge[0] * a[1]) * scale};
}

/// Barycentric coordinates of a triangle's incentre: proportional to the opposite edge lengths. The incentres of two
/// triangles sharing an edge lie on their angle bisectors, so the segment between them crosses that edge in its
/// interior — the condition of the PS 6-split for a C¹ spline (Powell & Sabin 1977; Lai & Schumaker 2007).
std::array<double, 3> incentre(const std::array<Point2, 3>& v) {
  std::array<double, 3> side;
  for (int m = 0; m < 3; ++m) {
    const Point2 edge = difference(v[(m + 2) % 3], v[(m + 1) % 3]);
    side[m] = std::hypot(edge[0], edge[1]);
  }
  const double perimeter = side[0] + side[1] + side[2];
  return {side[0] / perimeter, side[1] / perimeter, side[2] / perimeter};
}

Point2 combination(const std::array<Point2, 3>& v, const std::array<double, 3>& w) {
  return {w[0] * v[0][0] + w[1] * v[1][0] + w[2] * v[2][0], w[0] * v[0][1] + w[1] * v[1][1] + w[2] * v[2][1]};
}

/// Parameter t of R = A + t (B − A), where segment Z_e Z_f crosses edge AB (Z_e left of A→B, Z_f right of it).
double crossing(const Point2& a, const Point2& b, const Point2& z_e, const Point2& z_f) {
  const Point2 edge = difference(b, a);
  const double left = cross(edge, difference(z_e, a)), right = cross(edge, difference(z_f, a));
  const double mu = left / (left - right);
  const Point2 r{z_e[0] + mu * (z_f[0] - z_e[0]), z_e[1] + mu * (z_f[1] - z_e[1])};
  return dot(difference(r, a), edge) / dot(edge, edge);
}

// ---- the PS triangle of a vertex ----------------------------------------------------------------------------

/// A triangle as the intersection of three half-planes n_k · y ≤ h_k (unit outward normals), y relative to the vertex.
/// A fixed line lies on a side of the box; a free line is moved onto the points (h_k is their support), so the
/// triangle touches them.
struct HalfPlanes {
  std::array<Point2, 3> normal{};
  std::array<double, 3> offset{};
  std::array<int, 3> side{-1, -1, -1};  // the box side of a fixed line, −1 for a free line
};

/// Corner q_k of the triangle is opposite line k, where lines k + 1 and k + 2 meet. False when the normals do not
/// positively span the plane (all three turns between successive normals of one sign): the region is unbounded.
bool corners(const HalfPlanes& t, std::array<Point2, 3>& q) {
  const auto& n = t.normal;
  constexpr double min_turn = 1e-3;  // sine of the smallest turn between two normals: nearly parallel lines refused
  const double orientation = cross(n[0], n[1]) > 0 ? 1.0 : -1.0;
  for (int k = 0; k < 3; ++k)
    if (orientation * cross(n[k], n[(k + 1) % 3]) < min_turn) return false;
  for (int k = 0; k < 3; ++k) {
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double det = cross(n[a], n[b]);  // Cramer's rule for n_a · y = h_a, n_b · y = h_b
    q[k] = {(t.offset[a] * n[b][1] - t.offset[b] * n[a][1]) / det,
            (n[a][0] * t.offset[b] - n[b][0] * t.offset[a]) / det};
  }
  return true;
}

/// Moves the free lines onto the points and finds the corners; the area of the triangle, or +∞ if unbounded.
double enclosing_area(HalfPlanes& t, const std::vector<Point2>& points, std::array<Point2, 3>& q) {
  for (int k = 0; k < 3; ++k) {
    if (t.side[k] >= 0) continue;
    t.offset[k] = -std::numeric_limits<double>::infinity();
    for (const Point2& p : points) t.offset[k] = std::max(t.offset[k], dot(t.normal[k], p));
  }
  if (!corners(t, q)) return std::numeric_limits<double>::infinity();
  return 0.5 * std::abs(cross(difference(q[1], q[0]), difference(q[2], q[0])));
}

double enclosing_area(HalfPlanes& t, const std::vector<Point2>& points) {
  std::array<Point2, 3> q;
  return enclosing_area(t, points, q);
}

/// The starting lines: one on each box side the vertex lies on (an edge of the PS triangle along the side, as for
/// boundary conditions in Speleers et al. 2012: then one B-spline of the vertex vanishes on the side), the free ones
/// at equal turns. With no side, the best-fitting rotation of an equilateral triangle, sampled every 5°.
HalfPlanes starting_lines(const std::vector<std::pair<int, double>>& sides, const std::vector<Point2>& points) {
  // outward normal angle of each box side: x = 0, x = box₀, y = 0, y = box₁
  constexpr std::array<double, 4> outward{pi, 0, -pi / 2, pi / 2};
  HalfPlanes t;
  for (std::size_t k = 0; k < sides.size(); ++k) {
    t.side[k] = sides[k].first;
    t.normal[k] = unit(outward[sides[k].first]);
    t.offset[k] = sides[k].second;
  }
  if (sides.size() == 2) {  // a corner: the third normal points away from the two sides
    const Point2 away{-(t.normal[0][0] + t.normal[1][0]), -(t.normal[0][1] + t.normal[1][1])};
    t.normal[2] = {away[0] / std::hypot(away[0], away[1]), away[1] / std::hypot(away[0], away[1])};
  } else if (sides.size() == 1) {
    const double angle = outward[sides[0].first];
    t.normal[1] = unit(angle + 2 * pi / 3);
    t.normal[2] = unit(angle + 4 * pi / 3);
  } else {
    double best = std::numeric_limits<double>::infinity();
    for (int step = 0; step < 24; ++step) {
      HalfPlanes trial;
      for (int k = 0; k < 3; ++k) trial.normal[k] = unit(step * pi / 36 + k * 2 * pi / 3);
      const double area = enclosing_area(trial, points);
      if (area < best) best = area, t = trial;
    }
  }
  return t;
}

/// A small triangle containing the points (Dierckx 1997 takes the smallest; any containing one gives a
/// non-negative basis, a small one a better-conditioned one): a pattern search over the free lines' directions,
/// each step tried both ways and halved when neither helps, down to about 0.1°.
HalfPlanes small_enclosing_triangle(const std::vector<std::pair<int, double>>& sides,
                                    const std::vector<Point2>& points) {
  HalfPlanes t = starting_lines(sides, points);
  double best = enclosing_area(t, points);
  for (double step = pi / 36; step > 2e-3; step /= 2) {
    const double c = std::cos(step), s = std::sin(step);
    for (bool improved = true; improved;) {
      improved = false;
      for (int k = 0; k < 3; ++k) {
        if (t.side[k] >= 0) continue;
        for (const double turn : {s, -s}) {
          HalfPlanes trial = t;
          const Point2 n = t.normal[k];
          trial.normal[k] = {c * n[0] - turn * n[1], turn * n[0] + c * n[1]};
          const double area = enclosing_area(trial, points);
          if (area < best) best = area, t = trial, improved = true;
        }
      }
    }
  }
  return t;
}

// ---- the Bézier net of a PS spline on one triangle ----------------------------------------------------------

/// The four PS points of vertex V_m in a triangle, where a function of V_m has its stored ordinates: V_m and the
/// midpoints of V_m Z, of V_m R_{m+2} (edge m + 2 starts at V_m) and of V_m R_{m+1} (edge m + 1 ends at V_m).
enum RingPoint { at_vertex, toward_centre, forward, backward };

/// The kinds of the 19 domain points of the quadratic Bézier nets of a triangle's six sub-triangles; a point is
/// named by its kind and the vertex m or edge k it belongs to.
enum class Kind {
  vertex,            // V_m
  split,             // R_k
  centre,            // Z
  toward_centre,     // (V_m + Z) / 2
  centre_split,      // (R_k + Z) / 2
  split_from_start,  // (V_{k+1} + R_k) / 2
  split_to_end,      // (R_k + V_{k+2}) / 2
};

/// A Bernstein polynomial's value and gradient at the evaluation point.
struct Weight {
  double value, dx, dy;
};
using RingWeights = std::array<std::array<Weight, 4>, 3>;  // [vertex m][RingPoint]

void add(Weight& to, double factor, const Weight& w) {
  to.value += factor * w.value;
  to.dx += factor * w.dx;
  to.dy += factor * w.dy;
}

/// Adds the Bernstein polynomial w of a domain point (of this kind, at vertex or edge `index`) to the weights of the
/// PS-point ordinates that determine its ordinate. The ordinate at a PS point of V_m is the value there of the
/// function's linear Taylor polynomial at V_m (its Hermite data); the others follow from the C¹ conditions between
/// Bézier triangles (Farin 1986), each the affine combination of its neighbours that gives the point itself:
///   R_k = σ_k (V_{k+1} + R_k)/2 + (1 − σ_k)(R_k + V_{k+2})/2      C¹ along the edge, and across it as Z_e, R, Z_f
///                                                               are collinear
///   (R_k + Z)/2 = σ_k (V_{k+1} + Z)/2 + (1 − σ_k)(V_{k+2} + Z)/2  C¹ across the sub-edge R_k Z
///   Z = Σ ζ_m (V_m + Z)/2                                       C¹ across the sub-edges V_m Z
/// (the Bézier net of a PS spline from its Hermite data: Powell & Sabin 1977, Dierckx 1997).
template <Kind kind>
void spread(int index, const Weight& w, const std::array<double, 3>& sigma, const std::array<double, 3>& zeta,
            RingWeights& weights) {
  const int k = index, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  if constexpr (kind == Kind::vertex) add(weights[k][at_vertex], 1, w);
  if constexpr (kind == Kind::toward_centre) add(weights[k][toward_centre], 1, w);
  if constexpr (kind == Kind::split_from_start) add(weights[k1][forward], 1, w);
  if constexpr (kind == Kind::split_to_end) add(weights[k2][backward], 1, w);
  if constexpr (kind == Kind::split) {
    add(weights[k1][forward], sigma[k], w);
    add(weights[k2][backward], 1 - sigma[k], w);
  }
  if constexpr (kind == Kind::centre_split) {
    add(weights[k1][toward_centre], sigma[k], w);
    add(weights[k2][toward_centre], 1 - sigma[k], w);
  }
  if constexpr (kind == Kind::centre)
    for (int m = 0; m < 3; ++m) add(weights[m][toward_centre], zeta[m], w);
}

/// Spreads the Bernstein polynomials of sub-triangle 2k + half, in the order of its domain points P_0, P_1, P_2 and
/// the midpoints of P_0P_1, P_1P_2, P_2P_0, where (P_0, P_1, P_2) is (V_{k+1}, R_k, Z) or (R_k, V_{k+2}, Z).
void spread_sub_triangle(int k, int half, const std::array<Weight, 6>& w, const std::array<double, 3>& sigma,
                         const std::array<double, 3>& zeta, RingWeights& weights) {
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  if (half == 0) {
    spread<Kind::vertex>(k1, w[0], sigma, zeta, weights);
    spread<Kind::split>(k, w[1], sigma, zeta, weights);
    spread<Kind::centre>(0, w[2], sigma, zeta, weights);
    spread<Kind::split_from_start>(k, w[3], sigma, zeta, weights);
    spread<Kind::centre_split>(k, w[4], sigma, zeta, weights);
    spread<Kind::toward_centre>(k1, w[5], sigma, zeta, weights);
  } else {
    spread<Kind::split>(k, w[0], sigma, zeta, weights);
    spread<Kind::vertex>(k2, w[1], sigma, zeta, weights);
    spread<Kind::centre>(0, w[2], sigma, zeta, weights);
    spread<Kind::split_to_end>(k, w[3], sigma, zeta, weights);
    spread<Kind::toward_centre>(k2, w[4], sigma, zeta, weights);
    spread<Kind::centre_split>(k, w[5], sigma, zeta, weights);
  }
}

// ---- locating a point's sub-triangle ------------------------------------------------------------------------

/// Coordinates of a point in triangle (V_{k+1}, V_{k+2}, Z): λ = a e_{k+1} + b e_{k+2} + c ζ in the triangle's
/// barycentric coordinates λ. Linear in λ, so it maps gradients of λ as well.
struct Sector {
  double a, b, c;
};

Sector sector_coordinates(const std::array<double, 3>& lambda, const std::array<double, 3>& zeta, int k) {
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  const double c = lambda[k] / zeta[k];
  return {lambda[k1] - c * zeta[k1], lambda[k2] - c * zeta[k2], c};
}

/// Barycentric coordinates in sub-triangle 2k + half of the point with sector coordinates s (linear in s):
/// with R_k = σ V_{k+1} + (1 − σ) V_{k+2}, half 0 is (V_{k+1}, R_k, Z) and half 1 is (R_k, V_{k+2}, Z).
std::array<double, 3> sub_coordinates(const Sector& s, double sigma, int half) {
  if (half == 0) {
    const double r = s.b / (1 - sigma);
    return {s.a - r * sigma, r, s.c};
  }
  const double r = s.a / sigma;
  return {r, s.b - r * (1 - sigma), s.c};
}

/// The points of a triangle's 6-split.
struct Split {
  std::array<Point2, 3> vertex;
  Point2 centre;
  std::array<Point2, 3> edge;
};

}  // namespace

PowellSabinBasis::PowellSabinBasis(const TriangleMesh& mesh) : mesh_(&mesh) {
  const auto& nodes = mesh.nodes();
  const std::size_t triangle_count = mesh.triangle_count();
  elements_.resize(triangle_count);
  std::vector<Split> splits(triangle_count);

  // PS 6-split, step 1: the incentre of every triangle, and its barycentric map
  for (std::size_t e = 0; e < triangle_count; ++e) {
    const auto& t = mesh.triangle(e);
    Split& g = splits[e];
    Element& el = elements_[e];
    for (int m = 0; m < 3; ++m) g.vertex[m] = nodes[t[m]];
    el.centre = incentre(g.vertex);
    g.centre = combination(g.vertex, el.centre);
    el.origin = g.vertex[0];
    const std::array<Point2, 3> relative{Point2{0, 0}, difference(g.vertex[1], el.origin),
                                         difference(g.vertex[2], el.origin)};
    for (int m = 0; m < 3; ++m) {
      const Affine lambda = barycentric_coordinate(relative, m);
      el.barycentric[m] = {lambda.gx, lambda.gy, lambda.c};
      for (int j = 0; j < 3; ++j) el.index[3 * m + j] = 3 * t[m] + j;
    }
  }
  // step 2: the edge split points, computed once per interior edge (by the lower-numbered triangle) so that both
  // triangles use the same point; the shared edge runs the other way round in the neighbour (both counter-clockwise)
  for (std::size_t e = 0; e < triangle_count; ++e)
    for (int k = 0; k < 3; ++k) {
      const int f = mesh.neighbour(e, k);
      Split& g = splits[e];
      double& sigma = elements_[e].edge_split[k];
      const Point2 &start = g.vertex[(k + 1) % 3], &end = g.vertex[(k + 2) % 3];
      if (f < 0) {
        sigma = 0.5;
      } else if (static_cast<std::size_t>(f) > e) {
        sigma = 1 - crossing(start, end, g.centre, splits[f].centre);
      } else {
        int across = 0;
        while (mesh.neighbour(f, across) != static_cast<int>(e)) ++across;
        sigma = 1 - elements_[f].edge_split[across];
      }
      g.edge[k] = {sigma * start[0] + (1 - sigma) * end[0], sigma * start[1] + (1 - sigma) * end[1]};
    }

  // the PS points of every vertex (Dierckx 1997), relative to it: the vertex and the midpoints of the 6-split's
  // edges at it (towards each incident triangle's Z and each incident edge's R, the latter from the triangle that
  // computed R)
  std::vector<std::vector<Point2>> ps_points(nodes.size(), std::vector<Point2>{{0, 0}});
  for (std::size_t e = 0; e < triangle_count; ++e) {
    const Split& g = splits[e];
    for (int m = 0; m < 3; ++m) {
      auto& points = ps_points[mesh.triangle(e)[m]];
      points.push_back(half_of(difference(g.centre, g.vertex[m])));
      for (const int k : {(m + 1) % 3, (m + 2) % 3}) {
        const int f = mesh.neighbour(e, k);
        if (f < 0 || static_cast<std::size_t>(f) > e) points.push_back(half_of(difference(g.edge[k], g.vertex[m])));
      }
    }
  }
  // the PS triangle of every vertex and the barycentric coordinates λ_j of its corners, relative to the vertex
  std::vector<std::array<Affine, 3>> ps_lambda(nodes.size());
  touches_.assign(3 * nodes.size(), 0);
  const Point2& box = mesh.box();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Point2& x = nodes[i];
    // each side line in the vertex's coordinates: n · y = offset (exactly the box side, for the vanishing B-spline)
    const std::array<double, 4> side_offset{x[0], box[0] - x[0], x[1], box[1] - x[1]};
    std::vector<std::pair<int, double>> sides;
    for (int s = 0; s < 4; ++s)
      if (mesh.on_side(i, s)) sides.emplace_back(s, side_offset[s]);
    HalfPlanes t = small_enclosing_triangle(sides, ps_points[i]);
    std::array<Point2, 3> corner;
    enclosing_area(t, ps_points[i], corner);
    for (int j = 0; j < 3; ++j) {
      ps_lambda[i][j] = barycentric_coordinate(corner, j);
      // λ_j vanishes with its tangential derivative on line j, so B_i^j vanishes on that line's side
      for (const auto& side : sides)
        if (t.side[j] != side.first) touches_[3 * i + j] |= static_cast<unsigned char>(1u << side.first);
    }
  }

  // each function's ordinates at the PS points of its vertex in each triangle: λ_j there
  for (std::size_t e = 0; e < triangle_count; ++e) {
    const Split& g = splits[e];
    for (int k = 0; k < 3; ++k) {
      const Point2& v = g.vertex[k];
      for (int j = 0; j < 3; ++j) {
        const Affine& lambda = ps_lambda[mesh.triangle(e)[k]][j];
        auto& ring = elements_[e].ring[3 * k + j];
        ring[at_vertex] = lambda({0, 0});
        ring[toward_centre] = lambda(half_of(difference(g.centre, v)));
        ring[forward] = lambda(half_of(difference(g.edge[(k + 2) % 3], v)));
        ring[backward] = lambda(half_of(difference(g.edge[(k + 1) % 3], v)));
      }
    }
  }
}

std::size_t PowellSabinBasis::function_count() const { return touches_.size(); }

bool PowellSabinBasis::touches_side(std::size_t f, int side) const { return (touches_[f] >> side) & 1u; }

void PowellSabinBasis::evaluate(std::size_t e, const Point2& x, std::array<int, per_element>& index,
                                std::array<double, per_element>& value,
                                std::array<Point2, per_element>& gradient) const {
  const Element& el = elements_[e];
  const Point2 y = difference(x, el.origin);
  std::array<double, 3> lambda, dx_lambda, dy_lambda;
  for (int m = 0; m < 3; ++m) {
    dx_lambda[m] = el.barycentric[m][0];
    dy_lambda[m] = el.barycentric[m][1];
    lambda[m] = dx_lambda[m] * y[0] + dy_lambda[m] * y[1] + el.barycentric[m][2];
  }
  // x lies in triangle (V_{k+1}, V_{k+2}, Z) for the k of the smallest λ_k / ζ_k (its other sector coordinates are
  // then ≥ 0), and on the V_{k+1} side of the ray Z R_k iff a / (a + b) ≥ σ_k
  int k = 0;
  for (int m = 1; m < 3; ++m)
    if (lambda[m] * el.centre[k] < lambda[k] * el.centre[m]) k = m;
  const Sector sector = sector_coordinates(lambda, el.centre, k);
  const double sigma = el.edge_split[k];
  const int half = sector.a * (1 - sigma) >= sector.b * sigma ? 0 : 1;
  // the sub-triangle's barycentric coordinates τ and their (constant) gradients, by the same linear map
  const auto tau = sub_coordinates(sector, sigma, half);
  const auto dx_tau = sub_coordinates(sector_coordinates(dx_lambda, el.centre, k), sigma, half);
  const auto dy_tau = sub_coordinates(sector_coordinates(dy_lambda, el.centre, k), sigma, half);

  // the quadratic Bernstein polynomials τ_q² and 2 τ_q τ_{q+1}, spread onto the PS-point ordinates they depend on
  std::array<Weight, 6> bernstein;
  for (int q = 0; q < 3; ++q) {
    const int r = (q + 1) % 3;
    bernstein[q] = {tau[q] * tau[q], 2 * tau[q] * dx_tau[q], 2 * tau[q] * dy_tau[q]};
    bernstein[3 + q] = {2 * tau[q] * tau[r], 2 * (tau[q] * dx_tau[r] + tau[r] * dx_tau[q]),
                        2 * (tau[q] * dy_tau[r] + tau[r] * dy_tau[q])};
  }
  RingWeights weights{};
  spread_sub_triangle(k, half, bernstein, el.edge_split, el.centre, weights);
  for (int f = 0; f < per_element; ++f) {
    const auto& w = weights[f / 3];
    const auto& b = el.ring[f];
    double v = 0, gx = 0, gy = 0;
    for (int r = 0; r < 4; ++r) {
      v += b[r] * w[r].value;
      gx += b[r] * w[r].dx;
      gy += b[r] * w[r].dy;
    }
    value[f] = v;
    gradient[f] = {gx, gy};
  }
  index = el.index;
}

std::array<std::array<Point2, 3>, 6> PowellSabinBasis::split(std::size_t e) const {
  const auto& t = mesh_->triangle(e);
  const Element& el = elements_[e];
  std::array<Point2, 3> v;
  for (int m = 0; m < 3; ++m) v[m] = mesh_->nodes()[t[m]];
  const auto mix = [](const Point2& a, const Point2& b, double wa) {
    return Point2{wa * a[0] + (1 - wa) * b[0], wa * a[1] + (1 - wa) * b[1]};
  };
  Point2 z{0, 0};
  for (int m = 0; m < 3; ++m)
    for (int d = 0; d < 2; ++d) z[d] += el.centre[m] * v[m][d];
  std::array<std::array<Point2, 3>, 6> out;
  for (int k = 0; k < 3; ++k) {
    const Point2 &a = v[(k + 1) % 3], &b = v[(k + 2) % 3];
    const Point2 r = mix(a, b, el.edge_split[k]);
    out[2 * k] = {a, r, z};
    out[2 * k + 1] = {r, b, z};
  }
  return out;
}

}  // namespace mpm
