#include "quasiroll/core/checkpoints.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "quasiroll/core/limit_events.h"
#include "quasiroll/core/simulator.h"
#include "quasiroll/core/so3.h"

namespace quasiroll {

namespace {
// Times closer than this are the same instant (as the metrics' matching).
constexpr double kTimeTol = 1e-9;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

std::vector<double> CheckpointTimes(const std::vector<double>& reference_times,
                                    double interval,
                                    const std::vector<double>& extra) {
  if (!(interval > 0) || !std::isfinite(interval))
    throw std::invalid_argument(
        "checkpoint_interval: must be finite and > 0, got " +
        std::to_string(interval));
  std::vector<double> times;
  if (reference_times.empty()) return times;
  const double t_last = reference_times.back();
  std::size_t m = 1;
  if (reference_times.size() >= 2) {
    const double h = reference_times[1] - reference_times[0];
    if (h > 0) m = std::max<std::size_t>(1, std::llround(interval / h));
  }
  for (std::size_t i = m; i < reference_times.size(); i += m)
    times.push_back(reference_times[i]);
  times.push_back(t_last);
  for (double t : extra)
    if (t > kTimeTol && t <= t_last + kTimeTol) times.push_back(t);
  std::sort(times.begin(), times.end());
  std::vector<double> merged;
  for (double t : times)
    if (t > kTimeTol && (merged.empty() || t - merged.back() > kTimeTol))
      merged.push_back(t);
  return merged;
}

void FillSample(const KinematicModel& model, double t,
                const Configuration& theta, const QuasiStaticSolution& sol,
                TrajectorySample* out) {
  TrajectorySample& s = *out;
  s.t = t;
  s.theta = theta;
  Mat3 R;
  model.PlatformPose(theta, &R, &s.position);
  s.rpy = RpyFromRotation(R);
  const bool ok = sol.status == QuasiStaticStatus::kOk;
  s.velocity = ok ? Vec3(R * sol.twist.head<3>()) : Vec3::Constant(kNaN);
  s.angular_velocity =
      ok ? Vec3(R * sol.twist.tail<3>()) : Vec3::Constant(kNaN);
  for (int j = 0; j < 6; ++j) s.joints[j] = theta(ConfigIndex::kTheta + j);
  for (int i = 0; i < 3; ++i) {
    ContactSample& c = s.contacts[i];
    const ContactOutput& o = sol.contacts[i];
    ChainState chain;
    model.EvaluateChain(theta, i, &chain);
    c.point = chain.p_c;
    c.normal_force = ok ? o.normal_force : kNaN;
    c.traction_lon = ok ? o.traction(0) : kNaN;
    c.traction_lat = ok ? o.traction(1) : kNaN;
    c.slip = ok ? o.slip.norm() : kNaN;
    c.friction_use = ok ? o.friction_use : kNaN;
  }
  LoopClosure h;
  model.Constraints(theta, &h);
  s.drift = h.lpNorm<Eigen::Infinity>();
  s.gap_max = GeometricGap(model, theta);
  s.nlp_status = ToString(sol.status);
  s.nlp_iterations = sol.nlp_iterations;
}

CheckpointRecorder::CheckpointRecorder(const KinematicModel& model,
                                       Coupling coupling)
    : model_(model), coupling_(coupling) {}

void CheckpointRecorder::Begin(const std::vector<double>* times,
                               QuasiStaticSolver* solver,
                               std::vector<TrajectorySample>* out) {
  times_ = times;
  solver_ = solver;
  next_ = 0;
  solves_ = 0;
  iterations_ = 0;
  seconds_ = 0;
  out->clear();
  if (times_) out->reserve(times_->size());
  if (solver_) solver_->Reset();
}

void CheckpointRecorder::Rewind(double t0, std::vector<TrajectorySample>* out) {
  if (!times_) return;
  while (!out->empty() && out->back().t > t0 + kTimeTol) out->pop_back();
  next_ = static_cast<std::size_t>(
      std::upper_bound(times_->begin(), times_->end(), t0 + kTimeTol) -
      times_->begin());
}

void CheckpointRecorder::AtSample(const TrajectorySample& sample,
                                  std::vector<TrajectorySample>* out) {
  if (!times_) return;
  if (!out->empty() && out->back().t > sample.t + kTimeTol) {
    while (!out->empty() && out->back().t > sample.t + kTimeTol)
      out->pop_back();
    next_ = static_cast<std::size_t>(
        std::lower_bound(times_->begin(), times_->end(), sample.t - kTimeTol) -
        times_->begin());
  }
  while (next_ < times_->size() && (*times_)[next_] <= sample.t + kTimeTol) {
    if ((*times_)[next_] >= sample.t - kTimeTol) {
      out->push_back(sample);
      out->back().t = (*times_)[next_];
      for (ContactSample& c : out->back().contacts)
        c.sliding_distance = c.creep_distance = kNaN;
    }
    ++next_;  // a time before the sample not recorded: the run skipped it
  }
}

bool CheckpointRecorder::Slope(const Configuration& theta, const Vec12& w,
                               Configuration* f) {
  return model_.Rhs(theta, w, f);
}

void CheckpointRecorder::Solve(const Configuration& theta,
                               QuasiStaticSolution* sol) {
  solver_->Solve(theta, sol);
  solves_ += sol->nlp_solves;
  iterations_ += sol->nlp_iterations;
}

void CheckpointRecorder::InInterval(double t0, const Configuration& theta0,
                                    const QuasiStaticSolution& sol0,
                                    const Vec12& w0, double t1,
                                    const Configuration& theta1, double t_limit,
                                    std::vector<TrajectorySample>* out) {
  if (!times_ || next_ >= times_->size() ||
      (*times_)[next_] >= t_limit - kTimeTol)
    return;
  const auto start = std::chrono::steady_clock::now();
  const bool coupled = coupling_ == Coupling::kCoupled;
  const double h = t1 - t0;
  // The end slopes; without them (K singular, a failed solve at Theta_1)
  // the dense output is linear.
  bool hermite = Slope(theta0, w0, &f0_);
  if (hermite && coupled) {
    Solve(theta1, &sol1_);
    hermite =
        sol1_.status == QuasiStaticStatus::kOk &&
        Slope(theta1, solver_->problem().JointSpaceVelocity(sol1_.z), &f1_);
  } else if (hermite) {
    hermite = Slope(theta1, w0, &f1_);
  }
  for (; next_ < times_->size() && (*times_)[next_] < t_limit - kTimeTol;
       ++next_) {
    const double tc = (*times_)[next_];
    if (tc <= t0 + kTimeTol) continue;  // at t0: taken by AtSample
    const double s = (tc - t0) / h;
    if (hermite) {
      theta_c_ = HermiteState(theta0, f0_, theta1, f1_, h, s);
    } else {
      theta_c_ = (1.0 - s) * theta0 + s * theta1;
    }
    if (coupled) Solve(theta_c_, &sol_c_);
    out->emplace_back();
    FillSample(model_, tc, theta_c_, coupled ? sol_c_ : sol0, &out->back());
    for (ContactSample& c : out->back().contacts)
      c.sliding_distance = c.creep_distance = kNaN;
  }
  seconds_ +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
}

}  // namespace quasiroll
