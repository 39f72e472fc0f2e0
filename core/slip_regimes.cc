#include "quasiroll/core/slip_regimes.h"

#include <cmath>

namespace quasiroll {

void AccumulateSlipDistances(const TrajectorySample& previous, double epsilon,
                             TrajectorySample* current,
                             const SlipIncrements* increments) {
  const double half_dt = 0.5 * (current->t - previous.t);
  for (int i = 0; i < 3; ++i) {
    const ContactSample& before = previous.contacts[i];
    ContactSample& now = current->contacts[i];
    now.sliding_distance = before.sliding_distance;
    now.creep_distance = before.creep_distance;
    if (increments) {
      now.sliding_distance += (*increments)[i].sliding;
      now.creep_distance += (*increments)[i].creep;
      continue;
    }
    CreditTrapezoid(half_dt, before.slip, now.slip, epsilon,
                    &now.sliding_distance, &now.creep_distance);
  }
}

SlipDistances TotalSlipDistances(const std::vector<TrajectorySample>& run) {
  SlipDistances total;
  if (run.empty()) return total;
  for (const ContactSample& c : run.back().contacts) {
    total.sliding += c.sliding_distance;
    total.creep += c.creep_distance;
  }
  return total;
}

}  // namespace quasiroll
