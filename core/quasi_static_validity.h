// Quasi-static validity of a simulated motion (docs/model.md §8.8): how
// large the inertial loads the model drops are against the contact forces it
// keeps. A pure function of the samples and the scene; the harness reports it
// as qs_inertia_ratio (runs.csv, run.json).
#pragma once

#include <vector>

#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {

// The validity threshold of the ratio below (docs/model.md §8.8): inertial
// loads at 1 % of the contact loads.
constexpr double kQuasiStaticInertiaThreshold = 1e-2;

// Principal moments of inertia [kg m^2] the validity metric assumes: scenes
// carry only the mass, so the robot is taken as a uniform solid box spanning
// its wheel footprint — length a + b (wheelbase), width `track`, height
// z_h + rho (platform above the ground) — I = m/12 (W^2 + H^2, L^2 + H^2,
// L^2 + W^2) about the platform axes (x forward, y left, z up).
Vec3 EstimatedInertia(const Scene& scene);

// Quasi-static validity (docs/model.md §8.8): the max
// over the samples of
//   (m |a_com| + |I_w alpha + omega x I_w omega| / L0) / sum_i |F_i|
// with a_com, alpha from central differences of the recorded COM and angular
// velocities (one-sided at the ends and next to samples without velocities,
// e.g. a failed solve), I_w = R diag(EstimatedInertia) R^T, L0 = a + b (the
// quasi-static problem's moment scale) and |F_i| = |(n_i, t_lon_i, t_lat_i)|.
// NaN with fewer than two samples with finite velocities and forces.
double QuasiStaticInertiaRatio(const std::vector<TrajectorySample>& run,
                               const Scene& scene);
// The same over a run's samples with result.stop_retry (the twist at or
// just before the stop, solved after the run) in place of the stop's own
// sample, or after the last sample when the stop has none: the motion up to
// the stop
// includes the twist there (a breakaway's diverging twist, model.md §8.8,
// lies between the last usable sample and the stop, where no sample sees
// it).
double QuasiStaticInertiaRatio(const SimulationResult& result,
                               const Scene& scene);
// The ratio at result.stop_retry alone (its difference to the last usable
// sample, as above): whether the stop's own twist leaves the quasi-static
// domain (a breakaway, model.md §8.8), apart from the motion before it.
// NaN without a stop_retry or a usable sample before it.
double StopInertiaRatio(const SimulationResult& result, const Scene& scene);

}  // namespace quasiroll
