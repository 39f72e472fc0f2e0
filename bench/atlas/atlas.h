// Traversability atlas (docs/atlas.md): over a grid of planar poses
// (x, y, heading) of a scene's terrain and the actuation modes, the smallest
// friction coefficient that admits the commanded quasi-static motion,
//   mu_min(Theta) = min over statically admissible forces of
//                   max_i |f_t,i| / f_n,i                  (docs/model.md §7.7)
// at the pose's consistent initial configuration Theta (model.md §3), the
// wheel that attains it and the margin mu - mu_min at the scene's mu.
//
// A pose where the robot cannot stand is a row with its cause, never skipped:
//   no_contact          no consistent contact configuration (§3.1)
//   degenerate_contact  a validity check of §3.2 fails (tread angle,
//                       relative curvature, second contact, outside terrain)
//   singular_statics    the statics rows are rank deficient (mu_min undefined)
//   lift_off            mu_min = +inf: no force without pulling (§7.7)
// Cells are independent and computed in any order by any number of threads;
// the output is ordered by cell index, so it does not depend on --jobs.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "quasiroll/bench/io/json_reader.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::bench {

// One axis of the grid: `count` values evenly spaced from `lo` to `hi`
// (both included; count 1 = lo).
struct AtlasAxis {
  double lo = 0.0, hi = 0.0;
  int count = 1;
  double Value(int i) const;
};

struct AtlasSpec {
  std::string scene_path;
  Scene scene;  // loaded from scene_path
  AtlasAxis x, y;
  int headings = 16;  // evenly spaced over [0, 2 pi)
  std::vector<ActuationMode> modes = {ActuationMode::kPaper,
                                      ActuationMode::kPvc};
  // Cells of the edge-reliability study (edge.h; edge.csv), 0 = none. Not
  // part of the grid's key.
  int edge_cells = 0;
  // Cells are (x, y, heading, mode) with mode innermost; their count.
  std::int64_t CellCount() const;
  // Throws std::invalid_argument "<key>: <problem>, got <value>".
  void Validate() const;
};

// Reads an atlas spec YAML file: {scene: PATH, x: [lo, hi, n], y: [lo, hi,
// n], headings: N, modes: [paper, pvc]} (docs/atlas.md); relative scene paths
// are resolved against the spec's directory. Throws SceneError naming the key.
AtlasSpec LoadAtlasSpec(const std::string& path);
// The same grid as one line of text (part of meta.json and the resume check).
std::string CanonicalAtlasKey(const AtlasSpec& spec);

struct AtlasCell {
  std::int64_t index = 0;
  double x = 0.0, y = 0.0, heading = 0.0;  // [m, m, rad]
  ActuationMode mode = ActuationMode::kPaper;
};
AtlasCell CellAt(const AtlasSpec& spec, std::int64_t index);
// The spec's scene placed at the cell's pose, in the cell's mode.
Scene SceneAt(const AtlasSpec& spec, const AtlasCell& cell);

struct AtlasRow {
  AtlasCell cell;
  std::string status;             // "ok" or one of the causes above
  std::string detail;             // why, for a cause ("" when ok)
  double mu_min = 0.0;            // NaN when undefined
  int critical_wheel = 0;         // 1-based, 0 when none
  double mu = 0.0;                // the scene's mu
  double margin = 0.0;            // mu - mu_min (NaN when undefined)
  double min_normal_force = 0.0;  // [N] at the minimiser, NaN if undefined
  double z = 0.0, roll = 0.0, pitch = 0.0;  // platform pose, NaN if no contact
  double wall_s = 0.0;
};

// Evaluates one cell (allocation aside, independent of every other cell).
AtlasRow EvaluateAtlasCell(const AtlasSpec& spec, const AtlasCell& cell);
// Evaluates cells given by index; consecutive cells of one pose (its modes)
// share the placement and its checks, which do not depend on the mode (half
// the cost of a cell on R1). Row k equals EvaluateAtlasCell(spec,
// CellAt(spec, cells[k])) but for wall_s: the shared time is split evenly
// among the pose's rows.
std::vector<AtlasRow> EvaluateAtlasCells(
    const AtlasSpec& spec, const std::vector<std::int64_t>& cells);

struct AtlasOptions {
  std::string out_dir;
  int jobs = 1;
  bool resume = false;
  int progress = 0;  // 0 none, 1 a line on stderr
  // --shard I/N (docs/cluster.md, "Atlas"): compute only ShardCells(I, N)
  // into OUT/shards/I-of-N/ (atlas.csv, meta.json, its partial file), no
  // edge study (it needs every cell: `quasiroll merge` runs it). count 1 =
  // the whole atlas into OUT.
  int shard_index = 0, shard_count = 1;
};

