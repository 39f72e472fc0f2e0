// The retry ladder of numerical references (docs/harness.md, "Reference
// retries"): a reference is the ground truth of every verdict, so it must not
// stop on its own numerical failure where methods go on.
//
// A reference run stops for one of three reasons (ReferenceStopOf):
//   end                 it reached t_end;
//   physical:<limit>    a physical limit of the model (status
//                       INFEASIBLE_FRICTION, LIFT_OFF or DEGENERATE_CONTACT;
//                       <limit> is the located StopEvent::limit, e.g.
//                       friction_limit, relative_curvature, second_contact,
//                       or the status's own name when none was located);
//   model:breakaway     a stop that is not physical, whose own twist
//                       (SimulationResult::stop_retry, solved after the run)
//                       leaves the quasi-static domain: StopInertiaRatio over
//                       kQuasiStaticInertiaThreshold (the twist diverges
//                       there, model.md §8.8). No rung is tried: past that
//                       point the quasi-static problem has no root, and a
//                       rung that steps across lands on a motion the model
//                       does not describe;
//   reference_failure   anything else (SOLVER_FAILURE, SINGULAR, an
//                       integrator status) that persisted through the ladder.
//
// The ladder (RunReferenceWithRetries). When the run stops on anything but a
// physical limit, its last good state is the last sample on the output grid
// t_k = k h (h the reference's output interval) whose quasi-static solve
// succeeded (nlp_status OK). From that state (t_g, Theta_g) the failing
// interval [t_g, min(t_g + h, t_end)] is run again by a fresh Simulator with,
// in order, until one rung reaches its end or meets a physical limit:
//   1. step/4    the integrator step divided by 4;
//   2. step/16   divided by 16;
//   3. nlp       the second NLP backend (SecondReferenceNlp), the primary
//                step and tolerance;
//   4. relaxed   the primary backend at residual tolerance
//                kRelaxedToleranceFactor x the reference's (1e-9 for 1e-12)
//                over that interval only; the continuation returns to the
//                reference's own tolerance at the interval's end, so the next
//                solve polishes the state back to it (the backends' own
//                active-set polish, core/nlp_polish.h, is part of their
//                solve at every tolerance).
// The rung's samples replace the run's after t_g (times shifted by t_g,
// cumulative slip distances continued); then the primary configuration
// continues from t_g + h to t_end with a fresh Simulator and may be rescued
// again, at most kMaxReferenceRescues times per reference. When every rung
// fails, the run keeps its samples as they were and is a reference failure.
// Every run of the ladder (the primary's, each rung's, each continuation's)
// is an attempt in the log, and its cost is added to the result's counters.
// The simulator the methods use is unchanged.
#pragma once

#include <string>
#include <vector>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll::bench {

// The version of the rules above that decide where a reference stops,
// written into references/<hash>.json (`stop_rules`): 2 since breakaways
// (model:breakaway). A cache written under other rules is recomputed, since
// the key names only the scene and the reference settings.
constexpr int kReferenceStopRules = 2;

// Failing intervals one reference may rescue (each rescue costs at most
// 4 + 16 + cost_ratio + 1 output intervals' worth of solves; 50 of them stay
// below the ~1600 intervals of a 20 s reference at h = 0.0125 s).
constexpr int kMaxReferenceRescues = 50;
// Rung 4's residual tolerance over the reference's.
constexpr double kRelaxedToleranceFactor = 1e3;

// One run of the ladder, times absolute [s].
struct ReferenceAttempt {
  // "primary" (the first run and every continuation), "step/4", "step/16",
  // "nlp", "relaxed", or "rerun" (a whole rerun, ComputeNumericalReference).
  std::string rung;
  std::string detail;  // what the rung changed ("" for primary)
  double t_start = 0;  // the state it started from
  double t_end = 0;    // the end of the span it was to cover
  std::string status;  // its SimulationResult::status
  double t_reached = 0;
};

struct ReferenceRetryLog {
  std::vector<ReferenceAttempt> attempts;
  int rescues = 0;   // failing intervals a rung passed
  std::string stop;  // ReferenceStopOf the returned result
};

// INFEASIBLE_FRICTION, LIFT_OFF, DEGENERATE_CONTACT.
bool IsPhysicalReferenceStatus(const std::string& status);
// A stop at a breakaway (above).
bool BreakawayStop(const SimulationResult& result, const Scene& scene);
// "end", "physical:<limit>", "model:breakaway" or "reference_failure"
// (above).
std::string ReferenceStopOf(const SimulationResult& result, const Scene& scene);

// The second NLP backend of the ladder, chosen from the registry by
// BackendInfo, never by name: among the registered backends other than
// `primary` that may run concurrently (thread_safe; references are computed
// by parallel jobs), one of another method family than the primary's if any,
// the cheapest by cost_ratio (unknown = 0 last), ties by name. "" when none.
std::string SecondReferenceNlp(const std::string& primary);

// Runs `options` (coupled, fixed-step: the numerical reference's primary
// configuration) with the ladder above; *log (required) receives the
// attempts, the number of rescues and the stop.
SimulationResult RunReferenceWithRetries(const Scene& scene,
                                         const SimulationOptions& options,
                                         ReferenceRetryLog* log);

}  // namespace quasiroll::bench
