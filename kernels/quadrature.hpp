#pragma once
// Gauss–Legendre rules on [0, 1] (used for the "gauss" particle layout and the Gauss-point integration path).
#include <cmath>
#include <numbers>
#include <vector>

namespace mpm {

struct GaussRule {
  std::vector<double> x;  ///< nodes in [0, 1]
  std::vector<double> w;  ///< weights, summing to 1
};

/// n-point Gauss–Legendre rule on [0, 1], nodes by Newton's method on P_n (exact for degree 2n − 1).
inline GaussRule gauss_legendre(int n) {
  GaussRule r;
  r.x.resize(n);
  r.w.resize(n);
  for (int i = 0; i < n; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    double dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;  // P_0, P_1; recurrence (k+1) P_{k+1} = (2k+1) z P_k − k P_{k−1}
      for (int k = 1; k < n; ++k) {
        const double p2 = ((2 * k + 1) * z * p1 - k * p0) / (k + 1);
        p0 = p1;
        p1 = p2;
      }
      dp = n * (z * p1 - p0) / (z * z - 1.0);
      const double dz = p1 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    r.x[n - 1 - i] = 0.5 * (1.0 + z);
    r.w[n - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);  // 2/((1−z²)P'²) on [−1,1], halved for [0,1]
  }
  return r;
}

}  // namespace mpm
