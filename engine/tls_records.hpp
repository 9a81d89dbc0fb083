#pragma once
// What a TLS rebuild (tls_rebuild.hpp) records per cell: the sums of a cell's own particles, what the
// neighbourhood fits read of a cell, and what a later momentum-only rebuild of the same positions reuses.
#include <Eigen/Dense>

#include "kernels/reconstruction.hpp"
#include "kernels/taylor_ls.hpp"

namespace mpm {

/// What a TLS rebuild fits besides the density: the velocity (for a scatter of momentum), the stress and the body
/// force (for a scatter of force). `reuse`: the velocity alone, the density and the normal matrices kept from the
/// last rebuild (GaussPoints::rebuild_momentum). Fitting only what the next scatter reads: MUSL's first P2G
/// scatters no momentum, and with no body force the ρb fits are zeros.
struct TlsFields {
  bool velocity = false;
  bool stress = false;
  bool reuse = false;
};

namespace detail {

/// What a neighbourhood fit needs of its own cell besides the normal sums: the bounds of the unconstrained fields
/// over the cell's particles (for the limiter) and the cell's momentum (for the momentum shift).
template <int Dim, int KF>
struct TlsFitBounds {
  Eigen::Matrix<double, KF, 1> lo, hi;
  Eigen::Matrix<double, Dim, 1> momentum;
};

/// What a TLS rebuild sums per cell over the cell's own particles, in the cell's Taylor frame, in its first pass:
/// the normal system of all K fields (ρ | v | σ | ρb, those the rebuild fits; the fits share the samples, hence D),
/// the fields' bounds for the limiter, and the cell's mass and momentum for the constraints. The last KF fields
/// are the unconstrained fits (the row sums of pass 2 hold them alone).
template <int Dim, int Degree, int K, int KF>
struct TlsCellSums {
  CellBox<Dim> box;         ///< the TLS cell (1D: clipped to the body)
  TaylorFrame<Dim> frame;   ///< its Taylor frame, in which the sums are taken
  TaylorNormalSystem<Dim, Degree, K> sys;
  Eigen::Matrix<double, K, 1> lo = Eigen::Matrix<double, K, 1>::Zero();  ///< the fields' bounds over the cell's
  Eigen::Matrix<double, K, 1> hi = Eigen::Matrix<double, K, 1>::Zero();  ///< particles
  double mass = 0.0;
  Eigen::Matrix<double, Dim, 1> momentum = Eigen::Matrix<double, Dim, 1>::Zero();
  /// What the unconstrained fits' limiter and the momentum shift read of the cell.
  TlsFitBounds<Dim, KF> bounds() const { return {lo.template tail<KF>(), hi.template tail<KF>(), momentum}; }
  /// Fields [first, first + count) of the system, as a system of their own.
  template <int First, int Count>
  TaylorNormalSystem<Dim, Degree, Count> fields() const {
    TaylorNormalSystem<Dim, Degree, Count> f;
    f.D = sys.D;
    f.b = sys.b.template middleCols<Count>(First);
    f.shift = sys.shift.template segment<Count>(First);
    f.shift_set = sys.shift_set;
    f.points = sys.points;
    return f;
  }
};

/// What a TLS rebuild keeps of a cell for a later momentum-only rebuild of the same particle positions
/// (GaussPoints::rebuild_momentum), all of which depends on the positions only: the density fit's outcome (its
/// values stay at the Gauss points); whether the cell's own particles determined its fit, and then the factors
/// of their normal matrix (refactorising it was 4.5 % of a 2×2 MUSL-TLS step). 72 bytes in 2D at degree 1.
template <int Dim, int Degree>
struct TlsKeptFit {
  FitStatus rho;
  bool near_sparse = false;  ///< next to a cell too sparse for its own fit: the neighbourhood fits read its sums
  bool own_fitted = false;
  PivotedLdlt<taylor_size<Dim>(Degree)> own_factors;
};

/// The same for the cells whose sums the neighbourhood fits read: their own normal matrix and, for those fitted
/// to their neighbourhood, its matrix. Apart from TlsKeptFit, which every cell writes: with these in it, the
/// record of every cell was 216 bytes, most of them unused.
template <int Dim, int Degree>
struct TlsKeptMatrices {
  static constexpr int N = taylor_size<Dim>(Degree);
  Eigen::Matrix<double, N, N> own_D, neighbourhood_D;
};


}  // namespace detail

}  // namespace mpm
