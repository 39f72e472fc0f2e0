#include "quasiroll/core/switch_events.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "quasiroll/core/slip_regimes.h"

namespace quasiroll {

static_assert(kSwitchSlipOverEpsilon > kSlidingSlipOverEpsilon,
              "a switch lies inside the sliding regime of the split");

namespace {
// (|s| - level) / (|s| + level) in [-1, 1), >= 0 from the level up.
double LevelIndicator(double slip_speed, double level) {
  return (slip_speed - level) / (slip_speed + level);
}
}  // namespace

double SwitchIndicator(double slip_speed, double epsilon) {
  if (std::isnan(slip_speed)) return SwitchEvent::kNaN;
  return LevelIndicator(slip_speed, kSwitchSlipOverEpsilon * epsilon);
}

namespace {
// One Illinois step on the bracket [lo, hi] (values flo, fhi of opposite
// signs): the point m (value f) replaces lo if replaces_lo, else hi; the
// other end, if it was kept the step before too, has its value halved
// (what keeps regula falsi from converging from one side only). *kept:
// +1 after lo was replaced, -1 after hi, 0 to start afresh.
void IllinoisUpdate(bool replaces_lo, double m, double f, double* lo,
                    double* flo, double* hi, double* fhi, int* kept) {
  if (replaces_lo) {
    *lo = m;
    *flo = f;
    if (*kept == 1) *fhi *= 0.5;
    *kept = 1;
  } else {
    *hi = m;
    *fhi = f;
    if (*kept == -1) *flo *= 0.5;
    *kept = -1;
  }
}

// The value Brent's method below interpolates: -|f| on t0's side, +|f| on
// t1's (the side decides the sign, so that a value and its class cannot
// disagree at round-off), finite and nonzero.
double SidedValue(double f, bool start) {
  const double m = std::clamp(std::abs(f), std::numeric_limits<double>::min(),
                              1e3);  // |f| = inf (|s| = 0): a large value
  return start ? -m : m;
}

// Bisection's halvings of [t0, t1] to `tolerance` replayed against [lo, hi]
// (a midpoint left of lo lies on t0's side if the class changes once, one
// inside [lo, hi] is evaluated), then the ends of the result not evaluated
// checked (lo and hi count as evaluated if `evaluated`). True with
// [*ra, *rb] = bisection's bracket if every check agrees.
template <class Eval>
bool ReplayBisection(double tolerance, const Eval& eval, double t0, double t1,
                     double lo, double hi, bool evaluated, double* ra,
                     double* rb) {
  double f;
  bool start, a_seen = true, b_seen = true;
  *ra = t0;
  *rb = t1;
  while (*rb - *ra > tolerance) {
    const double m = 0.5 * (*ra + *rb);
    if (!(m > *ra && m < *rb)) break;  // round-off
    if (m <= lo || m >= hi) {
      const bool left = m <= lo;
      (left ? *ra : *rb) = m;
      (left ? a_seen : b_seen) = evaluated && m == (left ? lo : hi);
    } else if (eval(m, &f, &start)) {
      (start ? *ra : *rb) = m;
      (start ? lo : hi) = m;
      (start ? a_seen : b_seen) = true;
    } else {
      return false;
    }
  }
  if (!a_seen && !(eval(*ra, &f, &start) && start)) return false;
  if (!b_seen && !(eval(*rb, &f, &start) && !start)) return false;
  return true;
}

// A point that could not be evaluated (its solve failed) is replaced by
// one beside it inside the bracket [b, c] (or [c, b]): any interior point
// narrows it. Tried 1e-3 of the bracket to either side, then at its
// quarters; false if none can be evaluated. (A ceres probe at 1.1108 s on
// the bumpy scene stalled at a scaled residual 1e-10 and left the switch
// unlocated in a 2.3e-4 s bracket.)
template <class Eval>
bool EvalNearby(const Eval& eval, double b, double c, double* x, double* f,
                bool* start) {
  const double lo = std::min(b, c), hi = std::max(b, c), w = hi - lo;
  for (const double t :
       {*x + 1e-3 * w, *x - 1e-3 * w, lo + 0.25 * w, lo + 0.75 * w}) {
    if (!(t > lo && t < hi) || t == *x) continue;
    if (eval(t, f, start)) {
      *x = t;
      return true;
    }
  }
  return false;
}

// Narrows [*a, *b] (*a on t0's side, *b not; values fa, fb) to bisection's
// bracket of width <= tolerance by Brent's method and bisection's halvings
// replayed (see "Location" in the header). eval(t, &f, &start)
// returns false when f cannot be evaluated at t; *start: t on t0's side.
// A point that cannot be evaluated is replaced by one beside it
// (EvalNearby); when none can be, bisection of the bracket so far: false if
// one fails there.
template <class Eval>
bool NarrowBracket(double tolerance, const Eval& eval, double* a_io,
                   double* b_io, double fa_in, double fb_in) {
  const double t0 = *a_io, t1 = *b_io;
  double f = 0;
  bool start = false;
  // b: the latest best point, c: the other end of the bracket [b, c] (or
  // [c, b]), a: the previous b. Each new point lies strictly inside the
  // bracket and replaces the end on its side, so the end on t0's side
  // stays the lower one.
  double a = *a_io, b = *b_io, c = b;
  double fa = SidedValue(fa_in, true), fb = SidedValue(fb_in, false), fc = fb;
  double d = b - a, e = d, ra, rb;
  bool ok = true, tried = false;
  // Steps of at least tol1 from b: the last one, across the zero, closes
  // the bracket to <= 2 tol1 (< tolerance, with room for round-off).
  const double tol1 = 0.49 * tolerance;
  for (;;) {
    if ((fb > 0) == (fc > 0)) {
      c = a;
      fc = fa;
      e = d = b - a;
    }
    if (std::abs(fc) < std::abs(fb)) {
      a = b;
      b = c;
      c = a;
      fa = fb;
      fb = fc;
      fc = fa;
    }
    const double xm = 0.5 * (c - b);
    if (std::abs(xm) <= tol1) break;
    bool interpolated = false;
    if (std::abs(e) >= tol1 && std::abs(fa) > std::abs(fb)) {
      // Inverse quadratic interpolation (secant if a == c), accepted when
      // it lands inside 3/4 of the bracket and shrinks faster than half
      // the step before last.
      const double s = fb / fa;
      double p, q;
      if (a == c) {
        p = 2 * xm * s;
        q = 1 - s;
      } else {
        const double qa = fa / fc, r = fb / fc;
        p = s * (2 * xm * qa * (qa - r) - (b - a) * (r - 1));
        q = (qa - 1) * (r - 1) * (s - 1);
      }
      if (p > 0) {
        q = -q;
      } else {
        p = -p;
      }
      if (2 * p < std::min(3 * xm * q - std::abs(tol1 * q), std::abs(e * q))) {
        e = d;
        d = p / q;
        interpolated = true;
      } else {
        d = e = xm;
      }
    } else {
      d = e = xm;
    }
    // An interpolated correction below tol1: the zero is at b + d to far
    // better than the tolerance, so bisection's bracket around it is
    // checked at once instead of closing Brent's bracket first (once).
    if (interpolated && std::abs(d) <= tol1 && !tried) {
      tried = true;
      if (ReplayBisection(tolerance, eval, t0, t1, b + d, b + d, false, &ra,
                          &rb)) {
        *a_io = ra;
        *b_io = rb;
        return true;
      }
    }
    double x = std::abs(d) > tol1 ? b + d : b + std::copysign(tol1, xm);
    if (!(x > std::min(b, c) && x < std::max(b, c))) break;  // round-off
    if (!eval(x, &f, &start)) {
      if (!EvalNearby(eval, b, c, &x, &f, &start)) {
        ok = false;
        break;
      }
      d = e = x - b;  // a bisection-like step
    }
    a = b;
    fa = fb;
    b = x;
    fb = SidedValue(f, start);
  }
  // The bracket so far, its t0 side first; bisection's if the replay
  // agrees, else this one.
  double lo = std::min(b, c), hi = std::max(b, c);
  if (ok && ReplayBisection(tolerance, eval, t0, t1, lo, hi, true, &ra, &rb)) {
    lo = ra;
    hi = rb;
  }
  if (!ok) {
    ok = true;
    while (hi - lo > tolerance) {
      const double m = 0.5 * (lo + hi);
      if (!(m > lo && m < hi)) break;  // round-off
      if (!eval(m, &f, &start)) {
        ok = false;
        break;
      }
      (start ? lo : hi) = m;
    }
  }
  *a_io = lo;
  *b_io = hi;
  return ok;
}
}  // namespace

void SortAppended(std::size_t first, std::vector<SwitchEvent>* out) {
  std::sort(out->begin() + static_cast<std::ptrdiff_t>(first), out->end(),
            [](const SwitchEvent& x, const SwitchEvent& y) {
              return x.t < y.t || (x.t == y.t && x.wheel < y.wheel);
            });
}

int LocateSwitches(double t0, double t1, const std::array<double, 3>& slip0,
                   const std::array<double, 3>& slip1, double epsilon,
                   double tolerance, const SlipEvaluator& evaluate,
                   std::vector<SwitchEvent>* out) {
  if (!(t1 > t0))
    throw std::invalid_argument("LocateSwitches: t1 must be > t0");
  if (!(tolerance > 0))
    throw std::invalid_argument("LocateSwitches: tolerance must be > 0");
  if (!(epsilon > 0))
    throw std::invalid_argument("LocateSwitches: epsilon must be > 0");
  const std::size_t first = out->size();
  std::array<double, 3> slip;
  for (int i = 0; i < 3; ++i) {
    const double g0 = SwitchIndicator(slip0[i], epsilon);
    const double g1 = SwitchIndicator(slip1[i], epsilon);
    if (std::isnan(g0) || std::isnan(g1) || (g0 >= 0) == (g1 >= 0)) continue;
    SwitchEvent e;
    e.wheel = i + 1;
    e.from_sliding = g0 >= 0;
    e.to_sliding = g1 >= 0;
    // Interpolated: log(|s| / (kappa eps)), near linear in t across the
    // decades of a transition where g = tanh(log(...) / 2) saturates.
    const double level = kSwitchSlipOverEpsilon * epsilon;
    auto eval = [&](double t, double* f, bool* start) {
      if (!evaluate(t, &slip)) return false;
      const double g = SwitchIndicator(slip[i], epsilon);
      *f = std::log(slip[i] / level);
      *start = (g >= 0) == e.from_sliding;
      return !std::isnan(g);
    };
    double a = t0, b = t1;
    e.located =
        NarrowBracket(tolerance, eval, &a, &b, std::log(slip0[i] / level),
                      std::log(slip1[i] / level));
    e.t_lower = a;
    e.t_upper = b;
    e.t = b;
    out->push_back(e);
  }
  SortAppended(first, out);
  return static_cast<int>(out->size() - first);
}

namespace {
std::array<double, 3> Norms(const std::array<Eigen::Vector2d, 3>& s) {
  return {s[0].norm(), s[1].norm(), s[2].norm()};
}
}  // namespace

bool IsReversal(const Eigen::Vector2d& s0, const Eigen::Vector2d& s1,
                double epsilon) {
  const double n0 = s0.norm(), n1 = s1.norm();
  const double g0 = SwitchIndicator(n0, epsilon);
  const double g1 = SwitchIndicator(n1, epsilon);
  if (std::isnan(g0) || std::isnan(g1) || !(s0.dot(s1) < 0)) return false;
  if (g0 >= 0 && g1 >= 0) return true;
  const double floor = kCreepReversalSlipOverEpsilon * epsilon;
  return g0 < 0 && g1 < 0 && n0 >= floor && n1 >= floor;
}

bool IsSplitReversal(const Eigen::Vector2d& r, const Eigen::Vector2d& s0,
                     const Eigen::Vector2d& s1, double epsilon) {
  if (!(SwitchIndicator(s0.norm(), epsilon) < 0) ||
      !(s0.norm() >= kCreepReversalSlipOverEpsilon * epsilon))
    return false;
  return r.dot(s0) > 0 && !(s0.dot(s1) < 0) && IsReversal(r, s1, epsilon) &&
         SwitchIndicator(r.norm(), epsilon) < 0;
}

namespace {
// LocateSwitchesAndReversals with the wheels whose reversal in [t0, t1] is
// already recorded (bit i - 1 of located_reversals): the piece before a
// split ends at the bracket's far end b, so it holds the crossing just
// located, and s(t0) . s(b) < 0 there again; searching it again found the
// same crossing a second time (a bracket overlapping the first: 39 of the
// default suite's runs listed two creep reversals of one wheel ~6e-10 s
// apart), or the second search could not narrow and ended the loop, hiding
// another wheel's reversal in that piece.
int LocateInPiece(double t0, double t1,
                  const std::array<Eigen::Vector2d, 3>& slip0,
                  const std::array<Eigen::Vector2d, 3>& slip1, double epsilon,
                  double tolerance, const SlipVectorEvaluator& evaluate,
                  unsigned located_reversals, std::vector<SwitchEvent>* out,
                  bool* reversed,
                  const std::array<Eigen::Vector2d, 3>* before) {
  if (reversed) *reversed = false;
  SlipEvaluator norms = [&](double t, std::array<double, 3>* s) {
    std::array<Eigen::Vector2d, 3> v;
    if (!evaluate(t, &v)) return false;
    *s = Norms(v);
    return true;
  };
  if (!(t1 > t0) || !(tolerance > 0) || !(epsilon > 0))
    return LocateSwitches(t0, t1, Norms(slip0), Norms(slip1), epsilon,
                          tolerance, norms, out);  // throws
  // The first reversing wheel, sliding or creeping at both ends, splits the
  // interval; the pieces recurse.
  const std::size_t first = out->size();
  for (int i = 0; i < 3; ++i) {
    if ((located_reversals >> i) & 1u) continue;
    // The direction the turn is measured from: the start's, or for a turn
    // the grid split, the sample's before it.
    Eigen::Vector2d from = slip0[i];
    if (!IsReversal(slip0[i], slip1[i], epsilon)) {
      if (!before ||
          !IsSplitReversal((*before)[i], slip0[i], slip1[i], epsilon))
        continue;
      from = (*before)[i];
    }
    const bool creeping = SwitchIndicator(slip0[i].norm(), epsilon) < 0;
    double a = t0, b = t1, t_at_b = t1;
    std::array<Eigen::Vector2d, 3> at_b = slip1, v;
    auto eval = [&](double t, double* f, bool* start) {
      if (!evaluate(t, &v)) return false;
      *f = v[i].dot(from);
      *start = *f > 0;
      if (!*start) {
        at_b = v;
        t_at_b = t;
      }
      return true;
    };
    const bool located = NarrowBracket(tolerance, eval, &a, &b,
                                       slip0[i].dot(from), slip1[i].dot(from));
    // The split's slips (a later point on b's side may have replaced them).
    if (b < t1 && t_at_b != b && !evaluate(b, &at_b)) break;
    // Not narrowed (the crossing lies within the tolerance of t1): no split
    // for this wheel; the other wheels are still examined.
    if (!(b < t1)) continue;
    if (reversed) *reversed = true;
    if (creeping) {  // the reversal is the event
      SwitchEvent e = BracketedEvent(i + 1, a, b, located);
      e.reversal = true;
      out->push_back(e);
    }
    LocateInPiece(t0, b, slip0, at_b, epsilon, tolerance, evaluate,
                  located_reversals | (1u << i), out, nullptr, before);
    LocateInPiece(b, t1, at_b, slip1, epsilon, tolerance, evaluate,
                  located_reversals, out, nullptr, before);
    SortAppended(first, out);
    return static_cast<int>(out->size() - first);
  }
  return LocateSwitches(t0, t1, Norms(slip0), Norms(slip1), epsilon, tolerance,
                        norms, out);
}
}  // namespace

int LocateSwitchesAndReversals(double t0, double t1,
                               const std::array<Eigen::Vector2d, 3>& slip0,
                               const std::array<Eigen::Vector2d, 3>& slip1,
                               double epsilon, double tolerance,
                               const SlipVectorEvaluator& evaluate,
                               std::vector<SwitchEvent>* out, bool* reversed,
                               const std::array<Eigen::Vector2d, 3>* before) {
  return LocateInPiece(t0, t1, slip0, slip1, epsilon, tolerance, evaluate, 0u,
                       out, reversed, before);
}

bool IntegrateResolved(double a, double b, double tolerance, double min_step,
                       const SegmentAdvance& advance, Eigen::VectorXd* y,
                       ResolvedStop* stop) {
  if (!(b > a)) throw std::invalid_argument("IntegrateResolved: b must be > a");
  if (!(min_step > 0))
    throw std::invalid_argument("IntegrateResolved: min_step must be > 0");
  Eigen::VectorXd one, two;
  auto fail = [stop](double t, double t_failed) {
    if (stop) *stop = {t, t_failed};
    return false;
  };
  // One call on *y itself: an integrator that keeps its history across
  // calls (IDA) continues only from the state it returned.
  if (!(tolerance < std::numeric_limits<double>::infinity()))
    return advance(a, b, y);
  // March forward (warm starts of the solves along the way stay near the
  // state): try h as two half steps, then as one; accept the two halves
  // when they agree with the one step, then try 2h; else halve h. A state
  // from which no step of min_step succeeds (a quasi-static solve that
  // cannot meet its tolerance there, seen at the centre of a transition) is
  // left by redoing the step that reached it at 0.6, 0.36, ... of its size
  // (up to kMaxBackups times), so that the march lands elsewhere. The count
  // restarts only once the march gets past the failed piece's end (`wall`):
  // short of a limit that no step passes (a wheel's friction use -> 1), the
  // backups would otherwise crawl towards it in ever shorter steps.
  constexpr int kMaxBackups = 8;
  double t = a, h = b - a;
  double t_back = a, h_back = 0;
  double wall = -std::numeric_limits<double>::infinity();
  Eigen::VectorXd y_back = *y;
  int backups = 0;
  while (t < b) {
    h = std::min(h, b - t);
    const double m = t + 0.5 * h, e = h >= b - t ? b : t + h;
    if (!(m > t && m < e)) {  // a piece of a few ulps
      if (e < b) return fail(t, std::min(b, t + min_step));  // stalled
      two = *y;
      if (!advance(t, e, &two)) return fail(t, e);
      *y = two;
      return true;
    }
    two = *y;
    const bool ok_two = advance(t, m, &two) && advance(m, e, &two);
    one = *y;
    const bool ok_one = ok_two && advance(t, e, &one);
    const bool last = h <= min_step;
    if (ok_two && (last || (ok_one && (one - two).lpNorm<Eigen::Infinity>() <=
                                          tolerance))) {
      if (e > wall) backups = 0;
      t_back = t;
      h_back = e - t;
      y_back = *y;
      *y = two;
      t = e;
      h *= 2.0;
    } else if (last) {
      wall = std::max(wall, e);
      if (!(h_back > 0) || ++backups > kMaxBackups) return fail(t, e);
      t = t_back;
      *y = y_back;
      h = std::pow(0.6, backups) * h_back;
    } else {
      h *= 0.5;
    }
  }
  return true;
}

namespace {
using Slips = std::array<double, 3>;

// Adaptive Simpson on [a, b] for the three slip speeds (f at a, m, b known;
// `whole` the Simpson estimate); adds the integrals to *sum.
bool SimpsonSlips(double a, const Slips& fa, double m, const Slips& fm,
                  double b, const Slips& fb, const Slips& whole,
                  const Slips& tol, int depth, const SlipEvaluator& evaluate,
                  Slips* sum, int* evaluations) {
  const double lm = 0.5 * (a + m), rm = 0.5 * (m + b);
  Slips flm, frm;
  *evaluations += 2;
  if (!evaluate(lm, &flm) || !evaluate(rm, &frm)) return false;
  Slips left, right;
  bool good = true;
  for (int i = 0; i < 3; ++i) {
    left[i] = (m - a) / 6 * (fa[i] + 4 * flm[i] + fm[i]);
    right[i] = (b - m) / 6 * (fm[i] + 4 * frm[i] + fb[i]);
    good = good && std::abs(left[i] + right[i] - whole[i]) <= 15 * tol[i];
  }
  if (good || depth == 0) {
    for (int i = 0; i < 3; ++i)
      (*sum)[i] += left[i] + right[i] + (left[i] + right[i] - whole[i]) / 15;
    return true;
  }
  Slips half;
  for (int i = 0; i < 3; ++i) half[i] = 0.5 * tol[i];
  return SimpsonSlips(a, fa, lm, flm, m, fm, left, half, depth - 1, evaluate,
                      sum, evaluations) &&
         SimpsonSlips(m, fm, rm, frm, b, fb, right, half, depth - 1, evaluate,
                      sum, evaluations);
}

// The time in (a, b) at which wheel i's slip speed crosses `level`, its
// class (IsSliding) differing at a and b: Illinois (regula falsi that halves
// the retained end's weight) on the bounded h = (|s| - level)/(|s| + level),
// stopped when |h| <= 1e-4 (the slip within 2e-4 of the level) or the
// bracket is <= 1e-9 (b - a). A mislocation by dt moves ~level dt between
// the regimes: 2e-4 level^2 / |ds/dt|, 4e-4 of the (already O(eps^2))
// slide tail below the level. *at receives the slips there. False if an
// evaluation fails.
bool LocateSlipLevel(double a, double ha, double b, double hb, int i,
                     double level, const SlipEvaluator& evaluate, double* t,
                     Slips* at, int* evaluations) {
  const double width = 1e-9 * (b - a);
  int side = 0;
  for (int k = 0; k < 60; ++k) {
    double m = (a * hb - b * ha) / (hb - ha);
    if (!(m > a && m < b)) m = 0.5 * (a + b);
    ++*evaluations;
    if (!evaluate(m, at)) return false;
    const double h = LevelIndicator((*at)[i], level);
    if (std::isnan(h)) return false;
    *t = m;
    if (std::abs(h) <= 1e-4 || b - a <= width) return true;
    IllinoisUpdate((h >= 0) != (hb >= 0), m, h, &a, &ha, &b, &hb, &side);
  }
  return true;
}

// Adaptive Simpson on [a, b] (slips fa, fb and, if not null, those at the
// midpoint known) credited per wheel to the regime at the midpoint; adds to
// *out.
bool IntegratePiece(double a, const Slips& fa, double b, const Slips& fb,
                    const Slips* midpoint, double epsilon,
                    const SlipEvaluator& evaluate, SlipIncrements* out,
                    int* evaluations) {
  constexpr int kMaxDepth = 8;
  const double m = 0.5 * (a + b);
  Slips fm, whole, tol, sum{};
  if (midpoint) {
    fm = *midpoint;
  } else {
    ++*evaluations;
    if (!evaluate(m, &fm)) return false;
  }
  for (int i = 0; i < 3; ++i) {
    whole[i] = (b - a) / 6 * (fa[i] + 4 * fm[i] + fb[i]);
    tol[i] = std::max(1e-3 * std::abs(whole[i]), 1e-3 * epsilon * (b - a));
  }
  if (!SimpsonSlips(a, fa, m, fm, b, fb, whole, tol, kMaxDepth, evaluate, &sum,
                    evaluations))
    return false;
  for (int i = 0; i < 3; ++i)
    (IsSliding(fm[i], epsilon) ? (*out)[i].sliding : (*out)[i].creep) += sum[i];
  return true;
}

// One piece between two kinks: split further where a wheel's slip crosses
// the sliding level (its class differs between a, the midpoint and b:
// one crossing per half, e.g. both sides of a reversal's stick window).
bool IntegrateBetweenKinks(double a, const Slips& fa, double b, const Slips& fb,
                           double epsilon, const SlipEvaluator& evaluate,
                           SlipIncrements* out, int* evaluations) {
  const double m = 0.5 * (a + b);
  Slips fm;
  ++*evaluations;
  if (!evaluate(m, &fm)) return false;
  const double level = kSlidingSlipOverEpsilon * epsilon;
  // At most two crossings per wheel; their times and slips, unsorted.
  std::array<double, 6> cuts;
  std::array<Slips, 6> at;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    const std::array<std::array<double, 2>, 2> halves{{{a, m}, {m, b}}};
    const std::array<std::array<double, 2>, 2> ends{
        {{fa[i], fm[i]}, {fm[i], fb[i]}}};
    for (int k = 0; k < 2; ++k) {
      const double h0 = LevelIndicator(ends[k][0], level);
      const double h1 = LevelIndicator(ends[k][1], level);
      if (std::isnan(h0) || std::isnan(h1) || (h0 >= 0) == (h1 >= 0)) continue;
      if (!LocateSlipLevel(halves[k][0], h0, halves[k][1], h1, i, level,
                           evaluate, &cuts[n], &at[n], evaluations))
        return false;
      ++n;
    }
  }
  std::array<int, 6> order{0, 1, 2, 3, 4, 5};
  for (int k = 1; k < n; ++k)  // insertion sort by time
    for (int j = k; j > 0 && cuts[order[j]] < cuts[order[j - 1]]; --j)
      std::swap(order[j], order[j - 1]);
  double ta = a;
  Slips sa = fa;
  for (int k = 0; k <= n; ++k) {
    const double tb = k < n ? cuts[order[k]] : b;
    const Slips& sb = k < n ? at[order[k]] : fb;
    if (!(tb > ta)) continue;
    if (!IntegratePiece(ta, sa, tb, sb, n == 0 ? &fm : nullptr, epsilon,
                        evaluate, out, evaluations))
      return false;
    ta = tb;
    sa = sb;
  }
  return true;
}
}  // namespace

