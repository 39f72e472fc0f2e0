#include "quasiroll/integrators/cvode_projection.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <cvode/cvode_proj.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "quasiroll/core/weighted_projection.h"
#include "quasiroll/integrators/sundials_support_internal.h"

namespace quasiroll {

using Eigen::Map;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

class CvodeProjectionIntegrator final : public Integrator {
 public:
  CvodeProjectionIntegrator();
  ~CvodeProjectionIntegrator() override;
  std::string name() const override { return "cvode-projection"; }
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  void DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                   Eigen::Ref<Eigen::VectorXd> y,
                   const IntegratorOptions& options,
                   IntegratorResult* result) override;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace

namespace {
// CVODE's own defaults of the step controls.
constexpr sundials_internal::StepControls kCvodeStepControls{5, 3, 10, 7};
// Largest order CVODE allows for BDF (Adams: 12).
constexpr int kBdfMaxOrder = 5;
constexpr int kAdamsMaxOrder = 12;

using sundials_internal::RestartStep;

// restart_step=carry (sundials_internal::CarriedStep): the next restart
// starts at h (s / ||e||)^(1/2), which would have ||e|| = s; s =
// kCarrySafety^2 keeps the order-1 start well inside the error test (paper
// scene, zoh, adams: safety 0.2 / 0.3 / 0.4 / 0.5 give 4444 / 4014 / 4840 /
// 4910 right-hand sides, 2 rejections each; docs/performance.md).
constexpr double kCarrySafety = 0.3;
}  // namespace

struct CvodeProjectionIntegrator::Impl {
  Impl() : context("cvode-projection") {}
  ~Impl() { Free(); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void Free() {
    if (mem != nullptr) CVodeFree(&mem);
    // Not owned by CVODE: freed after it.
    if (fixed_point_solver != nullptr) {
      SUNNonlinSolFree(fixed_point_solver);
      fixed_point_solver = nullptr;
    }
    dense.Free();
    sundials_internal::DestroyVector(&yy);
    sundials_internal::DestroyVector(&ele);
    sundials_internal::DestroyVector(&ewt);
    n = -1;
    carried = sundials_internal::CarriedStep{};
    roots.registered = 0;
    jac_installed = false;
    jac_ode = nullptr;
    jac_reuse.valid = false;
  }

  // Per-call state, D and the workspaces (sized when n changes).
  void Begin(ConstrainedOde& problem, IntegratorResult* out) {
    ode = &problem;
    result = out;
    rhs.Reset();
    errors.last_error.clear();
    last_message.clear();
    projection.Begin(problem);
    const int n_new = problem.state_size();
    if (z.size() != n_new) {
      z.resize(n_new);
      delta.resize(n_new);
      y_pert.resize(n_new);
      f_pert.resize(n_new);
      jac_probe.resize(n_new, n_new);
      jac_saved.resize(n_new, n_new);
      jac_reuse.at.resize(n_new);
      last_y.resize(n_new);
      jac_reuse.valid = false;
    }
  }
  // CVodeReInit when the size is unchanged, else a new CVODE memory; y0 is
  // the (consistent) initial state. Returns a CVODE flag.
  int CreateOrReInit(double t0, const Eigen::Ref<const VectorXd>& y0);
  // dF/dy, tolerances, step controls, projection settings and root
  // functions; `flag` is CreateOrReInit's. Returns a CVODE flag.
  int Configure(int flag, double t0, double t1,
                const Eigen::Ref<const VectorXd>& y0,
                const IntegratorOptions& options);
  // Runs CVode from t0 to t1 and sets y and *result (status, counters,
  // message), then projects the returned state.
  void Solve(double t0, double t1, Eigen::Ref<VectorXd> y);
  // restart_step=carry, after the first step of a call: the carried step.
  void CarryFirstStep();
  static IntegratorStatus StatusOf(int flag);

  // Newton projection of state onto H = 0 (model.md §8.4); false (message
  // in last_message) on failure.
  bool Project(Eigen::Ref<VectorXd> state, bool* moved_out = nullptr) {
    bool moved = false;
    if (moved_out != nullptr) *moved_out = false;
    const IntegratorStatus status =
        projection.Project(*ode, state, projection_settings, result, &moved);
    if (moved_out != nullptr) *moved_out = moved;
    if (status == IntegratorStatus::kSuccess) return true;
    last_message = projection.message();
    return false;
  }

  static int Rhs(double t, N_Vector y, N_Vector ydot, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> ym(NV_DATA_S(y), s.n);
    Map<VectorXd> out(NV_DATA_S(ydot), s.n);
    // Positive = recoverable: CVODE retries with a smaller step (the point
    // may be a trial point off the path).
    return s.rhs.Call(*s.ode, t, ym, out, s.result) && out.allFinite() ? 0 : 1;
  }

  // Installed with jacobian=ift (Configure): the ODE's dF/dy where
  // RhsJacobian returns one, else forward differences of Rhs about fy =
  // F(t, y) for this evaluation (increment sqrt(eps) max(1, |y_j|), as ida;
  // a failing difference is recoverable like a failing Rhs).
  static int Jacobian(double t, N_Vector y, N_Vector fy, SUNMatrix jm,
                      void* user_data, N_Vector /*tmp1*/, N_Vector /*tmp2*/,
                      N_Vector /*tmp3*/) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> ym(NV_DATA_S(y), s.n), f0(NV_DATA_S(fy), s.n);
    Map<MatrixXd> out(SUNDenseMatrix_Data(jm), s.n, s.n);
    // Reuse (option jacobian_reuse, as ida): CVODE keeps its J between
    // steps but re-evaluates it at every CVodeReInit (each call: each zoh
    // hold interval); the last J is kept while y is within jacobian_reuse
    // (relative, max norm) of where it was evaluated and CVODE has had no
    // convergence failure since (a failure asks for a fresh J).
    long conv_fails = 0;
    CVodeGetNumNonlinSolvConvFails(s.mem, &conv_fails);
    if (s.jac_reuse.Keeps(ym, conv_fails, s.jacobian_reuse)) {
      out = s.jac_saved;
      return 0;
    }
    ++s.result->jacobian_evaluations;
    s.jac_reuse.valid = false;
    if (s.ode->RhsJacobian(t, ym, out) && out.allFinite()) {
      s.jac_reuse.Save(ym, conv_fails);
      s.jac_saved = out;
      return 0;
    }
    const double sqrt_eps = std::sqrt(std::numeric_limits<double>::epsilon());
    s.y_pert = ym;
    for (int j = 0; j < s.n; ++j) {
      const double yj = s.y_pert(j);
      s.y_pert(j) = yj + sqrt_eps * std::max(1.0, std::abs(yj));
      const double step = s.y_pert(j) - yj;  // exactly representable
      if (!s.rhs.Call(*s.ode, t, s.y_pert, s.f_pert, s.result) ||
          !s.f_pert.allFinite())
        return 1;
      out.col(j) = (s.f_pert - f0) / step;
      s.y_pert(j) = yj;
    }
    return 0;
  }

