// Basis evaluation: the fast closed-form path (UniformAxis) against the generic Cox–de Boor path (CoxDeBoorAxis)
// on the same open uniform knot vector. One item = one point: its stencil (per-axis values and derivatives) and,
// for the "weights" benchmarks, the S^Dim tensor-product values and gradients that the transfer kernels consume.
//
// Names: weights/<dim>d/<degree>/<path>  (stencil_at + for_each_node: values + gradients of all S^Dim functions)
//        stencil/<dim>d/<degree>/<path>  (stencil_at only: per-axis values + derivatives)
#include <array>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "kernels/bspline.hpp"
#include "kernels/stencil.hpp"

namespace {

constexpr std::size_t kPoints = 1 << 16;  // 0.5 MiB per coordinate column: stays in L2, so this times compute

template <int S>
mpm::UniformAxis<S> fast_axis(int cells) { return mpm::UniformAxis<S>(cells, 1.0); }
template <int S>
mpm::CoxDeBoorAxis<S> generic_axis(int cells) { return mpm::CoxDeBoorAxis<S>{mpm::KnotVector::open_uniform(S - 1, cells, 1.0)}; }

template <int Dim, class Axis>
mpm::TensorBasis<Dim, Axis> make_basis(int cells, Axis (*make)(int)) {
  const int f = cells + Axis::width - 1;  // open uniform: cells + degree functions per axis
  if constexpr (Dim == 1) return mpm::TensorBasis<1, Axis>{{make(cells)}, {f}};
  else return mpm::TensorBasis<2, Axis>{{make(cells), make(cells)}, {f, f}};
}

/// Random points in [0,1]^Dim, one column per axis (SoA, like the particle store).
template <int Dim>
std::array<std::vector<double>, Dim> random_points() {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::array<std::vector<double>, Dim> x;
  for (auto& c : x) {
    c.resize(kPoints);
    for (auto& v : c) v = u(rng);
  }
  return x;
}

// cells per axis: 1D 1024, 2D 256 x 256 (stencils spread over the whole grid, incl. the boundary spans)
template <int Dim>
constexpr int kCells = Dim == 1 ? 1024 : 256;

/// stencil_at + for_each_node: the Dim-dimensional values and gradients of all S^Dim functions of each point.
template <int Dim, class Axis>
void BM_Weights(benchmark::State& state, Axis (*make)(int)) {
  constexpr int S = Axis::width;
  constexpr int N = Dim == 1 ? S : S * S;
  const auto basis = make_basis<Dim>(kCells<Dim>, make);
  const auto x = random_points<Dim>();
  for (auto _ : state) {
    for (std::size_t p = 0; p < kPoints; ++p) {
      double xp[Dim];
      for (int d = 0; d < Dim; ++d) xp[d] = x[d][p];
      const auto st = mpm::stencil_at<Dim, S>(basis, xp);
      struct {
        int dof[N];
        double w[N];
        double dw[Dim][N];
      } out;
      int k = 0;
      mpm::for_each_node(st, basis.functions[0], [&](int i, double w, const std::array<double, Dim>& g) {
        out.dof[k] = i;
        out.w[k] = w;
        for (int d = 0; d < Dim; ++d) out.dw[d][k] = g[d];
        ++k;
      });
      benchmark::DoNotOptimize(out);
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kPoints);
}

/// stencil_at alone: per-axis first index, S values and S derivatives.
template <int Dim, class Axis>
void BM_Stencil(benchmark::State& state, Axis (*make)(int)) {
  constexpr int S = Axis::width;
  const auto basis = make_basis<Dim>(kCells<Dim>, make);
  const auto x = random_points<Dim>();
  for (auto _ : state) {
    for (std::size_t p = 0; p < kPoints; ++p) {
      double xp[Dim];
      for (int d = 0; d < Dim; ++d) xp[d] = x[d][p];
      auto st = mpm::stencil_at<Dim, S>(basis, xp);
      benchmark::DoNotOptimize(st);
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()) * kPoints);
}

}  // namespace

// quadratic (the headline pair), then linear and (generic only) cubic for context
namespace {
template <int S>
using Fast = mpm::UniformAxis<S>;
template <int S>
using Generic = mpm::CoxDeBoorAxis<S>;

const bool registered = [] {
  using benchmark::RegisterBenchmark;
  RegisterBenchmark("weights/1d/quadratic/fast", BM_Weights<1, Fast<3>>, &fast_axis<3>);
  RegisterBenchmark("weights/1d/quadratic/generic", BM_Weights<1, Generic<3>>, &generic_axis<3>);
  RegisterBenchmark("weights/2d/quadratic/fast", BM_Weights<2, Fast<3>>, &fast_axis<3>);
  RegisterBenchmark("weights/2d/quadratic/generic", BM_Weights<2, Generic<3>>, &generic_axis<3>);
  RegisterBenchmark("stencil/1d/quadratic/fast", BM_Stencil<1, Fast<3>>, &fast_axis<3>);
  RegisterBenchmark("stencil/1d/quadratic/generic", BM_Stencil<1, Generic<3>>, &generic_axis<3>);
  RegisterBenchmark("stencil/2d/quadratic/fast", BM_Stencil<2, Fast<3>>, &fast_axis<3>);
  RegisterBenchmark("stencil/2d/quadratic/generic", BM_Stencil<2, Generic<3>>, &generic_axis<3>);
  RegisterBenchmark("weights/1d/linear/fast", BM_Weights<1, Fast<2>>, &fast_axis<2>);
  RegisterBenchmark("weights/1d/linear/generic", BM_Weights<1, Generic<2>>, &generic_axis<2>);
  RegisterBenchmark("weights/2d/linear/fast", BM_Weights<2, Fast<2>>, &fast_axis<2>);
  RegisterBenchmark("weights/2d/linear/generic", BM_Weights<2, Generic<2>>, &generic_axis<2>);
  RegisterBenchmark("weights/2d/cubic/generic", BM_Weights<2, Generic<4>>, &generic_axis<4>);
  return true;
}();
}  // namespace
