#include "quasiroll/integrators/cvode_projection.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "quasiroll/core/weighted_projection.h"

namespace quasiroll {

using Eigen::Map;
using Eigen::MatrixXd;
using Eigen::VectorXd;

struct CvodeProjectionIntegrator::Impl {
  Impl() {
    if (SUNContext_Create(nullptr, &ctx) != 0 || ctx == nullptr)
      throw std::runtime_error("cvode-projection: SUNContext_Create failed");
  }
  ~Impl() {
    Free();
    if (ctx != nullptr) SUNContext_Free(&ctx);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void Free() {
    if (mem != nullptr) CVodeFree(&mem);
    if (ls != nullptr) SUNLinSolFree(ls);
    if (mat != nullptr) SUNMatDestroy(mat);
    if (yy != nullptr) N_VDestroy(yy);
    mem = nullptr;
    ls = nullptr;
    mat = nullptr;
    yy = nullptr;
    n = -1;
    registered_roots = 0;
    jac_fn_set = false;
  }

  // Newton projection of state onto H = 0 (model.md §8.4); false (message
  // in last_message) on failure.
  bool Project(Eigen::Ref<VectorXd> state) {
    bool moved = false;
    if (projection.Project(*ode, state, projection_tolerance,
                           max_projection_iterations, result,
                           &moved) == IntegratorStatus::kSuccess)
      return true;
    last_message = projection.message();
    return false;
  }

  bool CallRhs(double t, const Eigen::Ref<const VectorXd>& y,
               Eigen::Ref<VectorXd> out) {
    ++result->rhs_evaluations;
    const bool ok = ode->Rhs(t, y, out);
    rhs_failed = !ok;
    if (!ok) rhs_failure_time = t;
    return ok;
  }

  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> ym(NV_DATA_S(y), s.n);
    Map<VectorXd> out(NV_DATA_S(ydot), s.n);
    // Positive = recoverable: CVODE retries with a smaller step (the point
    // may be a trial point off the path).
    return s.CallRhs(t, ym, out) && out.allFinite() ? 0 : 1;
  }

  static int Jacobian(double t, N_Vector y, N_Vector /*fy*/, SUNMatrix jm,
                      void* user_data, N_Vector /*tmp1*/, N_Vector /*tmp2*/,
                      N_Vector /*tmp3*/) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> ym(NV_DATA_S(y), s.n);
    Map<MatrixXd> out(SUNDenseMatrix_Data(jm), s.n, s.n);
    ++s.result->jacobian_evaluations;
    return s.ode->RhsJacobian(t, ym, out) && out.allFinite() ? 0 : 1;
  }

  // CVODE's projection callback: corr with ycur + corr on H = 0, and the
  // error estimate projected onto the tangent space.
  static int Projection(double /*t*/, N_Vector ycur, N_Vector corr,
                        double /*eps_proj*/, N_Vector err, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> y(NV_DATA_S(ycur), s.n);
    Map<VectorXd> c(NV_DATA_S(corr), s.n);
    s.z = y;
    if (!s.Project(s.z)) return 1;  // recoverable: CVODE shrinks the step
    c = s.z - y;
    if (err != nullptr && s.projection.m() > 0) {
      // Tangent part of the error estimate: e <- e - D J^T A^{-1} J e.
      Map<VectorXd> e(NV_DATA_S(err), s.n);
      if (!s.projection.Factorize(*s.ode, s.z, s.result)) {
        s.last_message = s.projection.message();
        return 1;
      }
      WeightedProjection& p = s.projection;
      p.r().noalias() = p.jacobian() * e;
      p.SolveMultiplier(p.r(), p.lambda());
      p.Lift(p.lambda(), s.delta);
      e -= s.delta;
    }
    return 0;
  }

  static int RootFunction(double t, N_Vector y, double* gout, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> ym(NV_DATA_S(y), s.n);
    Map<VectorXd> g(gout, s.registered_roots);
    s.ode->Roots(t, ym, g);
    return 0;
  }

  static void ErrorHandler(int error_code, const char* module,
                           const char* function, char* msg, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    if (error_code == CV_WARNING) return;
    s.last_error = std::string(module) + "::" + function + ": " + msg;
  }

