// Solution jumps (docs/model.md §8.6, "Solution jumps"): the regularised
// quasi-static system can have more than one root at a state (§7.5, "More
// than one root"). The root a run follows in time can end in a fold, where
// it meets another root (one that runs back in time) and both vanish; the
// next solve then lands on a third root, and the solution jumps. On the
// paper scene (eps = 1e-8) the followed root ends at t = 2.9072174 s: wheel
// 1's slip, proportional to eps until then (impending slip at the edge of
// its cone), becomes 2.6x larger and eps-independent, while wheels 2 and
// 3 fall 2.5x. In the limit eps -> 0 this is where wheel 1 starts to slide
// (the stick -> slide switch is located earlier, at a margin convention:
// §8.6, "What the level marks as eps -> 0"). Nothing in a sample's
// classes shows it, and an interval's slip quadrature that runs across it
// refines to its depth limit at the jump.
//
// Location: natural-parameter continuation of the root in time, each step a
// short local solve (the caller's: a square-system Newton method limited to
// a few iterations, no fallbacks) from the last accepted root. A step is
// accepted if it converges and its slips moved little (the criterion
// below); one that is not is either too long for Newton's basin or beyond
// the end of the root. FollowBranch doubles the step after a success and,
// after a failure at b, bisects [a, b] (a the last accepted time); a
// failure from a over a step of at most `tolerance` ends the root in
// (a, a + step]; a success at b shows that b's failure was the basin's and
// the doubling resumes. Every bracket it reports was failed from its own
// lower end. Paper scene: the fold bracketed to 1e-9 s in 31 steps (the
// end sample's root followed back to it in 5).
#pragma once

#include <Eigen/Core>
#include <array>
#include <functional>
#include <vector>

#include "quasiroll/core/switch_events.h"

namespace quasiroll {

// Tries to continue the followed root from the last accepted time to t
// (> it): true, and t's root becomes the last accepted one, if the local
// solve converges; false leaves the last accepted root as it was.
using BranchStep = std::function<bool(double t)>;

struct BranchEnd {
  enum class Outcome {
    kContinues,    // the root was followed to t1
    kEnds,         // it ends in (t_lower, t_upper]
    kUndetermined  // max_steps used up (t_lower: reached so far)
  };
  Outcome outcome = Outcome::kUndetermined;
  double t_lower = 0, t_upper = 0;
  int steps = 0;  // calls of the step function
};

// Newton iterations of a continuation step: from a root at a nearby time
// Newton converges in 3-8 (paper scene: 6-8 over a whole 0.05 s interval
// from the start's root); beyond the root's end it does not. A solve of the
// run that needs more (or a fallback) is what makes the simulator look for
// a jump.
inline constexpr int kBranchStepIterations = 10;

// A converged step is accepted only if no wheel's slip changes by more
// than this fraction of the interval's largest change between its samples
// (max_i |s_i(t1) - s_i(t0)|), plus kBranchSlipFloorOverEpsilon eps (above
// the slips' spread between solves at one state, ~2e-10 m/s on the paper
// scene). A jump keeps its size however short the step, a continuous root's
// change vanishes with it; Newton alone can converge in a few iterations
// to the other root across a fold (paper scene, coupled: from 2.907031 s to
// 2.907422 s, wheel 1's slip 6.8e-6 -> 2.6e-5 m/s in 5 iterations, where
// the interval's largest change is 2.9e-5 m/s). A jump smaller than this
// fraction of the interval's change is found only if Newton fails there.
inline constexpr double kBranchStepSlipChange = 0.25;
inline constexpr double kBranchSlipFloorOverEpsilon = 0.1;

// After a failure at b, this many successes in a row of the bisection
// (a root that goes on near b) make the next step b itself.
inline constexpr int kBranchRetryAfter = 3;

// Follows the root from t0 (accepted) to t1 as above; the first step is the
// whole [t0, t1]. Throws std::invalid_argument for t1 <= t0, tolerance <= 0
// or max_steps < 1.
BranchEnd FollowBranch(double t0, double t1, double tolerance,
                       const BranchStep& step, int max_steps = 200);

// A wheel's slip speed changes by more than this fraction of the larger
// side across a jump for the jump to be recorded for it.
inline constexpr double kSolutionJumpRelativeSlipChange = 0.1;

// Appends the events of a jump bracketed by [t_lower, t_upper] (slips
// `before` of the ended root at t_lower, `after` of the root the run goes on
// with at t_upper), located (= bracket <= the location tolerance) or not:
// one per wheel whose slip speed changes by more than
// kSolutionJumpRelativeSlipChange, at least one (the wheel with the largest
// relative change), with jump = true and its classes on either side.
// Returns the number appended.
int AppendSolutionJump(double t_lower, double t_upper, bool located,
                       const std::array<Eigen::Vector2d, 3>& before,
                       const std::array<Eigen::Vector2d, 3>& after,
                       double epsilon, std::vector<SwitchEvent>* out);

// The roots of the last few solves along a run, by time, for warm starts
// that follow a root forward: a solve at t starts from the root at the
// latest time <= t (ties: the latest stored). An integrator evaluates its
// right-hand side out of time order (a step's later stages before a
// rejection, step doubling's whole step after its halves); starting from
// the most recent evaluation instead can cross a fold backwards and land
// on another root where two coexist (model.md §7.5, "More than one root").
// Meant for a local Newton method, which converges to roots only (the
// simulator uses it with Newton backends). The oldest entry is overwritten
// once kCapacity are stored; no allocation once every slot has held a root
// of the run's size.
class PastRoots {
 public:
  static constexpr int kCapacity = 8;
  void Clear() { count_ = next_ = 0; }
  // Ignored for a NaN t (a solve without a time).
  void Remember(double t, const Eigen::VectorXd& z);
  // The root to start a solve at t from; null if none is at or before t.
  const Eigen::VectorXd* StartFor(double t) const;

 private:
  std::array<double, kCapacity> t_{};
  std::array<long long, kCapacity> order_{};
  std::array<Eigen::VectorXd, kCapacity> z_;
  int count_ = 0, next_ = 0;
  long long stored_ = 0;
};

}  // namespace quasiroll
