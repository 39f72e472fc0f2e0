#include <cstdlib>
#include <sstream>
#include <stdexcept>

#include "quasiroll/integrators/sundials_support_internal.h"

namespace quasiroll::sundials_internal {

Context::Context(const char* backend) {
  if (SUNContext_Create(nullptr, &ctx_) != 0 || ctx_ == nullptr)
    throw std::runtime_error(std::string(backend) +
                             ": SUNContext_Create failed");
}

Context::~Context() {
  if (ctx_ != nullptr) SUNContext_Free(&ctx_);
}

void DestroyVector(N_Vector* v) {
  if (*v != nullptr) N_VDestroy(*v);
  *v = nullptr;
}

bool DenseLinearSolver::CreateMatrix(sunindextype size, SUNContext ctx) {
  matrix = SUNDenseMatrix(size, size, ctx);
  return matrix != nullptr;
}

bool DenseLinearSolver::CreateSolver(N_Vector y, SUNContext ctx) {
  solver = SUNLinSol_Dense(y, matrix, ctx);
  return solver != nullptr;
}

void DenseLinearSolver::Free() {
  if (solver != nullptr) SUNLinSolFree(solver);
  if (matrix != nullptr) SUNMatDestroy(matrix);
  solver = nullptr;
  matrix = nullptr;
}

void ErrorLog::Handler(int error_code, const char* module, const char* function,
                       char* msg, void* eh_data) {
  ErrorLog& log = *static_cast<ErrorLog*>(eh_data);
  if (error_code == log.warning_code) return;
  log.last_error = std::string(module) + "::" + function + ": " + msg;
}

int RootSlots::FirstFound(int (*get_root_info)(void*, int*), void* mem) {
  get_root_info(mem, found.data());
  for (int i = 0; i < registered; ++i)
    if (found[static_cast<std::size_t>(i)] != 0) return i;
  return -1;
}

int ApplyStepControls(const StepControlSetters& set, void* mem,
                      const IntegratorOptions& options, double t1,
                      const StepControls& controls, int flag) {
  if (flag == 0) flag = set.max_num_steps(mem, options.max_steps);
  if (flag == 0) flag = set.min_step(mem, options.min_step);
  if (flag == 0) flag = set.init_step(mem, options.step);
  if (flag == 0) flag = set.stop_time(mem, t1);
  if (flag == 0) flag = set.max_ord(mem, controls.max_order);
  if (flag == 0) flag = set.max_nonlin_iters(mem, controls.max_nonlin_iters);
  if (flag == 0) flag = set.max_conv_fails(mem, controls.max_conv_fails);
  if (flag == 0)
    flag = set.max_err_test_fails(mem, controls.max_err_test_fails);
  return flag;
}

OptionTable StepControlOptions(const StepControls& defaults,
                               const std::string& set_prefix) {
  return {
      OptionSpec::Int("max_order", defaults.max_order,
                      "largest BDF order (" + set_prefix + "MaxOrd)")
          .AtLeast(1)
          .AtMost(5),
      OptionSpec::Int(
          "max_nonlin_iters", defaults.max_nonlin_iters,
          "Newton iterations per step (" + set_prefix + "MaxNonlinIters)")
          .AtLeast(1),
      OptionSpec::Int(
          "max_conv_fails", defaults.max_conv_fails,
          "Newton failures per step (" + set_prefix + "MaxConvFails)")
          .AtLeast(1),
      OptionSpec::Int(
          "max_err_test_fails", defaults.max_err_test_fails,
          "error-test failures per step (" + set_prefix + "MaxErrTestFails)")
          .AtLeast(1),
  };
}

StepControls StepControlsFrom(const OptionValues& values) {
  StepControls controls;
  controls.max_order = static_cast<int>(values.GetInt("max_order"));
  controls.max_nonlin_iters =
      static_cast<int>(values.GetInt("max_nonlin_iters"));
  controls.max_conv_fails = static_cast<int>(values.GetInt("max_conv_fails"));
  controls.max_err_test_fails =
      static_cast<int>(values.GetInt("max_err_test_fails"));
  return controls;
}

OptionSpec RestartStepOption(const std::string& description) {
  return OptionSpec::Choice("restart_step", "carry",
                            {"carry", "given", "estimate"}, description);
}

RestartStep RestartStepFrom(const OptionValues& values) {
  const std::string text = values.GetString("restart_step");
  return text == "given"      ? RestartStep::kGiven
         : text == "estimate" ? RestartStep::kEstimate
                              : RestartStep::kCarry;
}

void CarriedStep::RecordFirstStep(const ErrorEstimateGetters& get, void* mem,
                                  N_Vector like, N_Vector* ele, N_Vector* ewt,
                                  int n_tested, int n_total,
                                  const ConstrainedOde* from, double inner,
                                  double outer) {
  ode = nullptr;
  double h = 0.0;
  int order = 0;
  if (*ele == nullptr) *ele = N_VClone(like);
  if (*ewt == nullptr) *ewt = N_VClone(like);
  // CV_SUCCESS == IDA_SUCCESS == 0.
  if (*ele == nullptr || *ewt == nullptr || get.last_step(mem, &h) != 0 ||
      get.last_order(mem, &order) != 0 || order != 1 ||
      get.local_errors(mem, *ele) != 0 || get.error_weights(mem, *ewt) != 0 ||
      !(h > 0.0))
    return;
  Eigen::Map<const Eigen::VectorXd> e(NV_DATA_S((*ele)), n_total),
      w(NV_DATA_S((*ewt)), n_total);
  const double norm = std::sqrt(
      e.head(n_tested).cwiseProduct(w.head(n_tested)).squaredNorm() / n_total);
  Record(from, h, norm, inner, outer);
}

std::string FlagName(char* name, const char* solver, int flag) {
  std::string out = name != nullptr
                        ? name
                        : std::string(solver) + " flag " + std::to_string(flag);
  std::free(name);
  return out;
}

std::string FailureMessage(const std::string& flag_name, double t,
                           const RhsTracker& rhs, const std::string& detail,
                           const std::string& last_error) {
  std::ostringstream os;
  os << flag_name << " at t = " << t;
  if (rhs.failed)
    os << " (Rhs returned false at t = " << rhs.failure_time << ")";
  if (!detail.empty()) os << " (" << detail << ")";
  if (!last_error.empty()) os << ": " << last_error;
  return os.str();
}

}  // namespace quasiroll::sundials_internal