  // Backend options.
  double projection_tolerance = 1e-12;
  int max_projection_iterations = 10;
  int max_order = 5;
  int max_nonlin_iters = 3;
  int max_conv_fails = 10;
  int max_err_test_fails = 7;
  bool proj_err_est = true;
  long proj_frequency = 1;
  int max_proj_fails = 10;
  double proj_fail_eta = 0.25;

  // SUNDIALS objects.
  SUNContext ctx = nullptr;
  void* mem = nullptr;
  N_Vector yy = nullptr;
  SUNMatrix mat = nullptr;
  SUNLinearSolver ls = nullptr;
  int n = -1;
  int registered_roots = 0;
  bool jac_fn_set = false;

  // Per call.
  ConstrainedOde* ode = nullptr;
  IntegratorResult* result = nullptr;
  bool rhs_failed = false;
  double rhs_failure_time = 0.0;
  std::string last_error, last_message;

  // Workspaces.
  WeightedProjection projection;
  VectorXd z, delta;
  std::vector<int> roots_found;
};

CvodeProjectionIntegrator::CvodeProjectionIntegrator()
    : impl_(std::make_unique<Impl>()) {}
CvodeProjectionIntegrator::~CvodeProjectionIntegrator() = default;

OptionTable CvodeProjectionIntegrator::option_table() const {
  return {
      OptionSpec::Double("projection_tolerance", 1e-12,
                         "projection stops when ||H||_inf <= this")
          .GreaterThan(0),
      OptionSpec::Int("max_projection_iterations", 10,
                      "Newton corrections per projection (more: a "
                      "recoverable projection failure)")
          .AtLeast(1),
      OptionSpec::Int("max_order", 5, "largest BDF order (CVodeSetMaxOrd)")
          .AtLeast(1)
          .AtMost(5),
      OptionSpec::Int("max_nonlin_iters", 3,
                      "Newton iterations per step (CVodeSetMaxNonlinIters)")
          .AtLeast(1),
      OptionSpec::Int("max_conv_fails", 10,
                      "Newton failures per step (CVodeSetMaxConvFails)")
          .AtLeast(1),
      OptionSpec::Int("max_err_test_fails", 7,
                      "error-test failures per step (CVodeSetMaxErrTestFails)")
          .AtLeast(1),
      OptionSpec::Bool("proj_err_est", true,
                       "project the local error estimate too "
                       "(CVodeSetProjErrEst)"),
      OptionSpec::Int("proj_frequency", 1,
                      "project every this many steps, 0 = never "
                      "(CVodeSetProjFrequency)")
          .AtLeast(0),
      OptionSpec::Int("max_proj_fails", 10,
                      "projection failures per step (CVodeSetMaxNumProjFails)")
          .AtLeast(1),
      OptionSpec::Double("proj_fail_eta", 0.25,
                         "step factor after a projection failure "
                         "(CVodeSetProjFailEta)")
          .GreaterThan(0)
          .AtMost(1),
  };
}

void CvodeProjectionIntegrator::ApplyBackendOptions(
    const OptionValues& values) {
  Impl& s = *impl_;
  s.projection_tolerance = values.GetDouble("projection_tolerance");
  s.max_projection_iterations =
      static_cast<int>(values.GetInt("max_projection_iterations"));
  s.max_order = static_cast<int>(values.GetInt("max_order"));
  s.max_nonlin_iters = static_cast<int>(values.GetInt("max_nonlin_iters"));
  s.max_conv_fails = static_cast<int>(values.GetInt("max_conv_fails"));
  s.max_err_test_fails = static_cast<int>(values.GetInt("max_err_test_fails"));
  s.proj_err_est = values.GetBool("proj_err_est");
  s.proj_frequency = static_cast<long>(values.GetInt("proj_frequency"));
  s.max_proj_fails = static_cast<int>(values.GetInt("max_proj_fails"));
  s.proj_fail_eta = values.GetDouble("proj_fail_eta");
}

namespace {

std::string FlagName(int flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string out =
      name != nullptr ? name : "CVODE flag " + std::to_string(flag);
  std::free(name);
  return out;
}

}  // namespace

void CvodeProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                            double t1,
                                            Eigen::Ref<Eigen::VectorXd> y,
                                            const IntegratorOptions& options,
                                            IntegratorResult* result) {
  Impl& s = *impl_;
  s.ode = &ode;
  s.result = result;
  s.rhs_failed = false;
  s.last_error.clear();
  s.last_message.clear();
  s.projection.Begin(ode);
  const int n = ode.state_size();
  if (s.z.size() != n) {
    s.z.resize(n);
    s.delta.resize(n);
  }
  auto fail = [&](IntegratorStatus status, const std::string& message) {
    result->status = status;
    result->t_reached = t0;
    result->message = message;
  };

  // Consistent start: project y onto H = 0.
  if (!s.Project(y))
    return fail(IntegratorStatus::kConstraintFailure,
                "initial state: " + s.last_message);

  int flag = CV_SUCCESS;
  if (s.mem != nullptr && s.n == n) {
    Map<VectorXd>(NV_DATA_S(s.yy), n) = y;
    flag = CVodeReInit(s.mem, t0, s.yy);
  } else {
    s.Free();
    s.yy = N_VNew_Serial(n, s.ctx);
    s.mat = SUNDenseMatrix(n, n, s.ctx);
    if (s.yy == nullptr || s.mat == nullptr)
      throw std::runtime_error("cvode-projection: cannot allocate");
    s.ls = SUNLinSol_Dense(s.yy, s.mat, s.ctx);
    s.mem = CVodeCreate(CV_BDF, s.ctx);
    if (s.ls == nullptr || s.mem == nullptr)
      throw std::runtime_error("cvode-projection: cannot create CVODE");
    s.n = n;
    Map<VectorXd>(NV_DATA_S(s.yy), n) = y;
    flag = CVodeSetErrHandlerFn(s.mem, &Impl::ErrorHandler, &s);
    if (flag == CV_SUCCESS) flag = CVodeInit(s.mem, &Impl::Rhs, t0, s.yy);
    if (flag == CV_SUCCESS) flag = CVodeSetUserData(s.mem, &s);
    if (flag == CV_SUCCESS) flag = CVodeSetLinearSolver(s.mem, s.ls, s.mat);
    if (flag == CV_SUCCESS && ode.num_constraints() > 0)
      flag = CVodeSetProjFn(s.mem, &Impl::Projection);
  }
  // dF/dy: the problem's own if it has one (probed once per size), else
  // CVODE's difference quotients.
  if (flag == CV_SUCCESS && !s.jac_fn_set) {
    Eigen::MatrixXd probe(n, n);
    if (ode.RhsJacobian(t0, y, probe)) {
      flag = CVodeSetJacFn(s.mem, &Impl::Jacobian);
      ++result->jacobian_evaluations;
    }
    s.jac_fn_set = true;
  }
  const int nr = ode.num_roots();
  if (flag == CV_SUCCESS)
    flag = CVodeSStolerances(s.mem, options.rtol, options.atol);
  if (flag == CV_SUCCESS) flag = CVodeSetMaxNumSteps(s.mem, options.max_steps);
  if (flag == CV_SUCCESS) flag = CVodeSetMinStep(s.mem, options.min_step);
  if (flag == CV_SUCCESS) flag = CVodeSetInitStep(s.mem, options.step);
  if (flag == CV_SUCCESS) flag = CVodeSetStopTime(s.mem, t1);
  if (flag == CV_SUCCESS) flag = CVodeSetMaxOrd(s.mem, s.max_order);
  if (flag == CV_SUCCESS)
    flag = CVodeSetMaxNonlinIters(s.mem, s.max_nonlin_iters);
  if (flag == CV_SUCCESS) flag = CVodeSetMaxConvFails(s.mem, s.max_conv_fails);
  if (flag == CV_SUCCESS)
    flag = CVodeSetMaxErrTestFails(s.mem, s.max_err_test_fails);
  if (flag == CV_SUCCESS && ode.num_constraints() > 0) {
    flag = CVodeSetProjErrEst(s.mem, s.proj_err_est ? SUNTRUE : SUNFALSE);
    if (flag == CV_SUCCESS)
      flag = CVodeSetProjFrequency(s.mem, s.proj_frequency);
    if (flag == CV_SUCCESS)
      flag = CVodeSetMaxNumProjFails(s.mem, s.max_proj_fails);
    if (flag == CV_SUCCESS) flag = CVodeSetProjFailEta(s.mem, s.proj_fail_eta);
  }
  if (flag == CV_SUCCESS && nr != s.registered_roots) {
    flag = CVodeRootInit(s.mem, nr, nr > 0 ? &Impl::RootFunction : nullptr);
    s.registered_roots = nr;
    s.roots_found.resize(static_cast<std::size_t>(nr));
  }
  if (flag != CV_SUCCESS)
    return fail(IntegratorStatus::kInvalidInput,
                "cvode setup: " + FlagName(flag) + " " + s.last_error);

  // --- integrate ---
  double t_ret = t0;
  flag = CVode(s.mem, t1, s.yy, &t_ret, CV_NORMAL);
  long steps = 0, error_test_failures = 0, jac_evals = 0;
  CVodeGetNumSteps(s.mem, &steps);
  CVodeGetNumErrTestFails(s.mem, &error_test_failures);
  CVodeGetNumJacEvals(s.mem, &jac_evals);
  result->steps += static_cast<int>(steps);
  result->rejected_steps += static_cast<int>(error_test_failures);
  if (!s.jac_fn_set || jac_evals > 0)
    result->jacobian_evaluations += static_cast<int>(jac_evals);
  y = Map<VectorXd>(NV_DATA_S(s.yy), n);
  result->t_reached = t_ret;

  IntegratorStatus status = IntegratorStatus::kSuccess;
  if (flag == CV_ROOT_RETURN) {
    status = IntegratorStatus::kEvent;
    CVodeGetRootInfo(s.mem, s.roots_found.data());
    for (int i = 0; i < nr; ++i) {
      if (s.roots_found[static_cast<std::size_t>(i)] != 0) {
        result->root_index = i;
        break;
      }
    }
  } else if (flag < 0) {
    switch (flag) {
      case CV_TOO_MUCH_WORK:
      case CV_TOO_MUCH_ACC:
      case CV_ERR_FAILURE:
        status = IntegratorStatus::kStepSizeTooSmall;
        break;
      case CV_PROJFUNC_FAIL:
      case CV_REPTD_PROJFUNC_ERR:
        status = IntegratorStatus::kConstraintFailure;
        break;
      case CV_RHSFUNC_FAIL:
      case CV_FIRST_RHSFUNC_ERR:
      case CV_REPTD_RHSFUNC_ERR:
      case CV_UNREC_RHSFUNC_ERR:
        status = IntegratorStatus::kRhsFailure;
        break;
      case CV_ILL_INPUT:
      case CV_MEM_NULL:
      case CV_NO_MALLOC:
      case CV_BAD_T:
      case CV_TOO_CLOSE:
        status = IntegratorStatus::kInvalidInput;
        break;
      default:  // convergence, linear solver, root function failures
        status = IntegratorStatus::kConvergenceFailure;
        break;
    }
    // A failing Rhs aborts CVODE through a recoverable error.
    if (s.rhs_failed) status = IntegratorStatus::kRhsFailure;
    std::ostringstream os;
    os << FlagName(flag) << " at t = " << t_ret;
    if (s.rhs_failed)
      os << " (Rhs returned false at t = " << s.rhs_failure_time << ")";
    if (!s.last_message.empty()) os << " (" << s.last_message << ")";
    if (!s.last_error.empty()) os << ": " << s.last_error;
    result->message = os.str();
  }
  // The returned state is a projected step state unless CVODE interpolated
  // (a root): project it so that H holds to the tolerance in every case.
  if ((status == IntegratorStatus::kSuccess ||
       status == IntegratorStatus::kEvent) &&
      !s.Project(y)) {
    status = IntegratorStatus::kConstraintFailure;
    result->message = "final projection: " + s.last_message;
  }
  result->status = status;
}

}  // namespace quasiroll
