// Integrator backend conformance suites (docs/plugins.md, "Conformance kit").
//
// One line in a test file linking quasiroll::conformance and
// GTest::gtest_main runs every check on a registered integrator:
//
//   QUASIROLL_INTEGRATOR_CONFORMANCE(my_method, "my-method");
//   QUASIROLL_INTEGRATOR_CONFORMANCE(my_rk, "my-rk",
//                                    .backend_options = {{"scheme", "dp54"}});
//
// The optional arguments after the name initialise
// IntegratorConformanceTraits: backend options every accuracy check sets
// first (e.g. an adaptive scheme, or substeps), and the step of the Andrews
// check (0: the method's own starting step, which a fixed-step method takes
// as one step over the whole 0.03 s).
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <ostream>
#include <string>

#include "quasiroll/conformance/integrator_reference_problems.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/options.h"

namespace quasiroll {
// GTest prints statuses by name.
inline void PrintTo(IntegratorStatus status, std::ostream* os) {
  *os << ToString(status);
}
}  // namespace quasiroll

namespace quasiroll::conformance {

struct IntegratorConformanceTraits {
  // Set with SetBackendOptions() before the accuracy checks.
  GivenOptions backend_options;
  // IntegratorOptions::step of the Andrews check.
  double andrews_step = 0.0;
};

struct IntegratorConformanceParam {
  std::string backend;  // IntegratorRegistry name
  IntegratorConformanceTraits traits;
};
void PrintTo(const IntegratorConformanceParam& param, std::ostream* os);

// Bounds of the accuracy checks (origins in integrator_conformance.cc).
inline constexpr double kPendulumPositionTolerance = 3e-6;
inline constexpr double kPendulumDriftTolerance = 1e-7;
inline constexpr double kAndrewsAngleTolerance = 2e-5;
inline constexpr double kAndrewsDriftTolerance = 1e-8;

// Pendulum (PendulumOde) from 0.5 rad at rest, 2 s as 40 hold intervals of
// 0.05 s (one Integrate() each, as the simulator calls it), step 0.01, rtol
// 1e-8, atol 1e-10: every call kSuccess ending on its t1, |y(2) - reference|
// <= kPendulumPositionTolerance, ||H(y(2))|| <= kPendulumDriftTolerance.
void ExpectPendulumAccuracy(Integrator& integrator);
// Andrews' mechanism (SevenBodyMechanismOde) over [0, 0.03] in one call,
// step `step`, rtol 1e-9, atol 1e-11: kSuccess, the angles beta, Theta,
// gamma within kAndrewsAngleTolerance of the test set's reference, ||H|| <=
// kAndrewsDriftTolerance.
void ExpectAndrewsAccuracy(Integrator& integrator, double step = 0.0);
// As ExpectOptionTableValid for NLP backends (nlp_conformance.h).
void ExpectOptionTableValid(Integrator& integrator);

class IntegratorConformanceTest
    : public ::testing::TestWithParam<IntegratorConformanceParam> {
 protected:
  // The backend from the registry, with the traits' backend options set.
  std::unique_ptr<Integrator> Create() const;
};

// Used by QUASIROLL_INTEGRATOR_CONFORMANCE; defined next to the TEST_Ps so
// that a registration links them in from the static library.
IntegratorConformanceParam MakeIntegratorConformanceParam(
    const std::string& backend, IntegratorConformanceTraits traits = {});
std::string IntegratorConformanceName(
    const ::testing::TestParamInfo<IntegratorConformanceParam>& info);

}  // namespace quasiroll::conformance

// The suites' names (gtest needs them unqualified where they are
// instantiated).
using QuasirollIntegratorConformance =
    ::quasiroll::conformance::IntegratorConformanceTest;

// Runs the integrator conformance suite on the registered backend
// `backend_name`; `id` is a C++ identifier naming the instantiation; an
// optional IntegratorConformanceTraits initialiser follows.
#define QUASIROLL_INTEGRATOR_CONFORMANCE(id, backend_name, ...)      \
  INSTANTIATE_TEST_SUITE_P(                                          \
      id, QuasirollIntegratorConformance,                            \
      ::testing::Values(                                             \
          ::quasiroll::conformance::MakeIntegratorConformanceParam(  \
              backend_name,                                          \
              ::quasiroll::conformance::IntegratorConformanceTraits{ \
                  __VA_ARGS__})),                                    \
      ::quasiroll::conformance::IntegratorConformanceName)
