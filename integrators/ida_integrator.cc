#include "quasiroll/integrators/ida_integrator.h"

#include <ida/ida.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "quasiroll/core/weighted_projection.h"
#include "quasiroll/integrators/sundials_support_internal.h"

namespace quasiroll {

namespace {

class IdaIntegrator final : public Integrator {
 public:
  IdaIntegrator();
  ~IdaIntegrator() override;
  std::string name() const override { return "ida"; }
  OptionTable option_table() const override;

 private:
  void ApplyBackendOptions(const OptionValues& values) override;
  void DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                   Eigen::Ref<Eigen::VectorXd> y,
                   const IntegratorOptions& options,
                   IntegratorResult* result) override;

  struct Impl;
  static void ConfigureAndSolve(Impl& s, ConstrainedOde& ode, int flag,
                                double t0, double t1,
                                Eigen::Ref<Eigen::VectorXd> y,
                                const IntegratorOptions& options,
                                IntegratorResult* result);
  static void IntegrateResidualForm(Impl& s, ConstrainedOde& ode, double t0,
                                    double t1, Eigen::Ref<Eigen::VectorXd> y,
                                    const IntegratorOptions& options,
                                    IntegratorResult* result);
  static void Finish(Impl& s, ConstrainedOde& ode, double t1,
                     Eigen::Ref<Eigen::VectorXd> y,
                     const IntegratorOptions& options,
                     IntegratorResult* result);
  std::unique_ptr<Impl> impl_;
};

}  // namespace

using Eigen::Map;
using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {
// IDA's own defaults of the step controls.
constexpr sundials_internal::StepControls kIdaStepControls{5, 4, 10, 10};
using sundials_internal::RestartStep;
}  // namespace

struct IdaIntegrator::Impl {
  Impl() : context("ida") {}
  ~Impl() { Free(); }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  void Free() {
    if (mem != nullptr) IDAFree(&mem);
    dense.Free();
    for (N_Vector* v : {&yy, &yp, &id, &atol, &ewt, &ele})
      sundials_internal::DestroyVector(v);
    n = m = -1;
    roots.registered = 0;
    last.valid = false;
    carried = sundials_internal::CarriedStep{};
    dfdx_reuse.valid = false;
  }

  // Whether this call continues the last one (see ContinuesLastCall in the
  // .cc's DoIntegrate); evaluates F at IDA's current point.
  bool ContinuesLastCall(ConstrainedOde& ode, double t0,
                         const Eigen::Ref<const VectorXd>& y,
                         const IntegratorOptions& options);

  // Creates (or re-initialises, when the sizes are unchanged) the IDA memory
  // for initial values already stored in yy / yp. Returns an IDA flag.
  int Prepare(int n_new, int m_new, double t0);

  static int Residual(double t, N_Vector yy, N_Vector yp, N_Vector rr,
                      void* user_data);
  static int Jacobian(double t, double cj, N_Vector yy, N_Vector yp,
                      N_Vector rr, SUNMatrix jac, void* user_data,
                      N_Vector tmp1, N_Vector tmp2, N_Vector tmp3);
  static int RootFunction(double t, N_Vector yy, N_Vector yp, double* gout,
                          void* user_data);

  // Rhs / Residual calls are tracked (sundials_internal::RhsTracker): IDA
  // recovers from a failure at a trial point (see Residual).
  bool CallRhs(double t, const Eigen::Ref<const VectorXd>& x,
               Eigen::Ref<VectorXd> f) {
    return rhs.Call(*ode, t, x, f, result);
  }
  bool Track(double t, bool ok) { return rhs.Track(t, ok); }
  bool ComputeDfdx(double t, const Eigen::Ref<const VectorXd>& x);

  // SUNDIALS objects.
  sundials_internal::Context context;
  void* mem = nullptr;
  N_Vector yy = nullptr, yp = nullptr, id = nullptr, atol = nullptr;
  N_Vector ewt = nullptr;  // error weights (continuation test)
  sundials_internal::DenseLinearSolver dense;
  int n = -1, m = -1;
  sundials_internal::RootSlots roots;
  // IDA's cumulative counters at the start of this call (they count from the
  // last IDAInit / IDAReInit).
  long steps_seen = 0, fails_seen = 0;
  // The last successful call of the GGL form: where it ended and the state it
  // returned, for the continuation test.
  struct LastCall {
    bool valid = false;
    const ConstrainedOde* ode = nullptr;
    double t = 0.0;
    VectorXd y;
    IntegratorOptions options;
  } last;
  bool continuing = false;  // this call continues the last one
  bool f_at_t0 = false;     // f = F(t0, y) for this call's y

