// Checkpoints: the method's state at fixed times that do not depend on its
// output interval dt or tolerance (docs/harness.md, "Errors at
// checkpoints"), so that accuracy metrics compare every method of a problem
// at the same instants and a coarse grid cannot look accurate by skipping a
// force spike between its samples.
//
// Times. CheckpointTimes builds the set of a problem: the reference's
// output samples at every m-th index, m = max(1, round(interval / h_ref))
// (a uniform grid of spacing m h_ref ~ interval, on the reference's own
// samples, so the reference is compared where it was computed and not
// interpolated), plus the reference's last time (t_end, or the located
// stop of a reference that met a physical limit), plus any extra times
// (e.g. located switch times of the reference). The set depends on the
// problem and the reference only.
//
// State. The simulator never shortens a step for a checkpoint (its output
// samples, trajectory.csv, are unchanged). A checkpoint t_c inside a hold
// interval [t0, t1] (t0 < t_c < t1) is read from the interval's dense
// output, the cubic Hermite interpolant (core/limit_events.h) of the
// method's own end states Theta_0, Theta_1 and the exact right-hand sides
// F_0 = F(Theta_0, w_0), F_1 = F(Theta_1, w_1) of the ODE the method
// integrates:
//   zoh      w_0 = w_1 = the held twist (the ODE is Theta' = F(Theta, w));
//   coupled  w_0 = w(Theta_0) of the sample solve at t0, w_1 = w(Theta_1)
//            solved at Theta_1.
// The Hermite interpolant of exact end values and slopes has error
// h^4/384 max|Theta''''| (h = t1 - t0). With end values of the method's own
// accuracy the checkpoint error is the method's error at the ends plus
// O(h^4):
//   RK4, one step per interval (the default ladders)   order 4, as RK4;
//   RK2/RK3, Euler (fixed step)                        the method's order;
//   fixed step with substeps s, or adaptive DP5(4),    the method's error
//   IDA, CVODE (output interval h)                     plus O(h^4) of the
//                                                      output interval, not
//                                                      of the internal step.
// A checkpoint that coincides with an output sample (|t_c - t_k| <= 1e-9 s)
// is that sample. A run records no checkpoint past its stop: those read from
// the last interval beyond a stop located inside it are dropped, and where
// a coupled run's integrator fails inside an interval (no end state, so no
// dense output) the checkpoints before the located stop in that interval
// are not recorded either (the run is measured over fewer checkpoints).
//
// Forces. The metrics compare forces and slip at checkpoints too; which
// quasi-static solution belongs to a checkpoint is the one the method
// *applies* there:
//   zoh      the solution held over the interval (solved at t0): the method
//            moves with it until t1, so a spike between two samples that the
//            held forces miss is an error of the method, as it is;
//   coupled  the method applies w(Theta(t)) at every instant: one
//            quasi-static solve at the interpolated state, by a solver of
//            its own (its own warm start: the method's solver, and so its
//            trajectory, are untouched), counted in checkpoint_solves and
//            not in nlp_solves; its time is not in wall_s.
// Cost: one comparison per interval; an interval holding a checkpoint costs
// two right-hand sides (zoh) or two solves (coupled) and the sample's
// kinematics. Allocation-free once the output vector is reserved (Begin).
#pragma once

#include <vector>

#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/quasi_static.h"

namespace quasiroll {

struct TrajectorySample;
enum class Coupling;

// The checkpoint times of a problem (see above): `reference_times` sorted
// ascending (the reference's sample times); `interval` > 0 [s]; `extra`
// times (any order) within [0, reference_times.back()] are added. t = 0 is
// not a checkpoint (every run starts from the same state). Sorted, with
// times closer than 1e-9 s merged. Throws std::invalid_argument for a
// non-positive or non-finite interval.
std::vector<double> CheckpointTimes(const std::vector<double>& reference_times,
                                    double interval,
                                    const std::vector<double>& extra = {});

// Fills sample `out` from the configuration and the quasi-static solution
// applied there (velocities, forces, slip NaN unless the solve is OK); the
// cumulative slip distances are left as they are.
void FillSample(const KinematicModel& model, double t,
                const Configuration& theta, const QuasiStaticSolution& sol,
                TrajectorySample* out);

// Records the checkpoints of one run (used by the Simulator).
class CheckpointRecorder {
 public:
  CheckpointRecorder(const KinematicModel& model, Coupling coupling);

  // Starts a run: `times` sorted ascending (SimulationOptions::checkpoints),
  // `out` cleared and reserved; `solver` for the coupled solves (not used in
  // zoh; may be null there). Counters reset.
  void Begin(const std::vector<double>* times, QuasiStaticSolver* solver,
             std::vector<TrajectorySample>* out);
  // An output sample was recorded: checkpoints recorded after its time (a
  // stop located before the end of the last interval) are dropped, and those
  // at its time take it.
  void AtSample(const TrajectorySample& sample,
                std::vector<TrajectorySample>* out);
  // The interval after t0 is integrated again (a switch restart, core/
  // switch_events.h): the checkpoints recorded after t0 are dropped and
  // InInterval records them anew.
  void Rewind(double t0, std::vector<TrajectorySample>* out);
  // The interval [t0, t1] was integrated from theta0 (sample solve sol0,
  // joint rates w0 applied at t0) to theta1; checkpoints in (t0, t_limit)
  // (t_limit <= t1: a located stop) are recorded from the dense output.
  void InInterval(double t0, const Configuration& theta0,
                  const QuasiStaticSolution& sol0, const Vec12& w0, double t1,
                  const Configuration& theta1, double t_limit,
                  std::vector<TrajectorySample>* out);

  int solves() const { return solves_; }
  long long iterations() const { return iterations_; }
  // Wall time spent recording since Begin() [s] (excluded from wall_s).
  double seconds() const { return seconds_; }

 private:
  bool Slope(const Configuration& theta, const Vec12& w, Configuration* f);
  void Solve(const Configuration& theta, QuasiStaticSolution* sol);

  const KinematicModel& model_;
  Coupling coupling_;
  const std::vector<double>* times_ = nullptr;
  QuasiStaticSolver* solver_ = nullptr;
  std::size_t next_ = 0;
  int solves_ = 0;
  long long iterations_ = 0;
  double seconds_ = 0;
  QuasiStaticSolution sol1_, sol_c_;
  Configuration f0_, f1_, theta_c_;
};

}  // namespace quasiroll
