// DDMPM basis on one axis (kernels/dual_domain.hpp) against the thesis' definition (§2.6.4) evaluated
// independently: the integrals ∫ φ_j ∇φ_i and V_j by Gauss quadrature of the P1 basis of the generic path.
#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "kernels/bspline.hpp"
#include "kernels/dual_domain.hpp"
#include "kernels/quadrature.hpp"
#include "kernels/transfer.hpp"

using namespace mpm;

namespace {

constexpr double length = 2.5;

/// The DDMPM gradient of every node at x from the thesis' formulas, with P1 from Cox–de Boor and the integrals
/// by a 2-point Gauss rule per cell (exact for the products of P1 functions and their derivatives).
std::vector<double> thesis_gradient(int cells, double x) {
  const KnotVector kv = KnotVector::open_uniform(1, cells, length);
  const int nodes = cells + 1;
  auto p1 = [&](double at, std::vector<double>& phi, std::vector<double>& dphi) {
    phi.assign(nodes, 0.0);
    dphi.assign(nodes, 0.0);
    double N[2], dN[2];
    const int first = cox_de_boor(kv, at, N, dN);
    for (int k = 0; k < 2; ++k) {
      phi[first + k] = N[k];
      dphi[first + k] = dN[k];
    }
  };
  std::vector<double> V(nodes, 0.0), G(nodes * nodes, 0.0), phi, dphi;  // G[j * nodes + i] = ∫ φ_j φ'_i
  const GaussRule rule = gauss_legendre(2);
  const double h = length / cells;
  for (int c = 0; c < cells; ++c)
    for (std::size_t g = 0; g < rule.x.size(); ++g) {
      p1((c + rule.x[g]) * h, phi, dphi);
      const double w = rule.w[g] * h;
      for (int j = 0; j < nodes; ++j) {
        V[j] += phi[j] * w;
        for (int i = 0; i < nodes; ++i) G[j * nodes + i] += phi[j] * dphi[i] * w;
      }
    }
  p1(x, phi, dphi);
  double alpha = 0.0;  // α = 2 Σ φ_i φ_{i+1}
  for (int i = 0; i + 1 < nodes; ++i) alpha += 2.0 * phi[i] * phi[i + 1];
  std::vector<double> grad(nodes);
  for (int i = 0; i < nodes; ++i) {
    double smooth = 0.0;
    for (int j = 0; j < nodes; ++j) smooth += phi[j] / V[j] * G[j * nodes + i];
    grad[i] = alpha * dphi[i] + (1.0 - alpha) * smooth;
  }
  return grad;
}

}  // namespace

TEST_CASE("DDMPM axis: values are P1, gradients are the thesis' blend of P1 and dual-domain gradients",
          "[basis][ddmpm]") {
  for (int cells : {1, 2, 3, 7}) {
    const DualDomainAxis axis(cells, length);
    for (int k = 0; k <= 40; ++k) {
      const double x = length * k / 40.0;
      const AxisWeights<4> a = axis(x);
      const std::vector<double> expected = thesis_gradient(cells, x);
      INFO("cells " << cells << ", x = " << x);
      double w_sum = 0.0, w_x = 0.0, dw_sum = 0.0, dw_x = 0.0;
      for (int r = 0; r < 4; ++r) {
        const int node = a.first + r - 1;  // function f is node f − 1 (ghost first)
        const double xn = node * length / cells;
        if (node < 0 || node > cells) {
          CHECK(a.w[r] == 0.0);
          CHECK(a.dw[r] == 0.0);
          continue;
        }
        CHECK(a.dw[r] == Approx(expected[node]).margin(1e-12));
        w_sum += a.w[r];
        w_x += a.w[r] * xn;
        dw_sum += a.dw[r];
        dw_x += a.dw[r] * xn;
      }
      // partition of unity, linear reproduction, exact gradients of constant and linear fields
      CHECK(w_sum == Approx(1.0).epsilon(1e-14));
      CHECK(w_x == Approx(x).margin(1e-13));
      CHECK(dw_sum == Approx(0.0).margin(1e-12));
      CHECK(dw_x == Approx(1.0).epsilon(1e-13));
    }
  }
}

TEST_CASE("DDMPM axis: gradients are continuous across cell boundaries, where P1's jump", "[basis][ddmpm]") {
  const int cells = 6;
  const DualDomainAxis axis(cells, length);
  const double h = length / cells, eps = 1e-9 * h;
  for (int node = 1; node < cells; ++node) {
    const AxisWeights<4> left = axis(node * h - eps), right = axis(node * h + eps);
    REQUIRE(right.first == left.first + 1);
    for (int f = right.first; f < left.first + 4; ++f)  // the functions both stencils hold
      CHECK(left.dw[f - left.first] == Approx(right.dw[f - right.first]).margin(1e-6 / h));
    // P1's gradient of the node itself jumps from 1/h to −1/h; DDMPM's is 0 there (α = 0, centred difference)
    CHECK(std::abs(right.dw[node + 1 - right.first]) < 1e-6 / h);
  }
}

TEST_CASE("DDMPM sub-points: the force scatter integrates the particle's stress at n points over its length",
          "[basis][ddmpm][subpoints]") {
  // One particle, stretched (J = 1.3), mass and stress given: the grid force must be −Σ_s ∇̄φ_i(x_s) V σ / n with
  // x_s evenly spread over [x_p − V/2, x_p + V/2], computed here from the axis directly.
  const int cells = 5, n = 7;
  const TensorBasis<1, DualDomainAxis> basis{{DualDomainAxis(cells, length, n)}, {cells + 3}};
  double x = 1.17, v = 0.0, F = 1.3, s = 2.5e3, m = 0.4, V0 = 0.2;
  ParticleView<1> p;
  p.x[0] = &x;
  p.v[0] = &v;
  p.F[0] = &F;
  p.s[0] = &s;
  p.m = &m;
  p.V0 = &V0;
  std::vector<double> gm(cells + 3, 0.0), gf(cells + 3, 0.0), expected(cells + 3, 0.0);
  GridView<1> g;
  g.stride1 = g.dofs = cells + 3;
  g.m = gm.data();
  g.f[0] = gf.data();
  const unsigned order[1] = {0};
  scatter_p2g<ScatterFields{true, false, true}, 1, 4>(basis, p, g, order, 0, 1, NoBodyForce{});
  const double V = F * V0;
  for (int k = 0; k < n; ++k) {
    const AxisWeights<4> a = basis.axis[0](x - V / 2 + (k + 0.5) * V / n);
    for (int r = 0; r < 4; ++r) expected[a.first + r] -= a.dw[r] * V * s / n;
  }
  double total = 0.0;
  for (int f = 0; f < cells + 3; ++f) {
    INFO("function " << f);
    CHECK(gf[f] == Approx(expected[f]).margin(1e-12 * V * s));
    total += gf[f];
  }
  CHECK(total == Approx(0.0).margin(1e-12 * V * s));  // internal forces sum to zero: momentum is conserved
  const AxisWeights<4> at = basis.axis[0](x);  // the mass still goes to the particle's own stencil
  for (int r = 0; r < 4; ++r) CHECK(gm[at.first + r] == Approx(at.w[r] * m));
}