  // Backend options (option_table()).
  struct Settings {
    int dae_index = 2;
    double sigma = 5.0;
    ProjectionSettings projection;
    double multiplier_atol = 1e3;
    sundials_internal::StepControls controls = kIdaStepControls;
    bool suppress_alg = true;
    bool ode_jacobian = true;  // jacobian=ift: ask ode.RhsJacobian first
    double jacobian_reuse = 0.01;
    RestartStep restart_step = RestartStep::kCarry;
  } settings;

  // restart_step=carry: after a restart's first step (IDA_ONE_STEP), the
  // order-1 step that its error estimate predicts; the next restart of the
  // same problem starts with it (capped by IntegratorOptions::step).
  void CarryFirstStep(const ConstrainedOde& problem);
  sundials_internal::CarriedStep carried;
  bool probe_first_step = false;  // this call restarts with restart_step=carry
  // Where the last dF/dx (in dfdx) holds (see Jacobian).
  sundials_internal::JacobianReuse dfdx_reuse;
  bool from_last_end = false;  // this call starts where the last one ended
  N_Vector ele = nullptr;      // IDA's local error estimate (workspace)

  // Per-call data.
  ConstrainedOde* ode = nullptr;
  IntegratorResult* result = nullptr;
  int dae_index = 2;
  double sigma = 0.0;
  bool residual_form = false;  // ode supplies F(t, y, y') itself
  VectorXd r0, r_pert, yp_pert;
  sundials_internal::RhsTracker rhs;
  sundials_internal::ErrorLog errors{IDA_WARNING};

  // Workspaces (resized only when sizes change).
  WeightedProjection correction;
  VectorXd f, f_pert, x_pert, jt_nu, h;
  MatrixXd jac, dfdx;
};

int IdaIntegrator::Impl::Prepare(int n_new, int m_new, double t0) {
  steps_seen = fails_seen = 0;
  // IDAReInit resets IDA's count: a failure since dfdx was saved drops it.
  long conv_fails = 0;
  if (mem != nullptr) IDAGetNumNonlinSolvConvFails(mem, &conv_fails);
  dfdx_reuse.BeforeReInit(conv_fails);
  if (mem != nullptr && n_new == n && m_new == m)
    return IDAReInit(mem, t0, yy, yp);
  // Sizes changed (or first call): the vectors, matrix and linear solver
  // are size-bound, so rebuild everything but the context.
  std::vector<double> y0(NV_DATA_S(yy), NV_DATA_S(yy) + NV_LENGTH_S(yy));
  std::vector<double> yp0(NV_DATA_S(yp), NV_DATA_S(yp) + NV_LENGTH_S(yp));
  Free();
  const sunindextype size = n_new + m_new;
  SUNContext ctx = context.get();
  yy = N_VNew_Serial(size, ctx);
  yp = N_VNew_Serial(size, ctx);
  id = N_VNew_Serial(size, ctx);
  atol = N_VNew_Serial(size, ctx);
  const bool matrix_created = dense.CreateMatrix(size, ctx);
  if (yy == nullptr || yp == nullptr || id == nullptr || atol == nullptr ||
      !matrix_created)
    throw std::runtime_error("ida: cannot allocate vectors / matrix");
  const bool solver_created = dense.CreateSolver(yy, ctx);
  mem = IDACreate(ctx);
  if (!solver_created || mem == nullptr)
    throw std::runtime_error("ida: cannot create linear solver / IDA memory");
  std::copy(y0.begin(), y0.end(), NV_DATA_S(yy));
  std::copy(yp0.begin(), yp0.end(), NV_DATA_S(yp));
  for (sunindextype i = 0; i < size; ++i)
    NV_Ith_S(id, i) = i < n_new ? 1.0 : 0.0;  // 1 differential, 0 algebraic
  n = n_new;
  m = m_new;
  int flag =
      IDASetErrHandlerFn(mem, &sundials_internal::ErrorLog::Handler, &errors);
  if (flag == IDA_SUCCESS) flag = IDAInit(mem, &Impl::Residual, t0, yy, yp);
  if (flag == IDA_SUCCESS) flag = IDASetUserData(mem, this);
  if (flag == IDA_SUCCESS)
    flag = IDASetLinearSolver(mem, dense.solver, dense.matrix);
  if (flag == IDA_SUCCESS) flag = IDASetJacFn(mem, &Impl::Jacobian);
  if (flag == IDA_SUCCESS) flag = IDASetId(mem, id);
  if (flag == IDA_SUCCESS) flag = IDASetSuppressAlg(mem, SUNTRUE);
  return flag;
}

