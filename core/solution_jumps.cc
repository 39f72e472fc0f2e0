#include "quasiroll/core/solution_jumps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace quasiroll {

BranchEnd FollowBranch(double t0, double t1, double tolerance,
                       const BranchStep& step, int max_steps) {
  if (!(t1 > t0)) throw std::invalid_argument("FollowBranch: t1 must be > t0");
  if (!(tolerance > 0))
    throw std::invalid_argument("FollowBranch: tolerance must be > 0");
  if (max_steps < 1)
    throw std::invalid_argument("FollowBranch: max_steps must be >= 1");
  constexpr double kNone = std::numeric_limits<double>::infinity();
  BranchEnd end;
  double a = t0, length = t1 - t0;
  double b = kNone;  // the earliest failed time above a since the last reset
  int run = 0;       // successes in a row since b's failure
  while (end.steps < max_steps) {
    double target;
    if (b == kNone) {
      target = std::min(a + length, t1);
    } else if (run >= kBranchRetryAfter || b - a <= tolerance) {
      target = b;  // b once more, from closer
    } else {
      target = a + 0.5 * (b - a);
    }
    if (!(target > a)) break;  // round-off: a bracket of one ulp
    ++end.steps;
    if (step(target)) {
      length = target - a;
      a = target;
      if (a >= t1) {
        end.outcome = BranchEnd::Outcome::kContinues;
        end.t_lower = end.t_upper = t1;
        return end;
      }
      if (target == b) {  // b's failure was the basin's
        b = kNone;
        run = 0;
      } else if (b != kNone) {
        ++run;
      }
      if (b == kNone) length *= 2.0;
    } else if (target - a <= tolerance) {
      end.outcome = BranchEnd::Outcome::kEnds;
      end.t_lower = a;
      end.t_upper = target;
      return end;
    } else {
      b = target;
      run = 0;
    }
  }
  end.t_lower = a;
  end.t_upper = b == kNone ? t1 : b;
  return end;
}

int AppendSolutionJump(double t_lower, double t_upper, bool located,
                       const std::array<Eigen::Vector2d, 3>& before,
                       const std::array<Eigen::Vector2d, 3>& after,
                       double epsilon, std::vector<SwitchEvent>* out) {
  std::array<double, 3> change{};
  int largest = 0;
  for (int i = 0; i < 3; ++i) {
    const double s0 = before[i].norm(), s1 = after[i].norm();
    const double larger = std::max(s0, s1);
    change[i] = larger > 0 ? std::abs(s1 - s0) / larger : 0.0;
    if (std::isnan(change[i])) change[i] = 0.0;
    if (change[i] > change[largest]) largest = i;
  }
  int appended = 0;
  for (int i = 0; i < 3; ++i) {
    if (!(change[i] > kSolutionJumpRelativeSlipChange) && i != largest)
      continue;
    SwitchEvent e = BracketedEvent(i + 1, t_lower, t_upper, located);
    e.jump = true;
    e.from_sliding = SwitchIndicator(before[i].norm(), epsilon) >= 0;
    e.to_sliding = SwitchIndicator(after[i].norm(), epsilon) >= 0;
    out->push_back(e);
    ++appended;
  }
  return appended;
}

void PastRoots::Remember(double t, const Eigen::VectorXd& z) {
  if (std::isnan(t)) return;
  const int slot = count_ < kCapacity ? count_++ : next_;
  if (count_ == kCapacity) next_ = (slot + 1) % kCapacity;
  t_[slot] = t;
  order_[slot] = ++stored_;
  z_[slot] = z;
}

const Eigen::VectorXd* PastRoots::StartFor(double t) const {
  int best = -1;
  for (int i = 0; i < count_; ++i) {
    if (!(t_[i] <= t)) continue;
    if (best < 0 || t_[i] > t_[best] ||
        (t_[i] == t_[best] && order_[i] > order_[best]))
      best = i;
  }
  return best < 0 ? nullptr : &z_[best];
}

}  // namespace quasiroll