bool IntegrateSlipRegimes(double t0, double t1, const Slips& slip0,
                          const Slips& slip1, const std::vector<double>& breaks,
                          double epsilon, const SlipEvaluator& evaluate,
                          SlipIncrements* out, int* evaluations,
                          const std::vector<std::array<double, 2>>& jumps) {
  if (!(t1 > t0))
    throw std::invalid_argument("IntegrateSlipRegimes: t1 must be > t0");
  *out = SlipIncrements{};
  *evaluations = 0;
  // A probe whose solve fails (a Newton stall in the steep transition at a
  // switch) is retried 1e-6 and 2e-6 of the interval to either side; the
  // slips there stand for those at t (an error ~|ds/dt| 2e-6 (t1 - t0) in a
  // node). Without it one failed probe dropped the whole interval to the
  // two-sample trapezoid: paper scene at event_tolerance 2e-9, wheel 1's
  // sliding over [2.90, 2.95] s 7.6e-7 m instead of 1.26e-6 m.
  struct Retry {
    const SlipEvaluator& evaluate;
    double t0, t1;
    int* evaluations;
  } retry{evaluate, t0, t1, evaluations};
  const SlipEvaluator robust = [&retry](double t, Slips* f) {
    if (retry.evaluate(t, f)) return true;
    const double step = 1e-6 * (retry.t1 - retry.t0);
    for (const double k : {1.0, -1.0, 2.0, -2.0}) {
      const double tk = t + k * step;
      if (!(tk > retry.t0 && tk < retry.t1)) continue;
      ++*retry.evaluations;
      if (retry.evaluate(tk, f)) return true;
    }
    return false;
  };
  double a = t0;
  Slips fa = slip0;
  for (std::size_t j = 0; j <= breaks.size(); ++j) {
    const double b = j < breaks.size() ? breaks[j] : t1;
    if (!(b > a) || b > t1) continue;
    Slips fb = slip1;
    if (j < breaks.size()) {
      ++*evaluations;
      if (!robust(b, &fb)) return false;
    }
    const bool jump = std::any_of(jumps.begin(), jumps.end(),
                                  [a, b](const std::array<double, 2>& k) {
                                    return k[0] == a && k[1] == b;
                                  });
    if (jump) {  // the trapezoid on the two roots' one-sided values
      for (int i = 0; i < 3; ++i)
        CreditTrapezoid(0.5 * (b - a), fa[i], fb[i], epsilon,
                        &(*out)[i].sliding, &(*out)[i].creep);
    } else if (!IntegrateBetweenKinks(a, fa, b, fb, epsilon, robust, out,
                                      evaluations)) {
      return false;
    }
    a = b;
    fa = fb;
  }
  return true;
}

}  // namespace quasiroll