// The first step after a restart is BDF1 from the predictor y0 + h y0', so
// IDA's correction ee = y1 - y0 - h y0' ~ h^2 y'' and the local error
// ~ ee / 2 ~ h^2. IDA's step rule for order 1 (error 1/2 of the test's
// bound) then gives h_new = h / sqrt(||ee||_wrms) (its masked norm: the
// algebraic nu excluded, divided by the full length). A zoh hold interval
// restarts with a new F of similar curvature, so this is the next restart's
// h0 instead of the sample interval (which fails the error test 2-3 times at
// rtol 1e-8). The ratio is clamped (one step says little about the next) and
// scaled by a safety factor (paper scene, zoh: 0.5 / 0.7 / 1 / 1.5 give
// 3906 / 3725 / 4626 / 4925 steps, all with 1 rejection per restart, the
// one ending IDA's order-raising start).
void IdaIntegrator::Impl::CarryFirstStep(const ConstrainedOde& problem) {
  constexpr double kSafety = 0.7;
  static constexpr sundials_internal::ErrorEstimateGetters kGet{
      &IDAGetLastStep, &IDAGetLastOrder, &IDAGetEstLocalErrors,
      &IDAGetErrWeights};
  carried.RecordFirstStep(kGet, mem, yy, &ele, &ewt, n, n + m, &problem, 1.0,
                          kSafety);
}

int IdaIntegrator::Impl::Residual(double t, N_Vector yy, N_Vector yp,
                                  N_Vector rr, void* user_data) {
  Impl& s = *static_cast<Impl*>(user_data);
  const int n = s.n, m = s.m;
  Map<const VectorXd> y(NV_DATA_S(yy), n + m), ydot(NV_DATA_S(yp), n + m);
  Map<VectorXd> r(NV_DATA_S(rr), n + m);
  // A residual that cannot be evaluated returns +1, IDA's recoverable error:
  // IDA retries with a smaller step (or a new Newton iterate). The failing
  // point is often a trial point off the solution path (a corrector iterate
  // or a long step past a stick/slip transition, where the quasi-static NLP
  // is singular); where the path itself leaves the feasible set, the retries
  // end in IDA_REP_RES_ERR just before that point -> kRhsFailure.
  if (s.residual_form) {
    ++s.result->rhs_evaluations;
    return s.Track(t, s.ode->Residual(t, y, ydot, r)) ? 0 : 1;
  }
  if (!s.CallRhs(t, y.head(n), s.f)) return 1;
  r.head(n) = ydot.head(n) - s.f;
  if (m == 0) return 0;
  s.ode->ConstraintJacobian(y.head(n), s.jac);
  ++s.result->jacobian_evaluations;
  s.jt_nu.noalias() = s.jac.transpose() * y.tail(m);
  r.head(n) -= s.correction.weights().cwiseProduct(s.jt_nu);
  s.ode->Constraints(y.head(n), s.h);
  if (s.dae_index == 2) {
    r.tail(m) = s.h;
  } else {
    r.tail(m).noalias() = s.jac * ydot.head(n);
    r.tail(m) += s.sigma * s.h;
  }
  return 0;
}

// dF/dx at (t, x) into dfdx: ode.RhsJacobian with jacobian=ift where it
// gives one, else forward differences of Rhs with increment
// sqrt(eps) * max(1, |x_j|). False if Rhs fails.
bool IdaIntegrator::Impl::ComputeDfdx(double t,
                                      const Eigen::Ref<const VectorXd>& x) {
  if (settings.ode_jacobian && ode->RhsJacobian(t, x, dfdx) && dfdx.allFinite())
    return true;
  if (!CallRhs(t, x, f)) return false;
  const double sqrt_eps = std::sqrt(std::numeric_limits<double>::epsilon());
  x_pert = x;
  for (int j = 0; j < n; ++j) {
    const double xj = x_pert(j);
    const double dx = sqrt_eps * std::max(1.0, std::abs(xj));
    x_pert(j) = xj + dx;
    const double step = x_pert(j) - xj;  // exactly representable increment
    if (!CallRhs(t, x_pert, f_pert)) return false;
    dfdx.col(j) = (f_pert - f) / step;
    x_pert(j) = xj;
  }
  return true;
}

