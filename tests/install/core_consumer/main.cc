// Uses quasiroll::core alone, through the installed <quasiroll/...> headers:
// a reference problem's published optimum must satisfy its constraints and
// give its published objective, and no NLP backend is linked in.
#include <cmath>
#include <cstdio>

#include <quasiroll/core/nlp.h>
#include <quasiroll/core/nlp_reference_problems.h>

int main() {
  auto p = quasiroll::MakeReferenceProblem("hs071");
  if (!p) return 1;
  const Eigen::VectorXd& x = p->known_solution();
  const int n = p->num_variables(), m = p->num_constraints();
  Eigen::VectorXd xl(n), xu(n), gl(m), gu(m), g(m);
  p->GetBounds(xl, xu, gl, gu);
  p->Constraints(x, g);
  // The published solution has 10 significant digits: violation and
  // objective error ~1e-9.
  const double violation =
      quasiroll::MaxConstraintViolation(x, g, xl, xu, gl, gu);
  const double f_error = std::abs(p->Objective(x) - p->known_objective());
  const auto backends = quasiroll::NlpSolverRegistry::Names();
  std::printf(
      "hs071: violation %.2e, |f - f*| %.2e, NLP backends linked: %zu\n",
      violation, f_error, backends.size());
  return violation <= 1e-8 && f_error <= 1e-8 && backends.empty() ? 0 : 1;
}
