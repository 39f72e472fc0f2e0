// SUNDIALS plumbing shared by the `ida` and `cvode-projection` backends:
// context, dense matrix + linear solver, error handler, flag names, Rhs
// failure tracking, root registration and the step controls both solvers
// take through identically shaped Set functions.
//
// Internal header: it includes SUNDIALS headers, so only the SUNDIALS
// backends' .cc files and sundials_support.cc include it, and
// cmake/QuasirollInstall.cmake does not install *_internal.h (installed
// headers carry no third-party headers).
#pragma once

#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "quasiroll/core/dae.h"

namespace quasiroll::sundials_internal {

// Owns a SUNContext. Throws std::runtime_error "<backend>: SUNContext_Create
// failed".
class Context {
 public:
  explicit Context(const char* backend);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  SUNContext get() const { return ctx_; }

 private:
  SUNContext ctx_ = nullptr;
};

// N_VDestroy(*v) if set, then *v = nullptr.
void DestroyVector(N_Vector* v);

// A dense size x size SUNMatrix and the dense SUNLinearSolver on it.
struct DenseLinearSolver {
  SUNMatrix matrix = nullptr;
  SUNLinearSolver solver = nullptr;
  // Creates the matrix (false if that fails; then no solver is attempted).
  bool CreateMatrix(sunindextype size, SUNContext ctx);
  // Creates the solver for `y`-shaped vectors (false if that fails).
  bool CreateSolver(N_Vector y, SUNContext ctx);
  void Free();
};

// Error handler (CVodeSetErrHandlerFn / IDASetErrHandlerFn, with this object
// as eh_data): keeps the last error as "module::function: msg"; warnings
// (e.g. "t + h = t") are not failures and are dropped.
struct ErrorLog {
  explicit ErrorLog(int warning) : warning_code(warning) {}
  static void Handler(int error_code, const char* module, const char* function,
                      char* msg, void* eh_data);
  int warning_code;
  std::string last_error;
};

// The latest Rhs / residual call only: the solvers recover from a failure at
// a trial point, so an earlier failure must not label a later, unrelated
// solver failure as kRhsFailure.
struct RhsTracker {
  bool failed = false;
  double failure_time = 0.0;
  void Reset() { failed = false; }
  bool Track(double t, bool ok) {
    failed = !ok;
    if (!ok) failure_time = t;
    return ok;
  }
  // ode.Rhs(t, y, f), counted in result->rhs_evaluations, tracked.
  bool Call(ConstrainedOde& ode, double t,
            const Eigen::Ref<const Eigen::VectorXd>& y,
            Eigen::Ref<Eigen::VectorXd> f, IntegratorResult* result) {
    ++result->rhs_evaluations;
    return Track(t, ode.Rhs(t, y, f));
  }
};

// Root functions registered with the solver and the root info buffer.
struct RootSlots {
  int registered = 0;
  std::vector<int> found;
  // XRootInit(mem, nr, fn or nullptr) when nr changed since the last call;
  // returns its flag (0 when nothing was to be done).
  template <typename RootFn>
  int Register(int (*root_init)(void*, int, RootFn), void* mem, int nr,
               RootFn fn) {
    if (nr == registered) return 0;
    const int flag = root_init(mem, nr, nr > 0 ? fn : nullptr);
    registered = nr;
    found.resize(static_cast<std::size_t>(nr));
    return flag;
  }
  // XGetRootInfo into `found`; the first component that fired (-1 if none).
  int FirstFound(int (*get_root_info)(void*, int*), void* mem);
};

// The step controls of IntegratorOptions and the backend options both solvers
// share, applied through the solver's Set functions (same signatures in
// CVODE and IDA) in one fixed order. `flag` is the status of the preceding
// set-up; nothing is called once a flag is non-zero.
struct StepControlSetters {
  int (*max_num_steps)(void*, long);
  int (*min_step)(void*, sunrealtype);
  int (*init_step)(void*, sunrealtype);
  int (*stop_time)(void*, sunrealtype);
  int (*max_ord)(void*, int);
  int (*max_nonlin_iters)(void*, int);
  int (*max_conv_fails)(void*, int);
  int (*max_err_test_fails)(void*, int);
};
struct StepControls {
  int max_order = 5;
  int max_nonlin_iters = 3;
  int max_conv_fails = 10;
  int max_err_test_fails = 10;
};
// The backend options max_order, max_nonlin_iters, max_conv_fails and
// max_err_test_fails with `defaults` (the solver's own) as defaults;
// `set_prefix` ("CVodeSet", "IDASet") names the Set functions in the docs.
OptionTable StepControlOptions(const StepControls& defaults,
                               const std::string& set_prefix);
// Those four from resolved backend options.
StepControls StepControlsFrom(const OptionValues& values);
int ApplyStepControls(const StepControlSetters& set, void* mem,
                      const IntegratorOptions& options, double t1,
                      const StepControls& controls, int flag);

// The rule of the option jacobian_reuse (docs/model.md §8.5, §8.7): a saved
// dF/dx is kept while x is within `reuse` (relative, max norm) of where it
// was evaluated and the solver has had no nonlinear convergence failure
// since (its count then is kept; a ReInit resets the solver's count).
struct JacobianReuse {
  bool valid = false;
  Eigen::VectorXd at;  // sized by the backend with its state
  long conv_fails = 0;
  bool Keeps(const Eigen::Ref<const Eigen::VectorXd>& x, long fails_now,
             double reuse) const {
    return reuse > 0.0 && valid && fails_now == conv_fails &&
           (x - at).lpNorm<Eigen::Infinity>() <=
               reuse * std::max(1.0, at.lpNorm<Eigen::Infinity>());
  }
  void Save(const Eigen::Ref<const Eigen::VectorXd>& x, long fails_now) {
    valid = true;
    at = x;
    conv_fails = fails_now;
  }
  // Before the solver's ReInit, given its failure count then.
  void BeforeReInit(long fails_now) {
    if (fails_now != conv_fails) valid = false;
    conv_fails = 0;
  }
};

// Option restart_step (docs/model.md §8.5, §8.7): the initial step of a call
// that re-initialises the solver. given = IntegratorOptions::step; estimate =
// the solver's own estimate; carry = the step the previous restart's first
// step predicts (CarriedStep).
enum class RestartStep { kGiven, kEstimate, kCarry };
// The option, default carry, with the backend's `description`.
OptionSpec RestartStepOption(const std::string& description);
RestartStep RestartStepFrom(const OptionValues& values);

// The solver's functions (same signatures in CVODE and IDA) that tell a
// step's size, order, local error estimate and error weights.
struct ErrorEstimateGetters {
  int (*last_step)(void*, sunrealtype*);
  int (*last_order)(void*, int*);
  int (*local_errors)(void*, N_Vector);
  int (*error_weights)(void*, N_Vector);
};

// restart_step=carry. A restart's first step h is taken at order 1, and its
// weighted RMS local error estimate ||e|| ~ C h^2 predicts the step that
// would meet ||e|| = 1: the next call that starts where this one ended (the
// next hold interval) begins at
//   h_next = outer h clamp(inner / sqrt(||e|| + 1e-4), 0.2, 5)
// (one step says little about the next interval, hence the clamp; the two
// safety factors are each backend's measured choice).
struct CarriedStep {
  double step = 0.0;
  const ConstrainedOde* ode = nullptr;  // the call the step came from

