// Reference trajectories of the benchmark harness (docs/harness.md):
// closed-form solutions where the scene admits one (model.md §9.1, oracles
// O1, O2, O3), otherwise the most accurate numerical configuration; cached on
// disk under DIR/references/<hash>.csv keyed by FNV-1a 64 of a canonical text
// of the scene's effective parameters and the reference settings.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/bench/harness/reference_retry.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/terrains.h"

namespace quasiroll::bench {

enum class AnalyticCase {
  kNone,
  kFlatStraight,  // O1: plane, steer 0, equal spin rates
  kCircle,        // O2: plane, steer locked at phi1 != 0, consistent rates
  kIncline,       // O3: incline, straight up or down the gradient
};
const char* ToString(AnalyticCase c);  // "none", "flat", "circle", "incline"

// Decides whether `scene` (terrain built from `terrain`) has a closed-form
// quasi-static trajectory, and which. All conditions must hold exactly (up to
// 1e-12 relative rounding on the rates):
//  * common: camber_offset = 0; initial cambers delta2 = delta3 = 0; steer
//    rate 0; in paper mode camber rates 0 (pvc ignores the passive rates
//    alpha1', delta2', delta3');
//  * kFlatStraight: plane terrain, phi1 = 0, equal driven spin rates
//    (paper: alpha1' = alpha2' = alpha3'; pvc: alpha2' = alpha3'). Motion:
//    straight along the initial heading at v = rho alpha', height h + h_c;
//  * kCircle: plane terrain, 0 < |phi1| < pi/2 and the rates of O2: with
//    v = rho (alpha2' + alpha3')/2 and omega = v tan(phi1)/L,
//    rho (alpha3' - alpha2') = omega t and (paper mode) alpha1' =
//    v / (rho cos phi1). Motion: the rear-axle centre turns about the fixed
//    point L/tan(phi1) to its left at yaw rate omega (COM radius
//    sqrt((L/tan phi1)^2 + b^2));
//  * kIncline: incline terrain (slope beta != 0), phi1 = 0, heading along
//    the gradient (yaw = azimuth or azimuth + pi), equal driven spin rates,
//    and friction sufficient for rolling (paper: mu > tan beta; pvc:
//    mu > L sin beta / (a cos beta +- h_c sin beta), + nose up). Motion:
//    straight along the slope at v = rho alpha'.
// `why_not` (optional) receives the first failed condition.
AnalyticCase DetectAnalyticCase(const Scene& scene, const TerrainSpec& terrain,
                                std::string* why_not = nullptr);

// The closed-form trajectory of a detected case (throws std::logic_error
// for kNone). Sample(t) fills pose, velocities, joints, contact points,
// normal forces (static load distribution), tractions, creep slip
// eps q / sqrt(1 - q^2) with q = |f_t| / (mu f_n), drift 0, gap 0.
class AnalyticSolution {
 public:
  AnalyticSolution(const Scene& scene, const TerrainSpec& terrain,
                   AnalyticCase kind);
  AnalyticCase kind() const { return kind_; }
  TrajectorySample Sample(double t) const;

 private:
  Scene scene_;
  AnalyticCase kind_;
  double rho_ = 0, h_c_ = 0, L_ = 0, mg_ = 0;
  double v_ = 0, omega_ = 0;       // speed of the reference point, yaw rate
  std::array<double, 6> rates_{};  // effective joint rates
  Mat3 R0_ = Mat3::Identity();     // initial orientation
  Vec3 p0_ = Vec3::Zero();         // initial COM
  Vec3 icr_ = Vec3::Zero();        // circle: fixed turning centre
  double rear_radius_ = 0;         // circle: signed L / tan(phi1)
  std::array<double, 3> normal_{}, traction_{}, slip_{};
};

struct Reference {
  std::string hash;    // 16 hex digits of FNV-1a 64 of `key`
  std::string key;     // canonical text (scene + settings)
  std::string kind;    // "analytic:flat" ..., "numerical", "numerical:dp54"
  std::string status;  // "success" or the numerical run's status
  std::string stop_reason;
  // Why the reference ended (runs.csv reference_stop, reference_retry.h):
  // "end", "physical:<limit>", "model:breakaway" or "reference_failure".
  std::string stop;
  // Failing intervals the retry ladder passed (0 for an analytic reference).
  int rescues = 0;
  std::string scene;  // suite scene name (informational)
  // Max over the reference samples of the quasi-static solver's mu_min
  // (runs.csv ref_mu_min); NaN when not computed (analytic references).
  double mu_min_max = std::numeric_limits<double>::quiet_NaN();
  // Estimated position error [m]: max |p_ref - p_check| against a check
  // reference of another method family (runs.csv ref_err_est); NaN if none.
  double err_est = std::numeric_limits<double>::quiet_NaN();
  // Where the reference ended minus where its check ended [s] (runs.csv
  // ref_check_t_diff): 0 when both reach t_end; for a stop, how far the
  // check confirms it. NaN if no check ran.
  double check_t_diff = std::numeric_limits<double>::quiet_NaN();
  std::string method;        // how it was computed (method, step/tolerance)
  std::string check_method;  // the check reference's ("" if none)
  std::vector<TrajectorySample> samples;  // on the reference output grid
  std::optional<AnalyticSolution> analytic;

