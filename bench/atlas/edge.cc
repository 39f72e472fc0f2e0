#include "quasiroll/bench/atlas/edge.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"

namespace quasiroll::bench {

const char* EdgeVerdict(double offset, QuasiStaticStatus status,
                        NlpStatus nlp_status) {
  const bool converged = status == QuasiStaticStatus::kOk;
  if (offset > 0) {
    if (converged) return "correct";
    return nlp_status == NlpStatus::kInfeasible ? "false_infeasibility"
                                                : "failure";
  }
  if (converged) return "wrong_claim";
  return status == QuasiStaticStatus::kInfeasibleFriction ? "correct"
                                                          : "failure";
}

std::vector<std::int64_t> ChooseEdgeCells(
    const std::vector<std::int64_t>& ok_cells, int count) {
  if (count <= 0) return {};
  if (static_cast<std::size_t>(count) >= ok_cells.size()) return ok_cells;
  std::vector<std::int64_t> chosen;
  for (int k = 0; k < count; ++k)
    chosen.push_back(ok_cells[k * ok_cells.size() / count]);
  return chosen;
}

std::vector<EdgeRow> RunEdgeStudy(const AtlasSpec& spec,
                                  const std::vector<std::int64_t>& cells,
                                  const EdgeOptions& options) {
  RegisterBuiltinNlpSolvers();
  const std::vector<std::string> backends =
      options.backends.empty() ? NlpSolverRegistry::Names() : options.backends;
  std::vector<EdgeRow> rows;
  for (std::int64_t index : cells) {
    const AtlasCell cell = CellAt(spec, index);
    const Scene scene = SceneAt(spec, cell);
    const KinematicModel model(scene.geometry, scene.terrain);
    const Configuration theta = SolveInitialConfiguration(model, scene);
    QuasiStaticProblem probe(model, QuasiStaticParameters::FromScene(scene));
    probe.SetConfiguration(theta);
    const double mu_min = probe.MinimumFriction(nullptr, nullptr);
    for (const std::string& backend : backends) {
      for (double d : options.offsets) {
        QuasiStaticParameters params = QuasiStaticParameters::FromScene(scene);
        params.mu = mu_min * (1.0 + d);
        QuasiStaticSolver solver(model, params,
                                 NlpSolverRegistry::Create(backend));
        QuasiStaticSolution sol;
        const auto start = std::chrono::steady_clock::now();
        solver.Solve(theta, &sol);
        EdgeRow row;
        row.wall_s = std::chrono::duration<double>(
                         std::chrono::steady_clock::now() - start)
                         .count();
        row.cell = index;
        row.mode = cell.mode;
        row.backend = backend;
        row.offset = d;
        row.mu = params.mu;
        row.verdict = EdgeVerdict(d, sol.status, sol.nlp_status);
        row.qs_status = ToString(sol.status);
        row.nlp_status = ToString(sol.nlp_status);
        row.iterations = sol.nlp_iterations;
        row.kkt_residual = sol.kkt_residual;
        rows.push_back(row);
      }
    }
  }
  return rows;
}

std::string EdgeCsvHeader() {
  return "cell,mode,backend,offset,mu,verdict,qs_status,nlp_status,"
         "iterations,kkt_residual,wall_s";
}

std::string EdgeCsvRow(const EdgeRow& r) {
  return JoinCsvRow({std::to_string(r.cell), ToString(r.mode), r.backend,
                     Num(r.offset), Num(r.mu), r.verdict, r.qs_status,
                     r.nlp_status, std::to_string(r.iterations),
                     Num(r.kkt_residual), Num(r.wall_s)});
}

}  // namespace quasiroll::bench