  void Record(const ConstrainedOde* from, double h, double error_norm,
              double inner, double outer) {
    step =
        outer * h * std::clamp(inner / std::sqrt(error_norm + 1e-4), 0.2, 5.0);
    ode = from;
  }
  // After a call's first step on `mem`: Record with ||e|| = the RMS of e_i
  // w_i over the first `n_tested` of `n_total` components (IDA's masked
  // norm excludes its algebraic ones), read through `get`; *ele and *ewt
  // are workspaces cloned from `like` on first use. Nothing is carried
  // unless the step was order 1 and every read succeeded.
  void RecordFirstStep(const ErrorEstimateGetters& get, void* mem,
                       N_Vector like, N_Vector* ele, N_Vector* ewt,
                       int n_tested, int n_total, const ConstrainedOde* from,
                       double inner, double outer);
  // The initial step of a call on `call_ode` by `mode`: `given`, 0 (the
  // solver's estimate), or with carry the carried step when the call starts
  // where the last ended on the same ODE and the step is below `given`
  // (else `given`, as on a fresh solver).
  double InitialStep(RestartStep mode, double given, bool from_last_end,
                     const ConstrainedOde* call_ode) const {
    switch (mode) {
      case RestartStep::kEstimate:
        return 0.0;
      case RestartStep::kCarry:
        if (from_last_end && ode == call_ode && step > 0.0 &&
            (given <= 0.0 || step < given))
          return step;
        return given;
      case RestartStep::kGiven:
        break;
    }
    return given;
  }
};

// The name of a return flag from XGetReturnFlagName (which allocates; freed
// here), or "<solver> flag <n>".
std::string FlagName(char* name, const char* solver, int flag);

// "<flag name> at t = <t>[ (Rhs returned false at t = ..)][ (<detail>)]
// [: <last error>]", the message of a failed solve.
std::string FailureMessage(const std::string& flag_name, double t,
                           const RhsTracker& rhs, const std::string& detail,
                           const std::string& last_error);

}  // namespace quasiroll::sundials_internal