// Iteration matrix dr/dy + cj dr/dy' for the dense linear solver:
//
//   [ cj I - dF/dx - d(D J^T nu)/dx    -D J^T ]
//   [ J                       (index 2)    0  ]
//   [ (cj + sigma) J + d(J x')/dx (idx 1)  0  ]
//
// d(D J^T nu)/dx and d(J x')/dx (second derivatives of H) are neglected:
// both vanish on the constraint-consistent solution with nu = 0 and only
// affect the convergence rate of IDA's (already modified) Newton iteration,
// never the converged solution. dF/dx comes from ode.RhsJacobian (option
// jacobian=ift, the default) where it returns true, else (per call, and
// always with jacobian=fd) from forward differences of Rhs with increment
// sqrt(eps) * max(1, |x_j|).
int IdaIntegrator::Impl::Jacobian(double t, double cj, N_Vector yy, N_Vector yp,
                                  N_Vector /*rr*/, SUNMatrix jac_matrix,
                                  void* user_data, N_Vector /*tmp1*/,
                                  N_Vector /*tmp2*/, N_Vector /*tmp3*/) {
  Impl& s = *static_cast<Impl*>(user_data);
  const int n = s.n, m = s.m;
  Map<const VectorXd> y(NV_DATA_S(yy), n + m);
  // SUNDenseMatrix stores column-major with leading dimension n + m.
  Map<MatrixXd> a(SUNDenseMatrix_Data(jac_matrix), n + m, n + m);
  ++s.result->jacobian_evaluations;
  if (s.residual_form) {
    // dF/dy + cj dF/dy' by forward differences of the user residual.
    Map<const VectorXd> yd(NV_DATA_S(yp), n);
    const double sqrt_eps = std::sqrt(std::numeric_limits<double>::epsilon());
    s.result->rhs_evaluations += 1 + 2 * n;
    // Recoverable (+1) as in Residual.
    if (!s.Track(t, s.ode->Residual(t, y, yd, s.r0))) return 1;
    s.x_pert = y;
    s.yp_pert = yd;
    for (int j = 0; j < n; ++j) {
      const double xj = s.x_pert(j), vj = s.yp_pert(j);
      const double dx = sqrt_eps * std::max(1.0, std::abs(xj));
      s.x_pert(j) = xj + dx;
      if (!s.Track(t, s.ode->Residual(t, s.x_pert, yd, s.r_pert))) return 1;
      a.col(j) = (s.r_pert - s.r0) / (s.x_pert(j) - xj);
      s.x_pert(j) = xj;
      const double dv = sqrt_eps * std::max(1.0, std::abs(vj));
      s.yp_pert(j) = vj + dv;
      if (!s.Track(t, s.ode->Residual(t, y, s.yp_pert, s.r_pert))) return 1;
      a.col(j) += cj * (s.r_pert - s.r0) / (s.yp_pert(j) - vj);
      s.yp_pert(j) = vj;
    }
    return 0;
  }
  // Reuse of dF/dx (modified Newton: only the residual must be exact):
  // while x is within jacobian_reuse (relative, max norm) of where dfdx was
  // evaluated and IDA has had no convergence failure since, dfdx is kept and
  // only cj and the constraint blocks are renewed. IDA calls this at every
  // change of cj beyond its threshold, e.g. at each step of its doubling
  // start after a restart, where x has barely moved.
  long conv_fails = 0;
  IDAGetNumNonlinSolvConvFails(s.mem, &conv_fails);
  if (!s.dfdx_reuse.Keeps(y.head(n), conv_fails, s.settings.jacobian_reuse)) {
    // A failure may leave dfdx half written: not to be kept.
    s.dfdx_reuse.valid = false;
    if (!s.ComputeDfdx(t, y.head(n))) return 1;
    s.dfdx_reuse.Save(y.head(n), conv_fails);
  }
  a.setZero();
  a.topLeftCorner(n, n) = -s.dfdx;
  a.diagonal().head(n).array() += cj;
  if (m > 0) {
    s.ode->ConstraintJacobian(y.head(n), s.jac);
    ++s.result->jacobian_evaluations;
    const VectorXd& d = s.correction.weights();
    a.topRightCorner(n, m).noalias() = -(d.asDiagonal() * s.jac.transpose());
    const double scale = s.dae_index == 2 ? 1.0 : cj + s.sigma;
    a.bottomLeftCorner(m, n) = scale * s.jac;
  }
  return 0;
}

int IdaIntegrator::Impl::RootFunction(double t, N_Vector yy, N_Vector /*yp*/,
                                      double* gout, void* user_data) {
  Impl& s = *static_cast<Impl*>(user_data);
  Map<const VectorXd> x(NV_DATA_S(yy), s.n);
  Map<VectorXd> g(gout, s.roots.registered);
  s.ode->Roots(t, x, g);
  return 0;
}