// The cells of shard `index` of `count`: a contiguous index range,
// [i q + min(i, r), (i + 1) q + min(i + 1, r)) with q = cells / count and
// r = cells mod count: the first r shards have q + 1 cells, the others q,
// and together they cover every cell once.
struct AtlasCellRange {
  std::int64_t begin = 0, end = 0;
};
AtlasCellRange ShardCells(std::int64_t cells, int index, int count);
// "OUT/shards/I-of-N" (as `bench --shard` names its shard directories).
std::string AtlasShardDir(const std::string& out, int index, int count);

struct AtlasSummary {
  std::int64_t cells = 0, computed = 0, reused = 0;
  std::int64_t ok = 0;
  std::int64_t edge_solves = 0;  // rows of edge.csv
  double wall_seconds = 0.0;
};

// Computes every cell into OUT/atlas.csv (docs/formats.md) and OUT/meta.json,
// then, when spec.edge_cells > 0, the edge-reliability study into
// OUT/edge.csv.
// With `resume`, rows of an existing atlas.csv of the same grid are kept and
// only the missing cells computed; a different grid is an error.
AtlasSummary RunAtlas(const AtlasSpec& spec, const AtlasOptions& options);

// --- The steps of RunAtlas, shared by shards, quasiroll merge and
// quasiroll-mpi (docs/cluster.md) so that every path writes the same files.

// Finished rows in DIR (cell index -> the row's text, without newline):
// atlas.csv and every atlas.partial*.csv (this process's, an MPI worker's),
// when DIR/meta.json names the same grid; throws std::invalid_argument
// naming --resume and both keys when it names another. A row whose
// position columns differ from CellAt (a torn or foreign line) is ignored,
// as is a last line without its newline.
std::map<std::int64_t, std::string> ReadFinishedAtlasRows(
    const AtlasSpec& spec, const std::string& dir);

// Adds the rows in `text` (atlas.csv or a partial file, or the end of one)
// to *rows with the rules of ReadFinishedAtlasRows: a last line without its
// newline, a line with other columns or position columns other than its
// cell's are ignored.
void ParseAtlasRows(const AtlasSpec& spec, std::string text,
                    std::map<std::int64_t, std::string>* rows);

// Appends rows to a partial file, one flushed line each, so that a killed
// process leaves every finished row on disk. Opening drops a torn last line
// (one without its newline) so that the next row starts on a line of its
// own. Append throws std::runtime_error naming the file on a failed write.
class AtlasPartialFile {
 public:
  explicit AtlasPartialFile(std::string path);
  void Append(const std::string& row);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
};

// Starts an output directory: creates it, removes stale partial files
// unless `resume`, and writes meta.json with the grid's key (so that a
// killed run can resume).
// How the rows of an output directory were made (its meta.json).
struct AtlasOutputInfo {
  int jobs = 1;
  // A shard writes only the rows of ShardCells(index, count), "shard" in
  // meta.json, and no edge study.
  int shard_index = 0, shard_count = 1;
  // Further meta.json members, key -> JSON text ("mpi", "merge").
  std::vector<std::pair<std::string, std::string>> extra_meta;
};

void BeginAtlasOutput(const AtlasSpec& spec, const std::string& dir,
                      bool resume, const AtlasOutputInfo& info);

// Finishes DIR with the row of every cell (of the shard's cells, for a
// shard): atlas.csv (in cell index order), edge.csv when spec.edge_cells > 0
// (not for a shard), meta.json (the summary: `summary.wall_seconds` so far,
// plus the time spent here), terrain.json; removes the partial files. Rows
// outside the cells are ignored. Throws std::invalid_argument naming how
// many cells are missing and the first when one has no row. Returns the
// summary with `cells`, `ok`, `edge_solves` and `wall_seconds` set.
AtlasSummary FinishAtlasOutput(const AtlasSpec& spec, const std::string& dir,
                               const std::map<std::int64_t, std::string>& rows,
                               AtlasSummary summary,
                               const AtlasOutputInfo& info);

// The spec as meta.json's "spec" member records it (scene: an absolute
// path), and back; SpecFromAtlasMeta loads the scene and throws SceneError
// naming the file when it is missing or the grid's key differs from `key`.
std::string AtlasSpecJson(const AtlasSpec& spec);
AtlasSpec SpecFromAtlasMeta(const JsonValue& meta, const std::string& path);

// atlas.csv: the header line and one row (no trailing newline).
std::string AtlasCsvHeader();
std::string AtlasCsvRow(const AtlasRow& row);

}  // namespace quasiroll::bench
