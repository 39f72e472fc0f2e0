// Sliding and creep (docs/model.md §7.5, "Sliding and creep"): the two
// regimes of the regularised Coulomb law C, sigma_i f_ti + mu f_ni s_i = 0
// with sigma_i = sqrt(|s_i|^2 + eps^2) (§7.2). C gives a wheel's friction
// use u = |f_t| / (mu f_n) = |s| / sqrt(|s|^2 + eps^2), i.e.
//   |s| = eps u / sqrt(1 - u^2).
// A wheel below its friction cone (u bounded away from 1 by the statics)
// creeps at a speed proportional to eps: the regularisation's stand-in for
// sticking, not physics. A wheel on its cone slides at a speed the
// kinematics sets, independent of eps, with u -> 1. The split counts a
// slip as sliding when |s| >= kSlidingSlipOverEpsilon eps = 10 eps
// (u >= 0.995); for eps -> 0 every slide passes and every creep stays below.
// The level trades two misattributions (docs/model.md §7.5): a slide that
// slows down at a rate a leaves its last (kappa eps)^2 / (2a) below the level
// (O(eps^2): breaks the proportionality of creep to eps, 100x smaller than
// at kappa = 100: paper scene, creep / eps 37.4, 37.0, 37.1 for eps 1e-8,
// 1e-9, 1e-10 instead of 82, 54, 49), while the creep of a wheel heading
// for its cone (|s| = eps / sqrt(2 r D), margin rate r) above the level,
// eps / (kappa r), counts as sliding (O(eps): vanishes with eps, keeps the
// proportionality). Switches (core/switch_events.h) sit higher, at 100 eps,
// where the slip's kink is.
#pragma once

#include <cmath>
#include <vector>

#include "quasiroll/core/simulator.h"

namespace quasiroll {

// |s| / eps above which a contact counts as sliding (u >= 0.995).
inline constexpr double kSlidingSlipOverEpsilon = 10.0;

inline bool IsSliding(double slip_speed, double epsilon) {
  return slip_speed >= kSlidingSlipOverEpsilon * epsilon;
}

// The trapezoid over an interval of length 2 half_dt with end slip speeds
// s0, s1: each end's half credited to its own regime (a non-finite slip
// adds nothing).
inline void CreditTrapezoid(double half_dt, double s0, double s1,
                            double epsilon, double* sliding, double* creep) {
  for (const double slip : {s0, s1}) {
    if (!std::isfinite(slip)) continue;
    *(IsSliding(slip, epsilon) ? sliding : creep) += half_dt * slip;
  }
}

// The per-wheel cumulative distances of `current` (ContactSample::
// sliding_distance, creep_distance): those of `previous` plus the trapezoid
// rule over [previous.t, current.t], each end's half going to its own
// regime, int |s_i| dt; or, given `increments` (an interval with a located
// switch or a wheel crossing the sliding level: IntegrateSlipRegimes,
// core/switch_events.h), those. A sample
// without a slip (NaN: failed solve) adds nothing.
void AccumulateSlipDistances(const TrajectorySample& previous, double epsilon,
                             TrajectorySample* current,
                             const SlipIncrements* increments = nullptr);

// Sum over the wheels of the last sample's cumulative distances (0 for no
// samples): a run's sliding and creep distance [m].
struct SlipDistances {
  double sliding = 0, creep = 0;
};
SlipDistances TotalSlipDistances(const std::vector<TrajectorySample>& run);

}  // namespace quasiroll