// A call continues the last one when it starts where that one ended (same
// problem object, t0 = its end time, y = the state it returned, bit for
// bit, same options) and the problem's right-hand side there is the one IDA
// has been integrating: the GGL residual r = x' - F(t0, y) - D J^T nu with
// IDA's current (x', nu) and F evaluated now at y (IDA's x up to the final
// projection; a restart from y reuses it), passes
//   || h r ||_wrms <= 1,
// h the step IDA would try next and the weights those of its error test:
// the change of the problem moves the next step's solution by ~ h r, less
// than the local error the error test accepts. Coupled mode (F = F(x))
// passes with r at the level of the corrector's convergence (paper scene,
// rtol 1e-8: up to 1.09, 3 of 407 calls above 1); a zoh hold interval
// changes the held twist, F jumps (there 26-1955) and the call restarts
// (IDAReInit), as does every call from another state (re-integration at
// switches and stops). Continuing keeps IDA's order and step (model.md
// §8.6, "IDA"); its history is that of its own unprojected iterates, the
// returned y is projected as before.
bool IdaIntegrator::Impl::ContinuesLastCall(ConstrainedOde& ode_now, double t0,
                                            const Eigen::Ref<const VectorXd>& y,
                                            const IntegratorOptions& options) {
  constexpr double kContinueTolerance = 1.0;
  if (!last.valid || mem == nullptr || &ode_now != last.ode || t0 != last.t ||
      ode_now.state_size() != n || ode_now.num_constraints() != m ||
      y.size() != last.y.size() || y != last.y)
    return false;
  const IntegratorOptions& o = last.options;
  if (o.rtol != options.rtol || o.atol != options.atol ||
      o.min_step != options.min_step || o.max_steps != options.max_steps)
    return false;
  last.valid = false;
  from_last_end = true;
  // F at the given y (IDA's point up to the final projection), reused by a
  // restart from the same y.
  if (!CallRhs(t0, y, f)) return false;
  f_at_t0 = true;
  Map<const VectorXd> x(NV_DATA_S(yy), n + m), xp(NV_DATA_S(yp), n + m);
  VectorXd& r = f_pert;  // workspace
  r = xp.head(n) - f;
  if (m > 0) {
    ode_now.ConstraintJacobian(x.head(n), jac);
    ++result->jacobian_evaluations;
    jt_nu.noalias() = jac.transpose() * x.tail(m);
    r -= correction.weights().cwiseProduct(jt_nu);
  }
  if (ewt == nullptr) ewt = N_VClone(yy);
  double h = 0.0;
  if (ewt == nullptr || IDAGetCurrentStep(mem, &h) != IDA_SUCCESS ||
      IDAGetErrWeights(mem, ewt) != IDA_SUCCESS)
    return false;
  Map<const VectorXd> w(NV_DATA_S(ewt), n + m);
  const double norm =
      std::abs(h) * std::sqrt(r.cwiseProduct(w.head(n)).squaredNorm() / n);
  return norm <= kContinueTolerance;
}

IdaIntegrator::IdaIntegrator() : impl_(std::make_unique<Impl>()) {}

OptionTable IdaIntegrator::option_table() const {
  OptionTable table = {
      OptionSpec::Int("dae_index", 2,
                      "2: index-2 GGL residual (H = 0 exact); 1: index-1 "
                      "Baumgarte residual J x' + sigma H = 0")
          .AtLeast(1)
          .AtMost(2),
      OptionSpec::Double("baumgarte_sigma", 5.0,
                         "Baumgarte gain sigma [1/s] of the index-1 form")
          .AtLeast(0),
  };
  const OptionTable projection = ProjectionSettings::Options(
      "index 2: initial and final projection until ||H||_inf <= this");
  table.insert(table.end(), projection.begin(), projection.end());
  table.push_back(
      OptionSpec::Double("multiplier_atol", 1e3,
                         "absolute tolerance of the multipliers nu in IDA's "
                         "Newton test (they are excluded from the error test)")
          .GreaterThan(0));
  const OptionTable controls =
      sundials_internal::StepControlOptions(kIdaStepControls, "IDASet");
  table.insert(table.end(), controls.begin(), controls.end());
  table.push_back(
      OptionSpec::Bool("suppress_alg", true,
                       "exclude the algebraic variables from the error test "
                       "(IDASetSuppressAlg)"));
  table.push_back(OptionSpec::Choice(
      "jacobian", "ift", {"ift", "fd"},
      "dF/dx in the iteration matrix: ift = the ODE's RhsJacobian where it "
      "gives one (robot: central differences of the kinematics + "
      "implicit-function-theorem sensitivities of the solve, model.md §8.9), "
      "else differences; fd = always forward "
      "differences of Rhs"));
  table.push_back(sundials_internal::RestartStepOption(
      "initial step after a re-initialisation: carry = predicted from the "
      "previous restart's first step (its error estimate; model.md §8.5), "
      "capped by the sample interval; given = the sample interval; estimate "
      "= IDA's own estimate"));
  table.push_back(
      OptionSpec::Double("jacobian_reuse", 0.01,
                         "keep dF/dx in the iteration matrix while x is "
                         "within this relative distance (max norm) of where "
                         "it was evaluated, the call starts where the last "
                         "ended and Newton has not failed; 0 = re-evaluate at "
                         "every matrix update")
          .AtLeast(0));
  return table;
}