  // CVODE's projection callback: corr with ycur + corr on H = 0, and the
  // error estimate projected onto the tangent space.
  static int Projection(double /*t*/, N_Vector ycur, N_Vector corr,
                        double /*eps_proj*/, N_Vector err, void* user_data) {
    Impl& s = *static_cast<Impl*>(user_data);
    Map<const VectorXd> y(NV_DATA_S(ycur), s.n);
    Map<VectorXd> c(NV_DATA_S(corr), s.n);
    s.z = y;
    bool moved = false;
    if (!s.Project(s.z, &moved)) return 1;  // recoverable: CVODE shrinks h
    c = s.z - y;
    if (err != nullptr && s.projection.m() > 0) {
      // Tangent part of the error estimate: e <- e - D J^T A^{-1} J e, with
      // the projection's last factorisation when it moved (at its last
      // iterate, within the final correction ~ the step's drift of z: the
      // tangent space is the same to that order), else one at z.
      Map<VectorXd> e(NV_DATA_S(err), s.n);
      if (!moved && !s.projection.Factorize(*s.ode, s.z, s.result)) {
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
    Map<VectorXd> g(gout, s.roots.registered);
    s.ode->Roots(t, ym, g);
    return 0;
  }

  // Backend options.
  ProjectionSettings projection_settings;
  sundials_internal::StepControls controls = kCvodeStepControls;
  bool proj_err_est = true;
  long proj_frequency = 1;
  int max_proj_fails = 10;
  double proj_fail_eta = 0.25;
  bool ode_jacobian = true;  // jacobian=ift
  double jacobian_reuse = 0.01;
  int lmm = CV_ADAMS;
  bool fixed_point = true;  // nonlinear_solver=fixedpoint
  RestartStep restart_step = RestartStep::kCarry;
  double eta_max_early = 3.0;

  // SUNDIALS objects.
  sundials_internal::Context context;
  void* mem = nullptr;
  N_Vector yy = nullptr;
  sundials_internal::DenseLinearSolver dense;  // Newton only
  SUNNonlinearSolver fixed_point_solver = nullptr;
  // The method and nonlinear solver the CVODE memory was created with (a
  // change of either creates a new one).
  int created_lmm = CV_ADAMS;
  bool created_fixed_point = true;
  int n = -1;
  sundials_internal::RootSlots roots;
  // Impl::Jacobian is installed (else CVODE's own difference quotients),
  // for the ODE jac_ode.
  bool jac_installed = false;
  const ConstrainedOde* jac_ode = nullptr;
  // The last RhsJacobian (jacobian_reuse) and where it holds. Kept only
  // for a call of the same ODE that starts where the last successful one
  // ended.
  sundials_internal::JacobianReuse jac_reuse;
  MatrixXd jac_saved;
  double last_t = 0.0;
  const ConstrainedOde* last_ode = nullptr;
  VectorXd last_y;  // the state the last successful call returned
  // restart_step=carry: the step carried to the next call of carried.ode
  // that starts where the last one ended; this call probes its first step.
  sundials_internal::CarriedStep carried;
  bool from_last_end = false;
  bool probe_first_step = false;
  N_Vector ele = nullptr, ewt = nullptr;  // CVODE's error estimate, weights

  // Per call.
  ConstrainedOde* ode = nullptr;
  IntegratorResult* result = nullptr;
  sundials_internal::RhsTracker rhs;
  sundials_internal::ErrorLog errors{CV_WARNING};
  std::string last_message;  // why the last projection failed

  // Workspaces.
  WeightedProjection projection;
  VectorXd z, delta, y_pert, f_pert;
  MatrixXd jac_probe;
};

CvodeProjectionIntegrator::CvodeProjectionIntegrator()
    : impl_(std::make_unique<Impl>()) {}
CvodeProjectionIntegrator::~CvodeProjectionIntegrator() = default;

OptionTable CvodeProjectionIntegrator::option_table() const {
  OptionTable table = ProjectionSettings::Options(
      "projection stops when ||H||_inf <= this",
      "Newton corrections per projection (more: a recoverable projection "
      "failure)");
  OptionTable controls =
      sundials_internal::StepControlOptions(kCvodeStepControls, "CVodeSet");
  // Adams goes to order 12 in CVODE; BDF stops at 5 whatever is given.
  for (OptionSpec& spec : controls) {
    if (spec.name == "max_order") {
      spec =
          OptionSpec::Int("max_order", kCvodeStepControls.max_order,
                          "largest order (CVodeSetMaxOrd; lmm=bdf: at most " +
                              std::to_string(kBdfMaxOrder) + ")")
              .AtLeast(1)
              .AtMost(kAdamsMaxOrder);
    }
  }
  const OptionTable projection_controls = {
      OptionSpec::Bool("proj_err_est", true,
                       "lmm=bdf: project the local error estimate too "
                       "(CVodeSetProjErrEst)"),
      OptionSpec::Int("proj_frequency", 1,
                      "lmm=bdf: project every this many steps, 0 = never "
                      "(CVodeSetProjFrequency)")
          .AtLeast(0),
      OptionSpec::Int("max_proj_fails", 10,
                      "lmm=bdf: projection failures per step "
                      "(CVodeSetMaxNumProjFails)")
          .AtLeast(1),
      OptionSpec::Double("proj_fail_eta", 0.25,
                         "lmm=bdf: step factor after a projection failure "
                         "(CVodeSetProjFailEta)")
          .GreaterThan(0)
          .AtMost(1),
  };
  table.insert(table.end(), controls.begin(), controls.end());
  table.insert(table.end(), projection_controls.begin(),
               projection_controls.end());
  table.push_back(OptionSpec::Choice(
      "jacobian", "ift", {"ift", "fd"},
      "nonlinear_solver=newton: dF/dy in the Newton matrix: ift = the "
      "ODE's RhsJacobian where it "
      "gives one (robot: central differences of the kinematics + "
      "implicit-function-theorem sensitivities of the solve, model.md §8.9), "
      "else differences; fd = always CVODE's difference quotients"));
  table.push_back(
      OptionSpec::Double("jacobian_reuse", 0.01,
                         "newton, jacobian=ift: keep dF/dy across calls (CVODE "
                         "re-initialises at each) while y is within this "
                         "relative distance (max norm) of where it was "
                         "evaluated, the call starts where the last ended and "
                         "Newton has not failed; 0 = re-evaluate")
          .AtLeast(0));
  table.push_back(OptionSpec::Choice(
      "lmm", "adams", {"adams", "bdf"},
      "multistep method (CVodeCreate): adams = Adams-Moulton, the state "
      "projected onto H = 0 at the end of each call (CVODE projects only "
      "with BDF); bdf = BDF with CVODE's projection after every step and of "
      "the error estimate (the behaviour before)"));
  table.push_back(OptionSpec::Choice(
      "nonlinear_solver", "fixedpoint", {"fixedpoint", "newton"},
      "corrector iteration: fixedpoint = functional iteration "
      "(SUNNonlinSol_FixedPoint, no dF/dy, no linear solves: for non-stiff "
      "F); newton = Newton with the dense dF/dy of option jacobian (the "
      "behaviour before)"));
  table.push_back(sundials_internal::RestartStepOption(
      "initial step after a re-initialisation: carry = the order-1 step "
      "the first step's error estimate predicts, from the last call that "
      "ended where this one starts (capped at IntegratorOptions::step); "
      "given = IntegratorOptions::step (the behaviour before); estimate = "
      "CVODE's own estimate"));
  table.push_back(
      OptionSpec::Double("eta_max_early", 3.0,
                         "largest step growth in the first 10 steps after a "
                         "re-initialisation (CVodeSetEtaMaxEarlyStep; CVODE's "
                         "own: 10)")
          .GreaterThan(1));
  return table;
}

void CvodeProjectionIntegrator::ApplyBackendOptions(
    const OptionValues& values) {
  Impl& s = *impl_;
  s.projection_settings = ProjectionSettings::From(values);
  s.controls = sundials_internal::StepControlsFrom(values);
  s.proj_err_est = values.GetBool("proj_err_est");
  s.proj_frequency = static_cast<long>(values.GetInt("proj_frequency"));
  s.max_proj_fails = static_cast<int>(values.GetInt("max_proj_fails"));
  s.proj_fail_eta = values.GetDouble("proj_fail_eta");
  s.ode_jacobian = values.GetString("jacobian") == "ift";
  s.jacobian_reuse = values.GetDouble("jacobian_reuse");
  s.lmm = values.GetString("lmm") == "bdf" ? CV_BDF : CV_ADAMS;
  s.fixed_point = values.GetString("nonlinear_solver") == "fixedpoint";
  s.restart_step = sundials_internal::RestartStepFrom(values);
  s.eta_max_early = values.GetDouble("eta_max_early");
}

namespace {

std::string FlagName(int flag) {
  return sundials_internal::FlagName(CVodeGetReturnFlagName(flag), "CVODE",
                                     flag);
}

}  // namespace

int CvodeProjectionIntegrator::Impl::CreateOrReInit(
    double t0, const Eigen::Ref<const VectorXd>& y0) {
  const int n_new = static_cast<int>(y0.size());
  // CVodeReInit resets CVODE's count: a failure since J was saved drops it.
  long conv_fails = 0;
  if (mem != nullptr) CVodeGetNumNonlinSolvConvFails(mem, &conv_fails);
  jac_reuse.BeforeReInit(conv_fails);
  if (mem != nullptr && n == n_new && lmm == created_lmm &&
      fixed_point == created_fixed_point) {
    Map<VectorXd>(NV_DATA_S(yy), n_new) = y0;
    return CVodeReInit(mem, t0, yy);
  }
  Free();
  yy = N_VNew_Serial(n_new, context.get());
  if (yy == nullptr)
    throw std::runtime_error("cvode-projection: cannot allocate");
  // The fixed-point iteration (Anderson depth 0: it converges in 1-2
  // iterations on this non-stiff F) needs no matrix; Newton the dense one.
  const bool solver_created =
      fixed_point ? (fixed_point_solver = SUNNonlinSol_FixedPoint(
                         yy, 0, context.get())) != nullptr
                  : dense.CreateMatrix(n_new, context.get()) &&
                        dense.CreateSolver(yy, context.get());
  mem = CVodeCreate(lmm, context.get());
  if (!solver_created || mem == nullptr)
    throw std::runtime_error("cvode-projection: cannot create CVODE");
  created_lmm = lmm;
  created_fixed_point = fixed_point;
  n = n_new;
  Map<VectorXd>(NV_DATA_S(yy), n_new) = y0;
  int flag =
      CVodeSetErrHandlerFn(mem, &sundials_internal::ErrorLog::Handler, &errors);
  if (flag == CV_SUCCESS) flag = CVodeInit(mem, &Impl::Rhs, t0, yy);
  if (flag == CV_SUCCESS) flag = CVodeSetUserData(mem, this);
  if (flag == CV_SUCCESS) {
    flag = fixed_point ? CVodeSetNonlinearSolver(mem, fixed_point_solver)
                       : CVodeSetLinearSolver(mem, dense.solver, dense.matrix);
  }
  // CVODE projects only with BDF (CVodeSetProjFn refuses Adams); with
  // Adams the returned state is projected (Solve).
  if (flag == CV_SUCCESS && lmm == CV_BDF && ode->num_constraints() > 0)
    flag = CVodeSetProjFn(mem, &Impl::Projection);
  return flag;
}

int CvodeProjectionIntegrator::Impl::Configure(
    int flag, double t0, double t1, const Eigen::Ref<const VectorXd>& y0,
    const IntegratorOptions& options) {
  // dF/dy (option jacobian): with ift, Impl::Jacobian once the ODE has
  // given one (probed at each call's start until it does: an ODE without
  // RhsJacobian returns false at once, and the robot's may fail at a
  // one-sided point); CVODE's difference quotients otherwise. The
  // fixed-point iteration uses no dF/dy.
  if (flag == CV_SUCCESS && !fixed_point) {
    bool install = ode_jacobian && jac_installed && jac_ode == ode;
    if (ode_jacobian && !install) {
      install = ode->RhsJacobian(t0, y0, jac_probe);
      if (install) ++result->jacobian_evaluations;
    }
    if (install != jac_installed)
      flag = CVodeSetJacFn(mem, install ? &Impl::Jacobian : nullptr);
    jac_installed = install;
    jac_ode = ode;
  }
  if (flag == CV_SUCCESS)
    flag = CVodeSStolerances(mem, options.rtol, options.atol);
  static constexpr sundials_internal::StepControlSetters kSetters = {
      &CVodeSetMaxNumSteps,  &CVodeSetMinStep,        &CVodeSetInitStep,
      &CVodeSetStopTime,     &CVodeSetMaxOrd,         &CVodeSetMaxNonlinIters,
      &CVodeSetMaxConvFails, &CVodeSetMaxErrTestFails};
  // Initial step (option restart_step): every call re-initialises CVODE.
  IntegratorOptions step_options = options;
  // carry: only for a call that starts where the last one ended (the next
  // hold interval), so a call from elsewhere (a re-integration, a new run)
  // computes as it would on a fresh integrator.
  probe_first_step = restart_step == RestartStep::kCarry;
  step_options.step =
      carried.InitialStep(restart_step, step_options.step, from_last_end, ode);
  sundials_internal::StepControls method_controls = controls;
  if (lmm == CV_BDF)
    method_controls.max_order = std::min(controls.max_order, kBdfMaxOrder);
  flag = sundials_internal::ApplyStepControls(kSetters, mem, step_options, t1,
                                              method_controls, flag);
  if (flag == CV_SUCCESS) flag = CVodeSetEtaMaxEarlyStep(mem, eta_max_early);
  if (flag == CV_SUCCESS && lmm == CV_BDF && ode->num_constraints() > 0) {
    flag = CVodeSetProjErrEst(mem, proj_err_est ? SUNTRUE : SUNFALSE);
    if (flag == CV_SUCCESS) flag = CVodeSetProjFrequency(mem, proj_frequency);
    if (flag == CV_SUCCESS) flag = CVodeSetMaxNumProjFails(mem, max_proj_fails);
    if (flag == CV_SUCCESS) flag = CVodeSetProjFailEta(mem, proj_fail_eta);
  }
  if (flag == CV_SUCCESS)
    flag = roots.Register(&CVodeRootInit, mem, ode->num_roots(),
                          &Impl::RootFunction);
  return flag;
}

void CvodeProjectionIntegrator::Impl::CarryFirstStep() {
  // CVODE's error test: ||ele||_wrms <= 1, over every component.
  static constexpr sundials_internal::ErrorEstimateGetters kGet{
      &CVodeGetLastStep, &CVodeGetLastOrder, &CVodeGetEstLocalErrors,
      &CVodeGetErrWeights};
  carried.RecordFirstStep(kGet, mem, yy, &ele, &ewt, n, n, ode, kCarrySafety,
                          1.0);
}

IntegratorStatus CvodeProjectionIntegrator::Impl::StatusOf(int flag) {
  switch (flag) {
    case CV_TOO_MUCH_WORK:
    case CV_TOO_MUCH_ACC:
    case CV_ERR_FAILURE:
      return IntegratorStatus::kStepSizeTooSmall;
    case CV_PROJFUNC_FAIL:
    case CV_REPTD_PROJFUNC_ERR:
      return IntegratorStatus::kConstraintFailure;
    case CV_RHSFUNC_FAIL:
    case CV_FIRST_RHSFUNC_ERR:
    case CV_REPTD_RHSFUNC_ERR:
    case CV_UNREC_RHSFUNC_ERR:
      return IntegratorStatus::kRhsFailure;
    case CV_ILL_INPUT:
    case CV_MEM_NULL:
    case CV_NO_MALLOC:
    case CV_BAD_T:
    case CV_TOO_CLOSE:
      return IntegratorStatus::kInvalidInput;
    default:  // convergence, linear solver, root function failures
      return IntegratorStatus::kConvergenceFailure;
  }
}

void CvodeProjectionIntegrator::Impl::Solve(double t0, double t1,
                                            Eigen::Ref<VectorXd> y) {
  double t_ret = t0;
  int flag = CV_SUCCESS;
  if (probe_first_step) {
    flag = CVode(mem, t1, yy, &t_ret, CV_ONE_STEP);
    if (flag == CV_SUCCESS || flag == CV_TSTOP_RETURN) CarryFirstStep();
  }
  if (flag == CV_SUCCESS && t_ret < t1)
    flag = CVode(mem, t1, yy, &t_ret, CV_NORMAL);
  long steps = 0, error_test_failures = 0, jac_evals = 0;
  CVodeGetNumSteps(mem, &steps);
  CVodeGetNumErrTestFails(mem, &error_test_failures);
  if (!fixed_point) CVodeGetNumJacEvals(mem, &jac_evals);
  result->steps += static_cast<int>(steps);
  result->rejected_steps += static_cast<int>(error_test_failures);
  // Impl::Jacobian counts itself; CVODE's own difference quotients here.
  if (!jac_installed)
    result->jacobian_evaluations += static_cast<int>(jac_evals);
  y = Map<VectorXd>(NV_DATA_S(yy), n);
  result->t_reached = t_ret;

  IntegratorStatus status = IntegratorStatus::kSuccess;
  if (flag == CV_ROOT_RETURN) {
    status = IntegratorStatus::kEvent;
    const int first = roots.FirstFound(&CVodeGetRootInfo, mem);
    if (first >= 0) result->root_index = first;
  } else if (flag < 0) {
    status = StatusOf(flag);
    // A failing Rhs aborts CVODE through a recoverable error.
    if (rhs.failed) status = IntegratorStatus::kRhsFailure;
    result->message = sundials_internal::FailureMessage(
        FlagName(flag), t_ret, rhs, last_message, errors.last_error);
  }
  // The returned state is a projected step state unless CVODE interpolated
  // (a root): project it so that H holds to the tolerance in every case.
  if ((status == IntegratorStatus::kSuccess ||
       status == IntegratorStatus::kEvent) &&
      !Project(y)) {
    status = IntegratorStatus::kConstraintFailure;
    result->message = "final projection: " + last_message;
  }
  result->status = status;
  if (status == IntegratorStatus::kSuccess) {
    last_t = result->t_reached;
    last_y = y;
    last_ode = ode;
  } else {
    jac_reuse.valid = false;
  }
}

void CvodeProjectionIntegrator::DoIntegrate(ConstrainedOde& ode, double t0,
                                            double t1,
                                            Eigen::Ref<Eigen::VectorXd> y,
                                            const IntegratorOptions& options,
                                            IntegratorResult* result) {
  Impl& s = *impl_;
  s.Begin(ode, result);
  // A call from elsewhere (a re-integration, a new run) computes as on a
  // fresh integrator.
  s.from_last_end = &ode == s.last_ode && t0 == s.last_t && y == s.last_y;
  if (!s.from_last_end) s.jac_reuse.valid = false;
  auto fail = [&](IntegratorStatus status, const std::string& message) {
    result->status = status;
    result->t_reached = t0;
    result->message = message;
  };
  // Consistent start: project y onto H = 0.
  if (!s.Project(y))
    return fail(IntegratorStatus::kConstraintFailure,
                "initial state: " + s.last_message);
  const int flag = s.Configure(s.CreateOrReInit(t0, y), t0, t1, y, options);
  if (flag != CV_SUCCESS)
    return fail(IntegratorStatus::kInvalidInput,
                "cvode setup: " + FlagName(flag) + " " + s.errors.last_error);
  s.Solve(t0, t1, y);
}

std::unique_ptr<Integrator> MakeCvodeProjectionIntegrator() {
  return std::make_unique<CvodeProjectionIntegrator>();
}

}  // namespace quasiroll
