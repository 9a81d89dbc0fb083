#pragma once
// The distinct reference coordinates of the particles, axis by axis, and each particle's ranks among them. Particles
// seeded on a lattice share few coordinates per axis (1024 per axis at 512² cells and 2×2 particles per cell), so a
// function separable in X, such as the plate's body force, is formed once per distinct coordinate and step and read
// by the particles through their ranks.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpm {

/// The distinct reference coordinates of each axis, ascending.
template <int Dim>
using ReferenceAxes = std::array<std::vector<double>, Dim>;

/// A particle's ranks i_d packed into one double, Σ_d i_d 2^(26 d): exact (an integer below 2^53 in 2D), so that a
/// particle column holds it and permutes it with the others; 8 bytes read per particle where the ranks as two
/// doubles took 16.
inline constexpr int axis_rank_bits = 26;
inline constexpr std::uint64_t axis_rank_limit = std::uint64_t{1} << axis_rank_bits;

template <int Dim>
std::array<unsigned, Dim> axis_ranks(double key) {
  const auto k = static_cast<std::uint64_t>(key);
  std::array<unsigned, Dim> r;
  for (int d = 0; d < Dim; ++d) r[d] = static_cast<unsigned>((k >> (axis_rank_bits * d)) & (axis_rank_limit - 1));
  return r;
}

/// Forms `axes` from the n reference positions X and key[p], the packed ranks of particle p (axes[d][i_d] == X_d[p]).
/// Throws std::length_error if an axis has 2^26 distinct coordinates or more.
template <int Dim>
void rank_reference_axes(std::array<const double*, Dim> X, std::size_t n, double* key, ReferenceAxes<Dim>& axes) {
  std::fill_n(key, n, 0.0);
  for (int d = 0; d < Dim; ++d) {
    std::vector<double>& values = axes[d];
    values.assign(X[d], X[d] + n);
    std::sort(values.begin(), values.end());
    values.erase(std::unique(values.begin(), values.end()), values.end());
    if (values.size() >= axis_rank_limit)
      throw std::length_error("reference axes: " + std::to_string(values.size()) + " distinct coordinates on axis " +
                              std::to_string(d) + ", at most " + std::to_string(axis_rank_limit - 1));
    const double weight = static_cast<double>(std::uint64_t{1} << (axis_rank_bits * d));
    for (std::size_t p = 0; p < n; ++p) {
      const auto rank = std::lower_bound(values.begin(), values.end(), X[d][p]) - values.begin();
      key[p] += static_cast<double>(rank) * weight;
    }
  }
}

}  // namespace mpm