void IdaIntegrator::ApplyBackendOptions(const OptionValues& values) {
  Impl::Settings& s = impl_->settings;
  s.dae_index = static_cast<int>(values.GetInt("dae_index"));
  s.sigma = values.GetDouble("baumgarte_sigma");
  s.projection = ProjectionSettings::From(values);
  s.multiplier_atol = values.GetDouble("multiplier_atol");
  s.controls = sundials_internal::StepControlsFrom(values);
  s.suppress_alg = values.GetBool("suppress_alg");
  s.ode_jacobian = values.GetString("jacobian") == "ift";
  s.jacobian_reuse = values.GetDouble("jacobian_reuse");
  s.restart_step = sundials_internal::RestartStepFrom(values);
}
IdaIntegrator::~IdaIntegrator() = default;

namespace {

std::string FlagName(int flag) {
  return sundials_internal::FlagName(IDAGetReturnFlagName(flag), "IDA", flag);
}

}  // namespace

// Runs IDASolve to t1 (IDA memory prepared, initial values set) and maps the
// outcome; shared by the GGL form and the user residual form.
void IdaIntegrator::Finish(Impl& s, ConstrainedOde& ode, double t1,
                           Eigen::Ref<Eigen::VectorXd> y,
                           const IntegratorOptions& options,
                           IntegratorResult* result) {
  const int n = s.n, m = s.m;
  bool moved = false;
  Map<VectorXd> yy_now(NV_DATA_S(s.yy), n + m);
  // --- integrate ---
  double t_ret = 0.0;
  IDAGetCurrentTime(s.mem, &t_ret);
  int flag = IDA_SUCCESS;
  if (s.probe_first_step) {
    flag = IDASolve(s.mem, t1, &t_ret, s.yy, s.yp, IDA_ONE_STEP);
    if (flag == IDA_SUCCESS || flag == IDA_TSTOP_RETURN) s.CarryFirstStep(ode);
  }
  if (flag == IDA_SUCCESS && t_ret < t1)
    flag = IDASolve(s.mem, t1, &t_ret, s.yy, s.yp, IDA_NORMAL);
  long steps = 0, error_test_failures = 0;
  IDAGetNumSteps(s.mem, &steps);
  IDAGetNumErrTestFails(s.mem, &error_test_failures);
  result->steps += static_cast<int>(steps - s.steps_seen);
  result->rejected_steps +=
      static_cast<int>(error_test_failures - s.fails_seen);
  s.steps_seen = steps;
  s.fails_seen = error_test_failures;
  y = yy_now.head(n);
  result->t_reached = t_ret;

  IntegratorStatus status = IntegratorStatus::kSuccess;
  if (flag == IDA_ROOT_RETURN) {
    status = IntegratorStatus::kEvent;
    const int first = s.roots.FirstFound(&IDAGetRootInfo, s.mem);
    if (first >= 0) result->root_index = first;
  } else if (flag < 0) {
    switch (flag) {
      case IDA_TOO_MUCH_WORK:  // max_steps reached
      case IDA_TOO_MUCH_ACC:   // tolerances below machine precision
      case IDA_ERR_FAIL:       // repeated error test failures / h < hmin
        status = IntegratorStatus::kStepSizeTooSmall;
        break;
      case IDA_RES_FAIL:
      case IDA_REP_RES_ERR:
      case IDA_FIRST_RES_FAIL:
      case IDA_CONV_FAIL:
      case IDA_LSETUP_FAIL:
      case IDA_LSOLVE_FAIL:
      case IDA_CONSTR_FAIL:
      case IDA_LINESEARCH_FAIL:
      case IDA_NO_RECOVERY:
      case IDA_NLS_INIT_FAIL:
      case IDA_NLS_SETUP_FAIL:
      case IDA_NLS_FAIL:
      case IDA_RTFUNC_FAIL:
        status = IntegratorStatus::kConvergenceFailure;
        break;
      default:  // IDA_ILL_INPUT, IDA_MEM_NULL, IDA_BAD_T, ...
        status = IntegratorStatus::kInvalidInput;
        break;
    }
    // A failing Rhs aborts IDA through the residual / Jacobian callbacks.
    if (s.rhs.failed) status = IntegratorStatus::kRhsFailure;
    result->message = sundials_internal::FailureMessage(
        FlagName(flag), t_ret, s.rhs, "", s.errors.last_error);
  }

  // --- polish: IDA enforces H = 0 only to its Newton tolerance ---
  if ((status == IntegratorStatus::kSuccess ||
       status == IntegratorStatus::kEvent) &&
      s.settings.dae_index == 2 && m > 0) {
    const IntegratorStatus projected =
        s.correction.Project(ode, y, s.settings.projection, result, &moved);
    if (projected != IntegratorStatus::kSuccess) {
      status = projected;
      result->message = "final projection: " + s.correction.message();
    }
  }
  result->status = status;
  s.last.valid = status == IntegratorStatus::kSuccess && !s.residual_form;
  if (s.last.valid) {
    s.last.ode = &ode;
    s.last.t = t_ret;
    s.last.y = y;
    s.last.options = options;
  }
}

