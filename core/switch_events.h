// Switches of the quasi-static solution's structure (docs/model.md §8.6,
// "Switches"): per wheel, stick or slide, located between output samples
// so that an integrator can be restarted there instead of stepping across
// the kink of the right-hand side.
//
// Classification (a switch is a kink of the slip, so it is placed where
// the slip leaves the regularisation's scale; the sliding/creep split of
// core/slip_regimes.h counts from the lower 10 eps, see there): with the
// regularised Coulomb law C, sigma_i f_ti + mu f_ni s_i = 0,
// sigma_i = sqrt(|s_i|^2 + eps^2), a wheel's friction use is
// u_i = |f_ti|/(mu f_ni) = |s_i|/sigma_i and
//   wheel i slides  <=>  |s_i| >= kappa eps  <=>  u_i >= u* = kappa /
//   sqrt(1 + kappa^2),                          kappa = 100 (u* = 0.99995),
// and sticks (creeps at a speed proportional to eps) otherwise. The two
// forms are the same test: u = |s|/sqrt(|s|^2 + eps^2) is increasing in
// |s|. In terms of the friction-cone margin m_i = (mu f_ni - |f_ti|) /
// (mu f_ni) = 1 - u_i a wheel sticks while m_i > 1 - u* = 5.0e-5.
//
// Indicator: the continuous, bounded function of the slip speed
//   g_i = (|s_i| - kappa eps) / (|s_i| + kappa eps)   in [-1, 1),
// g_i >= 0 <=> sliding. It is continuous wherever the quasi-static solution
// is (|s_i| is a continuous function of the solution, and the solution is a
// smooth function of Theta where the equality Jacobian is regular), so a
// class that differs at two times brackets a crossing of g_i = 0 that
// bisection can locate. g_i is the slip speed relative to the
// regularisation scale (>= 0: sliding) and, written with the cone margin,
// g_i < 0 <=> m_i > 1 - u* (the sticking wheel's distance from its cone).
//
// Location: LocateSwitches narrows, for each wheel whose class differs at
// the two ends of [t0, t1], a bracket on a caller-supplied evaluation of the
// slips at interior times (the simulator: the quasi-static solve at states
// of the interval's cubic Hermite dense output, core/limit_events.h),
// keeping the invariant "class at t_lower = class at t0, class at t_upper =
// class at t1" until t_upper - t_lower <= tolerance. The bracket is the one
// bisection ends with (if the class changes once and the probes agree with
// bisection's: a probe's class within its solve's noise of the level can
// differ with its warm start), found at fewer evaluations:
//  1. Brent's method on
//       v(t) = -|l(t)| on t0's side, +|l(t)| on t1's,
//       l = log(|s_i| / (kappa eps))
//     (g = tanh(l / 2) saturates across the decades of a transition, l is
//     near linear there; the side comes from g's sign, so v and the class
//     cannot disagree at round-off): inverse quadratic (or secant) steps
//     when they land inside 3/4 of the bracket and the step before last
//     shrank it at least twofold, bisection steps otherwise, each at least
//     tol1 = 0.49 tolerance from the best point, so the step across the zero
//     closes the bracket [lo, hi] to <= 2 tol1; its ends are evaluated
//     points of their classes;
//  2. bisection's halvings of [t0, t1] replayed against [lo, hi]: a
//     midpoint left of lo (right of hi) lies on t0's (t1's) side if the
//     class changes once, one inside is evaluated;
//  3. each end of the result not evaluated in 1-2 is evaluated and must be
//     in its class (else [lo, hi] is kept: a bracket of the invariant too).
// Once an interpolated correction d is below tol1 (the zero is at b + d to
// far better than the tolerance), 2-3 are tried at once against
// [b + d, b + d] (two evaluations: the ends), before the step that would
// close Brent's bracket; if a check disagrees, Brent goes on.
// A failed evaluation: bisection of the bracket so far. Paper scene (8
// switches, Delta t = 0.05 s): 6-11 evaluations per switch, 67 in all
// (Brent alone, without 2-3: 58), instead of 20-22 (168) with bisection to
// 1e-6 s and Illinois; plain bisection takes 26. Without 2-3 the located
// times move within the tolerance, which moved the coupled RK4 ladder's
// rungs at the 1e-10 m level of the resolved steps' tolerance (SwitchEvents
// test PaperSceneCoupledRk4LadderHasOrderFourAboveTheFloor). The switch time is
// t_upper (the first state found in the new class). A wheel that changes
// class twice within [t0, t1] has the same class at both ends and is not
// seen (the samples bound the resolution, as for any sampled detection).
//
// Resolution (coupled mode, fixed-step methods): with eps > 0 a switch is
// not a kink but a steep, smooth transition whose width scales with eps
// (on the paper scene the slip of one wheel rises from 1e-6 to 2.6e-5 m/s
// and two others fall within ~1 ms while the located class change lies a
// few ms before or after it). A restart at one point cannot keep a step of
// Delta t >> 1 ms from crossing it, and such a step errs by about
// |Delta V| x width (3e-8 m there) whatever Delta t is. So the segments of
// an interval with a switch are integrated by IntegrateResolved: step
// doubling on the run's own integrator, [a, b] accepted when one step and
// two half steps agree,
//   || y_(a->b) - y_(a->m->b) ||_inf <= tolerance,   m = (a + b)/2,
// keeping the two-half-step result (its local error is that difference
// / (2^p - 1) for a method of order p), and otherwise bisected, down to
// min_step. Adaptive methods resolve the transition with their own error
// control and are given each segment whole.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <functional>
#include <limits>
#include <vector>