  // Samples to compare a run against: the exact solution at `times` if
  // analytic, else `samples` (interpolated by the metrics).
  std::vector<TrajectorySample> ForTimes(
      const std::vector<double>& times) const;
};

// Canonical key text of the reference of `scene`.
std::string ReferenceKey(const Scene& scene, const TerrainSpec& terrain,
                         const std::string& heightmap_digest,
                         const ReferenceSettings& settings);

// Numerical reference: coupled mode, rk-projection with RK4 at step
// scene.dt / (dt_divisor * substeps), output every scene.dt / dt_divisor,
// settings.nlp at settings.residual_tolerance, run with the retry ladder
// (reference_retry.h). If it still ends in a reference failure (a status
// other than success, INFEASIBLE_FRICTION, LIFT_OFF, DEGENERATE_CONTACT), it
// is repeated whole with DP5(4) at rtol 1e-10, atol 1e-12 (attempt "rerun")
// and the run that gets further is returned; *method (optional) receives
// "rk4" or "dp54", *log (optional) the attempts and the returned run's stop.
SimulationResult ComputeNumericalReference(const Scene& scene,
                                           const ReferenceSettings& settings,
                                           std::string* method = nullptr,
                                           ReferenceRetryLog* log = nullptr);

// The check reference of a numerical reference computed with
// `primary_method` ("rk4" or "dp54"): coupled, on the same output grid,
// another method family — DP5(4) (adaptive, error-controlled) at rtol 1e-10,
// atol 1e-12 for an RK4 reference; IDA (BDF, index 2) at the same
// tolerances for a DP5(4) one.
SimulationOptions CheckReferenceOptions(const Scene& scene,
                                        const ReferenceSettings& settings,
                                        const std::string& primary_method);
// "coupled rk-projection rk4 step 0.003125 s, output every 0.0125 s, newton
// at residual 1e-12" (references/<hash>.json `method`, meta.json).
std::string DescribeReferenceMethod(const SimulationOptions& options);
// Relative precision of ref_mu_min (MinimumFriction's bisection width):
// plenty for a friction threshold, ~40 % of the cost of the solver's 1e-11.
constexpr double kPathMuMinTolerance = 1e-6;
// Max over the samples (their configurations `theta`) of the quasi-static
// solver's mu_min (QuasiStaticProblem::MinimumFriction, to relative
// kPathMuMinTolerance): evaluated on every `stride`-th sample and the last,
// then on every sample within `stride` of the coarse maximum (paper mode
// costs ~10 ms per evaluation; mu_min varies on the bump scale, ~1 s of
// travel, so a coarse grid of 0.1 s plus refinement finds the grid maximum).
// +inf if a sample admits no contact forces (lift-off), NaN if none was
// computed.
double PathMinimumFriction(const Scene& scene,
                           const std::vector<TrajectorySample>& samples,
                           int stride = 1);

// Returns the reference of a scene, from DIR/references/<hash>.{csv,json}
// if present with the same key, else computed (analytic if allowed and
// detected) and written there atomically. `dir` empty = no cache. Exceptions
// of the computation propagate.
Reference LoadOrComputeReference(const std::string& dir, const Scene& scene,
                                 const TerrainSpec& terrain,
                                 const std::string& heightmap_digest,
                                 const ReferenceSettings& settings,
                                 const std::string& scene_label);

// Parses a trajectory.csv (TrajectoryCsv format; columns located by name).
// Throws std::runtime_error naming the line on malformed input.
std::vector<TrajectorySample> ParseTrajectoryCsv(const std::string& text);

}  // namespace quasiroll::bench