// The residual form F(t, y, y') = 0 of the problem itself: y' from
// ConsistentDerivative, differential ids from the problem, atol on all of y.
void IdaIntegrator::IntegrateResidualForm(Impl& s, ConstrainedOde& ode,
                                          double t0, double t1,
                                          Eigen::Ref<Eigen::VectorXd> y,
                                          const IntegratorOptions& options,
                                          IntegratorResult* result) {
  const int n = ode.state_size();
  if (s.r0.size() != n) {
    s.r0.resize(n);
    s.r_pert.resize(n);
    s.yp_pert.resize(n);
  }
  if (s.yy == nullptr || NV_LENGTH_S(s.yy) != n) {
    s.Free();
    s.yy = N_VNew_Serial(n, s.context.get());
    s.yp = N_VNew_Serial(n, s.context.get());
    if (s.yy == nullptr || s.yp == nullptr)
      throw std::runtime_error("ida: cannot allocate vectors");
  }
  Map<VectorXd> yy0(NV_DATA_S(s.yy), n), yp0(NV_DATA_S(s.yp), n);
  yy0 = y;
  if (!ode.ConsistentDerivative(t0, y, yp0)) {
    result->status = IntegratorStatus::kInvalidInput;
    result->t_reached = t0;
    result->message = "residual form: ConsistentDerivative() gave no y' at t0";
    return;
  }
  int flag = s.Prepare(n, 0, t0);
  if (flag == IDA_SUCCESS) {
    VectorXd ids(n);
    ode.DifferentialIds(ids);
    for (int i = 0; i < n; ++i) NV_Ith_S(s.id, i) = ids(i) != 0 ? 1.0 : 0.0;
    flag = IDASetId(s.mem, s.id);
  }
  for (int i = 0; i < n; ++i) NV_Ith_S(s.atol, i) = options.atol;
  ConfigureAndSolve(s, ode, flag, t0, t1, y, options, result);
}

void IdaIntegrator::DoIntegrate(ConstrainedOde& ode, double t0, double t1,
                                Eigen::Ref<Eigen::VectorXd> y,
                                const IntegratorOptions& options,
                                IntegratorResult* result) {
  Impl& s = *impl_;
  s.residual_form = ode.HasResidualForm();
  const int n = ode.state_size();
  // In residual form the user's F(t, y, y') already encodes any constraints.
  const int m = s.residual_form ? 0 : ode.num_constraints();
  s.ode = &ode;
  s.result = result;
  s.dae_index = s.settings.dae_index;
  s.sigma = s.settings.sigma;
  s.rhs.Reset();
  s.errors.last_error.clear();
  s.correction.Begin(ode);
  if (s.f.size() != n) {
    s.f.resize(n);
    s.f_pert.resize(n);
    s.x_pert.resize(n);
    s.jt_nu.resize(n);
    s.dfdx.resize(n, n);
    s.dfdx_reuse.at.resize(n);
    s.dfdx_reuse.valid = false;
  }
  if (s.h.size() != m || s.jac.cols() != n) {
    s.h.resize(m);
    s.jac.resize(m, n);
  }
  auto fail = [&](IntegratorStatus status, const std::string& message) {
    result->status = status;
    result->t_reached = t0;
    result->message = message;
  };

  if (s.residual_form) {
    s.last.valid = s.continuing = false;
    return IntegrateResidualForm(s, ode, t0, t1, y, options, result);
  }
  // --- continuation: no re-initialisation (see ContinuesLastCall) ---
  s.f_at_t0 = false;
  s.from_last_end = false;
  s.continuing = s.ContinuesLastCall(ode, t0, y, options);
  if (s.continuing)
    return ConfigureAndSolve(s, ode, IDA_SUCCESS, t0, t1, y, options, result);

  // A restart from another state (re-integration at switches / stops):
  // dF/dx is re-evaluated (see Jacobian).
  if (!s.from_last_end) s.dfdx_reuse.valid = false;
  // --- consistent initial values (x, nu, x') ---
  bool moved = false;
  if (s.settings.dae_index == 2 && m > 0) {
    const IntegratorStatus status =
        s.correction.Project(ode, y, s.settings.projection, result, &moved);
    if (status != IntegratorStatus::kSuccess)
      return fail(status, "initial state: " + s.correction.message());
  }
  if (!(s.f_at_t0 && !moved) && !s.CallRhs(t0, y, s.f)) {
    std::ostringstream os;
    os << "Rhs returned false at t = " << t0;
    return fail(IntegratorStatus::kRhsFailure, os.str());
  }
  if (s.yy == nullptr || NV_LENGTH_S(s.yy) != n + m) {
    // Temporary holders so that Prepare() can copy the initial values.
    s.Free();
    s.yy = N_VNew_Serial(n + m, s.context.get());
    s.yp = N_VNew_Serial(n + m, s.context.get());
    if (s.yy == nullptr || s.yp == nullptr)
      throw std::runtime_error("ida: cannot allocate vectors");
  }
  Map<VectorXd> yy(NV_DATA_S(s.yy), n + m), yp(NV_DATA_S(s.yp), n + m);
  yy.head(n) = y;
  yp.head(n) = s.f;
  yp.tail(m).setZero();
  if (m > 0) {
    if (!s.correction.Factorize(ode, y, result))
      return fail(IntegratorStatus::kConstraintFailure,
                  "initial multipliers: " + s.correction.message());
    s.correction.r().noalias() = s.correction.jacobian() * s.f;
    if (s.settings.dae_index == 1) {
      ode.Constraints(y, s.h);
      s.correction.r() += s.settings.sigma * s.h;
    }
    s.correction.SolveMultiplier(s.correction.r(), s.correction.lambda());
    yy.tail(m) = -s.correction.lambda();  // nu0
    s.correction.Lift(s.correction.lambda(), s.jt_nu);
    yp.head(n) -= s.jt_nu;  // x'0 = F + D J^T nu0
  }

  // --- IDA setup (IDAReInit when the sizes are unchanged) ---
  int flag = s.Prepare(n, m, t0);
  // Prepare may have rebuilt the vectors: re-map.
  Map<VectorXd> yy_now(NV_DATA_S(s.yy), n + m);
  // Tolerances: rtol / atol on x. nu is excluded from the local error test
  // (IDASetSuppressAlg) but would still enter IDA's Newton convergence test.
  // There it must not: near a step size h the iteration determines nu only
  // to O(residual / h) (index 2: the nu block of the iteration matrix is
  // h J D J^T), so an atol of 1e-10 on nu makes the corrector fail at every
  // small h (observed: IDA_CONV_FAIL at h = hmin on the first step). nu acts
  // on the solution only through D J^T nu in x', whose convergence is tested
  // on x, so nu gets the loose multiplier_atol (default 1e3; results identical
  // for any value in [1, 1e6]; 1e-6 already works, 1e-10 does not).
  for (int i = 0; i < n + m; ++i)
    NV_Ith_S(s.atol, i) = i < n ? options.atol : s.settings.multiplier_atol;
  ConfigureAndSolve(s, ode, flag, t0, t1, y, options, result);
}