namespace quasiroll {

// |s| / eps at a switch between stick and slide (above the sliding/creep
// split's kSlidingSlipOverEpsilon of core/slip_regimes.h).
inline constexpr double kSwitchSlipOverEpsilon = 100.0;

// |s| / eps below which a creeping wheel's slip reversal is not an event:
// its traction is then under a tenth of the cone (mu f_n c / sqrt(1 + c^2),
// c = |s|/eps) and its slip's direction is set near round-off (on the flat
// scene, whose wheels hardly creep, 5194 such "reversals" in 20 s).
inline constexpr double kCreepReversalSlipOverEpsilon = 0.1;

// Whether wheel slips s0 (at t0) and s1 (at t1) reverse (s0 . s1 < 0) in the
// same class: both sliding, or both creeping with |s| >= 0.1 eps at both
// ends (LocateSwitchesAndReversals).
bool IsReversal(const Eigen::Vector2d& s0, const Eigen::Vector2d& s1,
                double epsilon);

// A creeping wheel's turn that the output grid splits over two intervals:
// with r its slip at the sample before t0, the turn from r to s0 and from
// s0 to s1 is each no reversal, but from r to s1 it is (r . s1 < 0), all
// three creeping and at least kCreepReversalSlipOverEpsilon eps. A sample
// near the slip's closest approach to 0 (where its traction turns, within
// ~eps/|s'|) leaves two intervals that each turn by less than 90 degrees
// (model.md §8.6, Reversals). The turn is then located in [t0, t1] on the
// sign of s(t) . r, which is positive at t0 and negative at t1.
bool IsSplitReversal(const Eigen::Vector2d& r, const Eigen::Vector2d& s0,
                     const Eigen::Vector2d& s1, double epsilon);

// g = (|s| - kappa eps)/(|s| + kappa eps); NaN for a NaN slip.
double SwitchIndicator(double slip_speed, double epsilon);

// "slide" or "stick".
inline const char* RegimeName(bool sliding) {
  return sliding ? "slide" : "stick";
}

// One located change of a wheel's class.
struct SwitchEvent {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  double t = kNaN;  // = t_upper when located, else the sample time t1
  double t_lower = kNaN, t_upper = kNaN;
  int wheel = -1;  // 1-based
  bool from_sliding = false, to_sliding = false;
  // Located: bracket width <= tolerance. Not located (an evaluation failed
  // inside the bracket): the bracket is the part of [t0, t1] narrowed so
  // far and t = t_upper.
  bool located = false;
  // Not a class change but a creeping wheel's slip reversal (stick ->
  // stick): its traction turns within a time proportional to eps
  // (LocateSwitchesAndReversals).
  bool reversal = false;
  // Not a class change but the end of the root the run followed, where the
  // solution jumps to another root (core/solution_jumps.h); its classes
  // may be the same on both sides.
  bool jump = false;
};

// An event of `wheel` (1-based) bracketed by [t_lower, t_upper], at
// t = t_upper; classes and kind left to the caller.
inline SwitchEvent BracketedEvent(int wheel, double t_lower, double t_upper,
                                  bool located) {
  SwitchEvent e;
  e.wheel = wheel;
  e.located = located;
  e.t_lower = t_lower;
  e.t_upper = t_upper;
  e.t = t_upper;
  return e;
}

// "switch", "creep_reversal" or "solution_jump" (run.json `kind`,
// docs/formats.md).
inline const char* SwitchKindName(const SwitchEvent& e) {
  return e.jump ? "solution_jump" : e.reversal ? "creep_reversal" : "switch";
}

// Puts the events appended to *out since `first` in time order (ties by
// wheel).
void SortAppended(std::size_t first, std::vector<SwitchEvent>* out);

// Slip speeds |s_i| [m/s] of the three wheels at time t; false if they
// cannot be evaluated there (e.g. a failed quasi-static solve).
using SlipEvaluator = std::function<bool(double t, std::array<double, 3>*)>;

// Appends to *out one event per wheel whose class (slip0 at t0, slip1 at t1)
// differs, located on `evaluate` to `tolerance` seconds (the bracket of
// bisection, see "Location" above), sorted by time. Returns the number
// appended. Throws std::invalid_argument for t1 <= t0, tolerance <= 0 or
// epsilon <= 0.
int LocateSwitches(double t0, double t1, const std::array<double, 3>& slip0,
                   const std::array<double, 3>& slip1, double epsilon,
                   double tolerance, const SlipEvaluator& evaluate,
                   std::vector<SwitchEvent>* out);

// Slip vectors s_i (contact frame) of the three wheels at time t; false if
// they cannot be evaluated there.
using SlipVectorEvaluator =
    std::function<bool(double t, std::array<Eigen::Vector2d, 3>*)>;

// Reversals: a wheel that slides at both ends of [t0, t1] with its slip
// vector reversed (s(t0) . s(t1) < 0) has passed through s = 0: for
// |s| < kappa eps it sticks (two class changes ~ 2 kappa eps / |s'| apart,
// 0.15 s on the paper scene at 15.5 s, both inside one interval at
// Delta t >= 0.2 s and so invisible to the class test), and its traction
// -mu f_n s / sqrt(|s|^2 + eps^2) flips within ~ eps / |s'|: a jump of the
// right-hand side as eps -> 0. A wheel that creeps at both ends with its
// slip reversed is split the same way: its class does not change, but its
// traction, -mu f_n c s^ / sqrt(1 + c^2) with c = |s|/eps, turns within a
// time proportional to eps too (paper scene, wheel 3 at ~9.09 s: 4.3 ->
// -3.0 N within 7.7e-3, 8.5e-4, 1.0e-4 s at eps 1e-8, 1e-9, 1e-10), and it
// is appended as an event of its own (reversal = true, stick -> stick),
// if its slip is at least kCreepReversalSlipOverEpsilon eps at both ends.
// Such an interval is split at the reversal, located on the sign of
// s(t) . s(t0) to `tolerance`, and the class changes of every piece are
// located as by LocateSwitches (slips at the split from `evaluate`; the
// reversal's bracket narrowed as there). With `before` (the slips at the
// sample before t0; a zero entry: no reference for that wheel), a creeping
// wheel's turn split over [t_before, t0] and [t0, t1] (IsSplitReversal) is a
// reversal too, located on the sign of s(t) . before. Without a reversal
// this is LocateSwitches. Returns the number of events appended (in time
// order); *reversed (if not null) receives whether a reversal was found.
// Throws as LocateSwitches.
int LocateSwitchesAndReversals(
    double t0, double t1, const std::array<Eigen::Vector2d, 3>& slip0,
    const std::array<Eigen::Vector2d, 3>& slip1, double epsilon,
    double tolerance, const SlipVectorEvaluator& evaluate,
    std::vector<SwitchEvent>* out, bool* reversed = nullptr,
    const std::array<Eigen::Vector2d, 3>* before = nullptr);

// The shortest piece IntegrateResolved refines to in the simulator [s].
inline constexpr double kSwitchMinStep = 1e-7;
// How long after a located switch the simulator keeps integrating
// resolved [s]: the located class change is not the steepest point of the
// transition. With the cone margin 1 - u falling at a rate r, a wheel
// heading for its cone creeps at |s| = eps / sqrt(2 (1 - u)), so it passes
// kappa eps 1 / (2 r kappa^2) before the margin's extrapolated zero, where
// the slip jumps (paper scene: r = 0.0116/s, 4.3 ms, measured 2.9029 s vs
// 2.9072 s); 0.05 s covers r >= 0.001/s. A switch out of sliding lies after
// its transition, inside the interval it is located in.
inline constexpr double kSwitchResolveWindow = 0.05;

// One interval's slip integral of a wheel, int |s_i| dt, split by regime
// (core/slip_regimes.h): sliding and the regularisation's creep [m].
struct SlipIncrement {
  double sliding = 0, creep = 0;
};
using SlipIncrements = std::array<SlipIncrement, 3>;

// The slip integrals over [t0, t1] of an interval in which a wheel changes
// class, split at `breaks` (the located switch times inside (t0, t1),
// sorted: kinks of the slip) and, between them, where a wheel's slip
// crosses the sliding level kSlidingSlipOverEpsilon eps (located by
// Illinois to |s| within 2e-4 of the level; at most one crossing per half
// of a piece, which covers a reversal's stick window), on each piece
// int |s_i| dt by adaptive Simpson on `evaluate` (error estimate <= 1e-3 of
// the piece's integral or 1e-3 eps (b - a), at most 2^8 subdivisions),
// credited to the regime of the slip at the piece's midpoint. The
// trapezoid over the two samples instead gives the sample next to a switch,
// where creep peaks (|s| = eps / sqrt(2 r D), D from the cone) or a short
// stick window opens (its length proportional to eps), the weight
// (t1 - t0) / 2 whatever its distance to the switch, so the creep of a run
// was not proportional to eps (paper scene, 20 s: 13.1x and 11.2x per
// decade of eps). False if an evaluation fails (*out then unspecified; the
// caller keeps the trapezoid). *evaluations receives the count. Paper
// scene: 209 evaluations over its 13 intervals with a switch or a crossing
// of the level (3 per piece that meets the tolerance at once; 51 and 38 in
// the two intervals whose pieces hold a switch's steep transition, refined
// to the depth limit there); the 8 at the breaks (the located t_upper) are
// answered from the simulator's cache of the location's probes: 201
// solves. A piece [t_lower, t_upper] listed in `jumps` (both ends among
// the breaks: a solution jump's bracket, core/solution_jumps.h) is not
// evaluated inside, where the roots meet: the trapezoid on its ends' slips
// (those of the ended root and of the next), each half credited to its own
// regime (an error of at most the bracket's width times the slip jump).
// Throws std::invalid_argument for t1 <= t0.
bool IntegrateSlipRegimes(double t0, double t1,
                          const std::array<double, 3>& slip0,
                          const std::array<double, 3>& slip1,
                          const std::vector<double>& breaks, double epsilon,
                          const SlipEvaluator& evaluate, SlipIncrements* out,
                          int* evaluations,
                          const std::vector<std::array<double, 2>>& jumps = {});

// The step-doubling tolerance of a resolved piece:
// max(floor, kSwitchToleranceRate h^4) in ||.||_inf of Theta, h the fixed
// step (the output interval / substeps). RK4's fixed step errs by ~K dt^4 over
// the run anyway (paper scene, coupled: K = 4e-8 m/s^4 from the dt ladder 1.6,
// 0.8, 0.4 s); resolving a switch to a tenth of that keeps the order and does
// not change the result (measured: the errors at dt 1.6 ... 0.4 equal those at
// 1e-13 to 3 %, at 1/22 to 1/5 of the steps), while a fixed 1e-13 made a
// coupled RK4 run cost 10-50x a plain one whatever dt. The floor
// (SimulationOptions::switch_step_tolerance, 1e-12) stays above the noise of
// the quasi-static solves (residual 1e-12).
inline constexpr double kSwitchToleranceRate = 4e-9;  // [1/s^4]
inline double SwitchResolutionTolerance(double step, double floor) {
  const double h2 = step * step;
  return std::max(floor, kSwitchToleranceRate * h2 * h2);
}

// The creep band: a sticking wheel whose creep |s| lies in
// [kSwitchBandSlipOverEpsilon eps, kSwitchSlipOverEpsilon eps) is close to
// its cone. There the regularised law makes the right-hand side steep but
// smooth: with the margin 1 - u falling (rising) at a rate r, the creep is
// |s| = eps / sqrt(2 r D), D the time to (since) the margin's zero, a
// D^(-1/2) precursor (aftermath) of the slip's jump whose derivatives grow
// like D^(-k - 1/2). A fixed step h that ends at D ~ h from the zero errs
// by ~ (eps / sqrt(r)) h^(1/2) instead of O(h^5): the order is lost however
// small h is. The band's lower edge is D = 1 / (2 r kappa_b^2) from the
// zero (kappa_b = 10: 0.43 s on the paper scene, r = 0.0116/s), so
// integrating every interval with a wheel in the band resolved keeps the
// fixed steps at D >= 0.43 s, where the precursor's error is at the smooth
// level (model.md §8.6, "The creep band").
inline constexpr double kSwitchBandSlipOverEpsilon = 10.0;

// Whether a wheel with slip speed |s| creeps inside the band (NaN: false).
inline bool InSwitchBand(double slip_speed, double epsilon) {
  return slip_speed >= kSwitchBandSlipOverEpsilon * epsilon &&
         slip_speed < kSwitchSlipOverEpsilon * epsilon;
}

// One call of the run's integrator from a to b on *y (false: it failed).
using SegmentAdvance =
    std::function<bool(double a, double b, Eigen::VectorXd* y)>;

// Where a failed IntegrateResolved got to: the last time it reached (*y
// holds the state there) and the end of the piece that then failed
// (t_failed - t <= min_step).
struct ResolvedStop {
  double t = std::numeric_limits<double>::quiet_NaN();
  double t_failed = std::numeric_limits<double>::quiet_NaN();
};

// Integrates *y from a to b with `advance`, refined by step doubling as
// above (tolerance = +inf: one call on *y, which a failure leaves
// unspecified, with *stop untouched). False if a call fails on a piece of
// min_step or shorter; *y is then the state at stop->t (when given), where
// the march stood. Throws std::invalid_argument for b <= a or
// min_step <= 0.
bool IntegrateResolved(double a, double b, double tolerance, double min_step,
                       const SegmentAdvance& advance, Eigen::VectorXd* y,
                       ResolvedStop* stop = nullptr);

}  // namespace quasiroll
