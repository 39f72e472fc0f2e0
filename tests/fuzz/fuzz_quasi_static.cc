// libFuzzer target: the quasi-static solve near the paper scene's start.
//
// The bytes decode (FuzzedDataProvider) into: actuation mode, mu, epsilon,
// joint rates, whether diagnostics (mu_min, condition number) are computed,
// and 1-4 configurations solved in sequence by one QuasiStaticSolver with
// "newton" (so warm starts are exercised), each the paper scene's consistent
// initial configuration plus bounded perturbations of the contact coordinates
// (u, v: 0.4 rad, x_g, y_g: 0.1 m, psi: 0.4 rad) and joint angles (0.5 rad).
// Perturbed configurations violate the loop closure; the solver must cope.
// A selector byte may inject a non-finite coordinate or parameter.
// Every field is decoded so that zero bytes (and missing bytes) give the
// scene's own value (mu 0.5, epsilon 1e-8, zero perturbation): the fuzzer
// starts on the successful path and mutates away from it. (Failed solves are
// ~100x dearer than successful ones: they compute mu_min.)
//
// Contract checked: Solve() never crashes and never throws, except
// std::invalid_argument for non-finite input; a kOk solution has finite
// outputs and a residual within tolerance.
#include <fuzzer/FuzzedDataProvider.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/kinematics.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/scene.h"

namespace {

using namespace quasiroll;

struct Fixture {
  Scene scene;
  std::unique_ptr<KinematicModel> model;
  Configuration theta0;
};

const Fixture& GetFixture() {
  static const Fixture* fixture = [] {
    auto* f = new Fixture;
    f->scene = LoadScene(std::string(QUASIROLL_SOURCE_DIR) +
                         "/bench/scenes/paper.yaml");
    f->model =
        std::make_unique<KinematicModel>(f->scene.geometry, f->scene.terrain);
    f->theta0 = SolveInitialConfiguration(*f->model, f->scene);
    RegisterBuiltinNlpSolvers();
    return f;
  }();
  return *fixture;
}

[[noreturn]] void Bug(const std::string& what) {
  std::fprintf(stderr, "fuzz_quasi_static: %s\n", what.c_str());
  std::abort();
}

// Runs `call` (`what` on the fuzzed `input`), which must throw
// std::invalid_argument exactly when the input is non-finite and nothing
// else; false when it rejected non-finite input, as it should.
template <typename Call>
bool RejectsOnlyNonFinite(const char* what, const char* input, bool non_finite,
                          Call call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    if (non_finite) return false;
    Bug(std::string(what) + " threw for finite input: " + e.what());
  } catch (const std::exception& e) {
    Bug(std::string(what) + " threw " + typeid(e).name() + ": " + e.what());
  }
  if (non_finite) Bug(std::string("non-finite ") + input + " accepted");
  return true;
}

bool Finite(const QuasiStaticSolution& s) {
  bool ok = s.twist.allFinite() && std::isfinite(s.gap) &&
            std::isfinite(s.residual) && s.z.allFinite();
  for (double r : s.joint_rates) ok = ok && std::isfinite(r);
  for (const ContactOutput& c : s.contacts)
    ok = ok && c.point.allFinite() && std::isfinite(c.normal_force) &&
         c.traction.allFinite() && c.force_world.allFinite() &&
         c.slip.allFinite() && std::isfinite(c.normal_velocity) &&
         std::isfinite(c.friction_use);
  return ok;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  const Fixture& fx = GetFixture();
  FuzzedDataProvider in(data, size);
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();

  // Signed fractions in [-1, 1), 0 for zero / missing bytes.
  auto s8 = [&in] {
    return static_cast<std::int8_t>(in.ConsumeIntegral<std::uint8_t>()) / 128.0;
  };
  auto s16 = [&in] {
    return static_cast<std::int16_t>(in.ConsumeIntegral<std::uint16_t>()) /
           32768.0;
  };

  QuasiStaticParameters params = QuasiStaticParameters::FromScene(fx.scene);
  params.mode = in.ConsumeBool() ? ActuationMode::kPvc : ActuationMode::kPaper;
  params.mu *= std::exp2(4.0 * s8());            // [0.03, 8)
  params.epsilon *= std::pow(10.0, 4.0 * s8());  // [1e-12, 1e-4)
  for (double& rate : params.joint_rates) rate += s8();
  QuasiStaticOptions options;
  options.diagnostics = in.ConsumeBool();
  options.homotopy = !in.ConsumeBool();
  const int solves = 1 + in.ConsumeIntegral<std::uint8_t>() % 4;

  // Selector: 0-247 nothing; 248-251 a non-finite coordinate in the last
  // configuration; 252-255 a non-finite mu / epsilon / joint rate.
  const std::uint8_t inject = in.ConsumeIntegral<std::uint8_t>();
  bool non_finite_params = false;
  if (inject >= 252) {
    const double bad = (inject & 1) ? kNaN : kInf;
    switch (inject & 3) {
      case 0:
        params.mu = bad;
        break;
      case 1:
        params.epsilon = bad;
        break;
      default:
        params.joint_rates[inject % 6] = bad;
        break;
    }
    non_finite_params = true;
  }

  std::unique_ptr<QuasiStaticSolver> solver;
  auto construct = [&] {
    solver = std::make_unique<QuasiStaticSolver>(
        *fx.model, params, NlpSolverRegistry::Create("newton"), options);
  };
  if (!RejectsOnlyNonFinite("constructor", "parameters", non_finite_params,
                            construct))
    return 0;

  QuasiStaticSolution solution;
  for (int k = 0; k < solves; ++k) {
    Configuration theta = fx.theta0;
    for (int chain = 0; chain < 3; ++chain) {
      const int base = 5 * chain;
      theta(base + 0) += 0.4 * s16();  // u_w
      theta(base + 1) += 0.4 * s16();  // v_w
      theta(base + 2) += 0.1 * s16();  // x_g
      theta(base + 3) += 0.1 * s16();  // y_g
      theta(base + 4) += 0.4 * s16();  // psi
    }
    for (int j = 15; j < kConfigSize; ++j) theta(j) += 0.5 * s16();
    const bool non_finite = inject >= 248 && inject < 252 && k == solves - 1;
    if (non_finite) theta(inject % kConfigSize) = (inject & 1) ? kNaN : kInf;

    QuasiStaticStatus status;
    if (!RejectsOnlyNonFinite("Solve", "configuration", non_finite, [&] {
          status = solver->Solve(theta, &solution);
        }))
      return 0;
    static const bool verbose =
        std::getenv("QUASIROLL_FUZZ_VERBOSE") != nullptr;
    if (verbose)
      std::fprintf(
          stderr,
          "solve %d/%d (%s, mu %.3g, eps %.1e): %s, %d iterations%s%s\n", k + 1,
          solves, ToString(params.mode), params.mu, params.epsilon,
          ToString(status), solution.nlp_iterations,
          solution.message.empty() ? "" : ": ", solution.message.c_str());
    if (status != solution.status)
      Bug("returned status differs from solution.status");
    if (status == QuasiStaticStatus::kOk) {
      if (!Finite(solution)) Bug("kOk solution with non-finite outputs");
      if (!(solution.residual <= options.residual_tolerance))
        Bug("kOk solution with residual " + std::to_string(solution.residual));
    } else if (solution.message.empty()) {
      Bug(std::string("non-OK status without message: ") + ToString(status));
    }
  }
  return 0;
}