// Tolerances (s.atol already filled), step limits, stop time and root
// functions, then the solve; shared by the GGL and residual forms. `flag` is
// the result of the preceding set-up calls.
void IdaIntegrator::ConfigureAndSolve(Impl& s, ConstrainedOde& ode, int flag,
                                      double t0, double t1,
                                      Eigen::Ref<Eigen::VectorXd> y,
                                      const IntegratorOptions& options,
                                      IntegratorResult* result) {
  // Continuing: the tolerances are unchanged, and IDASVtolerances between
  // two solves without a (re)initialisation would leave IDA's error-weight
  // function without its data (set only in IDA's initial setup).
  if (flag == IDA_SUCCESS && !s.continuing)
    flag = IDASVtolerances(s.mem, options.rtol, s.atol);
  static constexpr sundials_internal::StepControlSetters kSetters = {
      &IDASetMaxNumSteps,  &IDASetMinStep,        &IDASetInitStep,
      &IDASetStopTime,     &IDASetMaxOrd,         &IDASetMaxNonlinIters,
      &IDASetMaxConvFails, &IDASetMaxErrTestFails};
  // Initial step of a restart (option restart_step; continuing ignores it).
  IntegratorOptions step_options = options;
  s.probe_first_step = false;
  if (!s.continuing && !s.residual_form) {
    s.probe_first_step = s.settings.restart_step == RestartStep::kCarry;
    step_options.step = s.carried.InitialStep(
        s.settings.restart_step, step_options.step, s.from_last_end, &ode);
  }
  flag = sundials_internal::ApplyStepControls(kSetters, s.mem, step_options, t1,
                                              s.settings.controls, flag);
  if (flag == IDA_SUCCESS && !s.residual_form)
    flag =
        IDASetSuppressAlg(s.mem, s.settings.suppress_alg ? SUNTRUE : SUNFALSE);
  if (flag == IDA_SUCCESS)
    flag = s.roots.Register(&IDARootInit, s.mem, ode.num_roots(),
                            &Impl::RootFunction);
  if (flag != IDA_SUCCESS) {
    result->status = IntegratorStatus::kInvalidInput;
    result->t_reached = t0;
    result->message =
        "ida setup: " + FlagName(flag) + " " + s.errors.last_error;
    return;
  }
  Finish(s, ode, t1, y, options, result);
}

std::unique_ptr<Integrator> MakeIdaIntegrator() {
  return std::make_unique<IdaIntegrator>();
}

}  // namespace quasiroll
