// Solver reliability at the edge of traversability (docs/atlas.md, "Edge
// reliability"): at atlas cells where the robot stands, every NLP backend
// solves the quasi-static problem at mu = mu_min (1 + d). For d > 0 a
// solution exists (mu > mu_min; in paper mode sufficiency is not proven,
// docs/model.md §7.7) and a correct backend converges, KKT-verified by
// NlpSolver::Solve; for d < 0 none exists and a correct backend does not
// claim one. The friction-cone rows make mu_min the exact edge, so |d| down
// to 1e-3 is far above mu_min's own accuracy (relative 1e-11).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "quasiroll/bench/atlas/atlas.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/quasi_static.h"

namespace quasiroll::bench {

struct EdgeOptions {
  // Cells, chosen evenly among the atlas's `ok` cells in index order.
  int cells = 16;
  std::vector<double> offsets = {1e-1, 1e-2, 1e-3, -1e-3, -1e-2};
  // NLP backends; empty = every registered one.
  std::vector<std::string> backends;
};

struct EdgeRow {
  std::int64_t cell = 0;
  ActuationMode mode = ActuationMode::kPaper;
  std::string backend;
  double offset = 0.0;  // d
  double mu = 0.0;      // mu_min (1 + d)
  // correct | wrong_claim (converged below the edge) | false_infeasibility
  // (reported infeasible above it) | failure (no answer: iteration limit,
  // numerical failure, ...).
  std::string verdict;
  std::string qs_status;   // QuasiStaticStatus as text
  std::string nlp_status;  // the backend's last NlpStatus as text
  int iterations = 0;
  double kkt_residual = 0.0;  // NaN unless converged
  double wall_s = 0.0;
};

// The verdict of one solve at offset d (EdgeRow::verdict): above the edge
// (d > 0) "correct" iff it converged; below it "correct" iff it did not and
// the solve was classified INFEASIBLE_FRICTION, "wrong_claim" if it
// converged.
const char* EdgeVerdict(double offset, QuasiStaticStatus status,
                        NlpStatus nlp_status);

// The cells of the study: `count` indices spread evenly over `ok_cells`
// (sorted), all of them when there are fewer.
std::vector<std::int64_t> ChooseEdgeCells(
    const std::vector<std::int64_t>& ok_cells, int count);

// Solves every (cell, backend, offset); deterministic, serial (backends that
// are not thread-safe need no care).
std::vector<EdgeRow> RunEdgeStudy(const AtlasSpec& spec,
                                  const std::vector<std::int64_t>& cells,
                                  const EdgeOptions& options);

std::string EdgeCsvHeader();
std::string EdgeCsvRow(const EdgeRow& row);

}  // namespace quasiroll::bench
