#pragma once
// Energy-balance guard (DESIGN.md, `time.energy_tolerance`). A blow-up is not always caught by the other guards:
// a run can inject energy for thousands of steps while every value stays finite, J stays positive and the particles
// stay in the grid, and then "complete" with garbage. Energy catches it: an explicit MPM step may lose energy
// (grid-to-particle projection, impacts on fixed sides, USL's dissipation), but it must not gain more than the
// external forces put in. So the run tracks
//
//     excess(t) = E(t) − E(0) − W_ext(t),   E = kinetic + strain energy,   W_ext = ∫ Σ_p m_p b_p·v_p dt
//
// and stops when excess(t) > tolerance · scale(t), scale(t) = max(E(0), max_{s ≤ t} E(s)). Only a gain is a
// failure: a loss (excess < 0) is numerical dissipation, reported but not stopped. The scale is the largest
// energy seen, so a run that blows up drives excess/scale towards 1, while a healthy run keeps it near 0.
// W_ext is integrated by the trapezoid rule over the samples of the power.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

namespace mpm {

class EnergyBalance {
 public:
  /// What a checkpoint must carry for a resumed run to continue the balance bitwise.
  struct State {
    double energy0 = 0.0;     ///< E(0), J
    double work = 0.0;        ///< W_ext so far, J
    double power = 0.0;       ///< external power at the last sample, W
    double time = 0.0;        ///< time of the last sample, s
    double scale = 0.0;       ///< max(E(0), max E), J
    double excess_max = 0.0;  ///< largest excess / scale so far (gain)
    double excess_min = 0.0;  ///< smallest excess / scale so far (loss, ≤ 0)
  };

  EnergyBalance(double tolerance, double energy0, double power0, double t0) : tolerance_(tolerance) {
    st_.energy0 = energy0;
    st_.scale = energy0;
    st_.power = power0;
    st_.time = t0;
  }
  EnergyBalance(double tolerance, const State& state) : tolerance_(tolerance), st_(state) {}

  /// Adds a sample at time t with total energy `energy` and external power `power`. Returns the one-line reason
  /// when the energy gained beyond the external work exceeds the tolerance, nothing otherwise.
  std::optional<std::string> sample(long step, double t, double energy, double power) {
    st_.work += 0.5 * (st_.power + power) * (t - st_.time);
    st_.power = power;
    st_.time = t;
    if (!std::isfinite(energy)) return reason(step, t, energy, "non-finite energy");
    st_.scale = std::max(st_.scale, energy);
    if (st_.scale <= 0.0) return std::nullopt;  // nothing moves and nothing is strained
    const double rel = excess(energy) / st_.scale;
    st_.excess_max = std::max(st_.excess_max, rel);
    st_.excess_min = std::min(st_.excess_min, rel);
    if (rel > tolerance_) return reason(step, t, energy, nullptr);
    return std::nullopt;
  }

  const State& state() const { return st_; }
  double tolerance() const { return tolerance_; }

 private:
  double excess(double energy) const { return energy - st_.energy0 - st_.work; }

  std::string reason(long step, double t, double energy, const char* what) const {
    char buf[512];
    if (what) {
      std::snprintf(buf, sizeof buf, "energy balance violated at step %ld (t = %.6g s): %s (E(0) = %.6g J)", step, t,
                    what, st_.energy0);
    } else {
      std::snprintf(buf, sizeof buf,
                    "energy balance violated at step %ld (t = %.6g s): E = %.6g J, E(0) = %.6g J, external work "
                    "W = %.6g J, gain E - E(0) - W = %.6g J = %.3g x scale %.6g J (max energy so far); bound "
                    "time.energy_tolerance = %g",
                    step, t, energy, st_.energy0, st_.work, excess(energy), excess(energy) / st_.scale, st_.scale,
                    tolerance_);
    }
    return buf;
  }

  double tolerance_;
  State st_;
};

}  // namespace mpm
