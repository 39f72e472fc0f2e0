#include "quasiroll/bench/cluster/merge.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>

#include "quasiroll/bench/atlas/atlas.h"
#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/json_reader.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::bench {

namespace fs = std::filesystem;

const std::vector<std::string>& InvocationMetaKeys() {
  static const std::vector<std::string> keys = {
      "machine",    "jobs",     "resume", "options",       "shard",
      "start_time", "end_time", "wall_s", "runs_executed", "runs_resumed",
      "merge",      "mpi",      "command"};
  return keys;
}

const std::vector<std::string>& TimingAndHostColumns() {
  // wall_s*, wall_per_sim_s and timing_exclusive: timing (docs/harness.md);
  // host, cpu_model: the machine that executed the row.
  static const std::vector<std::string> columns = {
      "wall_s",     "wall_s_median",  "wall_s_min", "wall_s_max",
      "wall_s_all", "wall_per_sim_s", "host",       "cpu_model",
      "wall_s_q1",  "wall_s_q3",      "wall_s_iqr", "timing_exclusive"};
  return columns;
}

// ---------------------------------------------------------------- merge ----

namespace {

struct Meta {
  std::string path;
  JsonValue doc;  // an object
  // The member's text as written (copied verbatim into the merged meta.json).
  const std::string* Get(const std::string& key) const {
    const JsonValue* v = doc.Find(key);
    return v ? &v->raw() : nullptr;
  }
  // A string member's value; another value's text; "" if absent.
  std::string Str(const std::string& key) const {
    const JsonValue* v = doc.Find(key);
    if (!v) return "";
    return v->is_string() ? v->str() : v->raw();
  }
  bool complete() const {
    const std::string* v = Get("complete");
    return v && *v == "true";
  }
};

Meta ReadMeta(const fs::path& p) {
  std::string text;
  if (!ReadTextFile(p, &text)) throw SceneError(p.string() + ": cannot read");
  Meta m;
  m.path = p.string();
  try {
    m.doc = ParseJson(text, m.path);
  } catch (const JsonError& e) {
    throw SceneError(e.what());
  }
  if (!m.doc.is_object())
    throw SceneError(m.path + ": malformed JSON: object expected");
  return m;
}

// "I-of-N" -> (N, I) for ordering shard directories; others last.
std::pair<long, long> ShardOrder(const std::string& name) {
  const auto of = name.find("-of-");
  if (of == std::string::npos) return {1L << 40, 0};
  return {std::atol(name.substr(of + 4).c_str()),
          std::atol(name.substr(0, of).c_str())};
}

std::vector<Meta> CollectMetas(const std::vector<std::string>& inputs) {
  std::vector<Meta> metas;
  std::set<std::string> seen;  // canonical paths
  auto add = [&](const fs::path& p) {
    std::error_code ec;
    const std::string canon = fs::weakly_canonical(p, ec).string();
    if (seen.insert(ec ? p.string() : canon).second)
      metas.push_back(ReadMeta(p));
  };
  for (const std::string& in : inputs) {
    const fs::path dir(in);
    if (!fs::is_directory(dir))
      throw SceneError("merge: input " + in + ": not a directory");
    const std::size_t before = metas.size();
    if (fs::exists(dir / "meta.json")) add(dir / "meta.json");
    if (fs::is_directory(dir / "shards")) {
      std::vector<std::string> names;
      for (const auto& e : fs::directory_iterator(dir / "shards"))
        if (fs::exists(e.path() / "meta.json"))
          names.push_back(e.path().filename().string());
      std::sort(names.begin(), names.end(),
                [](const std::string& a, const std::string& b) {
                  return ShardOrder(a) < ShardOrder(b);
                });
      for (const std::string& n : names) add(dir / "shards" / n / "meta.json");
    }
    if (metas.size() == before && !fs::exists(dir / "meta.json"))
      throw SceneError("merge: input " + in +
                       ": no meta.json nor shards/*/meta.json (not an "
                       "output directory of quasiroll bench)");
  }
  return metas;
}

// Keys that must be byte-identical in every input: what was run, with what.
void CheckAgreement(const std::vector<Meta>& metas,
                    const std::vector<std::string>& keys) {
  for (const std::string& key : keys) {
    const std::string* first = metas[0].Get(key);
    for (std::size_t k = 1; k < metas.size(); ++k) {
      const std::string* v = metas[k].Get(key);
      if ((first == nullptr) != (v == nullptr) || (first && *first != *v))
        throw SceneError("merge: inputs disagree on " + key + ": " +
                         metas[0].path + " has " +
                         (first ? *first : "(no such key)") + ", " +
                         metas[k].path + " has " + (v ? *v : "(no such key)") +
                         " (merge only runs of one suite, commit and build)");
    }
  }
}

struct FoundRow {
  std::string header, row;
  fs::path dir;
};

// The finished row of `run_id` in `dir` (runs/<id>.csv with one row for that
// run and trajectories/<id>.csv present), as --resume accepts it.
bool FindRow(const fs::path& dir, const std::string& run_id, FoundRow* out) {
  std::string text;
  if (!ReadTextFile(dir / "runs" / (run_id + ".csv"), &text) || text.empty() ||
      text.back() != '\n')
    return false;
  if (!fs::exists(dir / "trajectories" / (run_id + ".csv"))) return false;
  const auto nl = text.find('\n');
  std::string row = text.substr(nl + 1);
  row.pop_back();
  if (row.find('\n') != std::string::npos || row.rfind(run_id + ",", 0) != 0)
    return false;
  out->header = text.substr(0, nl);
  out->row = row;
  out->dir = dir;
  return true;
}

bool SameFile(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::exists(b, ec) && fs::equivalent(a, b, ec);
}

// dst := src (a hard link if possible, else a copy), atomically.
void LinkOrCopy(const fs::path& src, const fs::path& dst) {
  if (SameFile(src, dst)) return;
  fs::create_directories(dst.parent_path());
  const fs::path tmp = dst.string() + ".tmp.merge";
  std::error_code ec;
  fs::remove(tmp, ec);
  fs::create_hard_link(src, tmp, ec);
  if (ec) fs::copy_file(src, tmp, fs::copy_options::overwrite_existing);
  fs::rename(tmp, dst);
}

// Every file of DIR/<sub>/ of every input into OUT/<sub>/ unless OUT has it.
void UnionDirectory(const std::vector<std::string>& inputs, const fs::path& out,
                    const std::string& sub) {
  for (const std::string& in : inputs) {
    const fs::path dir = fs::path(in) / sub;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      if (!e.is_regular_file()) continue;
      const std::string name = e.path().filename().string();
      if (name.find(".tmp.") != std::string::npos) continue;
      const fs::path dst = out / sub / name;
      if (!fs::exists(dst)) LinkOrCopy(e.path(), dst);
    }
  }
}

double NumberOr(const std::string* raw, double fallback) {
  if (!raw) return fallback;
  char* end = nullptr;
  const double v = std::strtod(raw->c_str(), &end);
  return end == raw->c_str() ? fallback : v;
}

// ------------------------------------------------- MergeOutputs phases ----

// The suite file: --suite, else the absolute path the first input recorded.
std::string ResolveSuitePath(const MergeOptions& options,
                             const std::vector<Meta>& metas) {
  std::string suite_path = options.suite;
  if (suite_path.empty()) {
    const JsonValue* suite_obj = metas[0].doc.Find("suite");
    const JsonValue* path =
        suite_obj ? suite_obj->Find("absolute_path") : nullptr;
    if (path) suite_path = path->is_string() ? path->str() : path->raw();
    if (suite_path.empty())
      throw SceneError("merge: " + metas[0].path +
                       " names no suite file; pass --suite FILE");
  }
  return suite_path;
}

// The grid is re-expanded from the suite file, so it must be the very file the
// inputs ran (a changed file could give other run ids or another order).
void CheckSuiteHash(const std::string& suite_path,
                    const std::string& suite_hash) {
  std::string text;
  if (!ReadTextFile(suite_path, &text))
    throw SceneError("merge: cannot read the suite file " + suite_path +
                     " (pass --suite FILE)");
  const std::string hash = Hex64(Fnv1a64(text));
  if (hash != suite_hash)
    throw SceneError("merge: the suite file " + suite_path + " has hash " +
                     hash + ", the inputs were run with suite_hash " +
                     suite_hash + " (pass --suite FILE with that suite)");
}

void WarnIncompleteInputs(const std::vector<Meta>& metas, std::FILE* log) {
  for (const Meta& m : metas)
    if (!m.complete() && log)
      std::fprintf(log,
                   "merge: warning: %s is not complete (interrupted?); its "
                   "finished runs are used\n",
                   m.path.c_str());
}

// The finished rows of the selected runs, in grid order.
struct MergedRows {
  std::string header;
  std::vector<std::string> columns;  // of header
  std::vector<FoundRow> rows;        // per selected run
};

// A second finished row of a run (another input, not a link to the kept one):
// counted, and compared with the kept row outside the timing and host columns,
// which legitimately differ between machines. Only the first differing column
// is reported.
void CompareDuplicateRow(const FoundRow& kept, const FoundRow& other,
                         const std::vector<std::string>& columns,
                         const std::string& id, std::FILE* log,
                         MergeSummary* summary) {
  ++summary->duplicates;
  const auto a = SplitCsvLine(kept.row), b = SplitCsvLine(other.row);
  const auto& skip = TimingAndHostColumns();
  for (std::size_t c = 0; c < columns.size() && c < a.size(); ++c) {
    if (std::find(skip.begin(), skip.end(), columns[c]) != skip.end()) continue;
    if (c >= b.size() || a[c] != b[c]) {
      ++summary->differing;
      if (log)
        std::fprintf(log,
                     "merge: warning: run %s differs between %s and %s in "
                     "column %s (%s vs %s); keeping the first\n",
                     id.c_str(), kept.dir.c_str(), other.dir.c_str(),
                     columns[c].c_str(), a[c].c_str(),
                     c < b.size() ? b[c].c_str() : "");
      break;
    }
  }
}

// Rows, in grid order: the first input holding a finished row wins. All
// inputs must share one runs.csv header; every selected run must be found.
MergedRows CollectRows(const MergeOptions& options, const SuitePlan& plan,
                       MergeSummary* summary) {
  MergedRows m;
  m.rows.resize(plan.selected.size());
  std::vector<std::string> missing;
  for (std::size_t i = 0; i < plan.selected.size(); ++i) {
    const std::string& id = plan.selected[i]->run_id;
    bool found = false;
    for (const std::string& in : options.inputs) {
      FoundRow f;
      if (!FindRow(in, id, &f)) continue;
      if (m.header.empty()) {
        m.header = f.header;
        m.columns = SplitCsvLine(m.header);
      } else if (f.header != m.header) {
        throw SceneError("merge: " + (f.dir / "runs" / (id + ".csv")).string() +
                         " has other columns than " +
                         (m.rows[0].dir / "runs").string() +
                         "/*.csv (made by another quasiroll version?)");
      }
      if (!found) {
        m.rows[i] = f;
        found = true;
        continue;
      }
      if (SameFile(m.rows[i].dir / "runs" / (id + ".csv"),
                   f.dir / "runs" / (id + ".csv")))
        continue;
      CompareDuplicateRow(m.rows[i], f, m.columns, id, options.log, summary);
    }
    if (!found) missing.push_back(id);
  }
  if (!missing.empty())
    throw SceneError(
        "merge: " + std::to_string(missing.size()) + " of " +
        std::to_string(plan.selected.size()) +
        " selected runs have no finished row in the inputs (first: " +
        missing[0] +
        "); run the shards that hold them again with --resume, then merge");
  return m;
}

// OUT/trajectories, OUT/runs, OUT/checkpoints, OUT/switches (linked from the
// winning inputs), the union of references and terrains, and OUT/runs.csv;
// counts failures and hosts.
void WriteMergedRuns(const fs::path& out, const SuitePlan& plan,
                     const MergedRows& m, const MergeOptions& options,
                     MergeSummary* summary) {
  fs::create_directories(out);
  const auto& columns = m.columns;
  const auto& status_it = std::find(columns.begin(), columns.end(), "status");
  const auto& host_it = std::find(columns.begin(), columns.end(), "host");
  std::set<std::string> hosts;
  std::string csv = m.header + "\n";
  for (std::size_t i = 0; i < m.rows.size(); ++i) {
    const std::string& id = plan.selected[i]->run_id;
    const FoundRow& f = m.rows[i];
    LinkOrCopy(f.dir / "trajectories" / (id + ".csv"),
               out / "trajectories" / (id + ".csv"));
    LinkOrCopy(f.dir / "runs" / (id + ".csv"), out / "runs" / (id + ".csv"));
    // Checkpoint samples (docs/harness.md, Errors at checkpoints) and the
    // located switches (docs/formats.md), when the input has them.
    for (const char* sub : {"checkpoints", "switches"})
      if (fs::exists(f.dir / sub / (id + ".csv")))
        LinkOrCopy(f.dir / sub / (id + ".csv"), out / sub / (id + ".csv"));
    csv += f.row + "\n";
    const auto fields = SplitCsvLine(f.row);
    const auto col = [&](auto it) -> std::string {
      const std::size_t c = static_cast<std::size_t>(it - columns.begin());
      return it != columns.end() && c < fields.size() ? fields[c] : "";
    };
    if (col(status_it) != "success") ++summary->failures;
    if (host_it != columns.end()) hosts.insert(col(host_it));
  }
  UnionDirectory(options.inputs, out, "references");
  UnionDirectory(options.inputs, out, "terrains");
  AtomicWriteFile((out / "runs.csv").string(), csv);
  summary->runs = static_cast<int>(m.rows.size());
  summary->hosts.assign(hosts.begin(), hosts.end());
}

// Invocation keys of the merged whole: the earliest start, the latest end,
// and sums of the per-input wall time and run counts.
struct MergedInvocation {
  std::string start_time, end_time;
  double wall = 0;
  long long executed = 0, resumed = 0;
};

MergedInvocation SumInvocations(const std::vector<Meta>& metas) {
  MergedInvocation inv;
  for (const Meta& m : metas) {
    const std::string* s = m.Get("start_time");
    const std::string* e = m.Get("end_time");
    if (s && (inv.start_time.empty() || *s < inv.start_time))
      inv.start_time = *s;
    if (e && (inv.end_time.empty() || *e > inv.end_time)) inv.end_time = *e;
    inv.wall += NumberOr(m.Get("wall_s"), 0);
    inv.executed += static_cast<long long>(NumberOr(m.Get("runs_executed"), 0));
    inv.resumed += static_cast<long long>(NumberOr(m.Get("runs_resumed"), 0));
  }
  if (inv.end_time.empty()) inv.end_time = JsonQuote(IsoTimeNow());
  return inv;
}

// The template's options with "out" = the merged directory ("" if the
// template has no options).
std::string MergedOptionsJson(const Meta& tmpl, const std::string& out) {
  std::string options_raw;
  if (const JsonValue* o = tmpl.doc.Find("options")) {
    options_raw = "{";
    bool first = true;
    for (const auto& [k, v] : o->members()) {
      if (!first) options_raw += ",";
      first = false;
      options_raw +=
          JsonQuote(k) + ":" + (k == "out" ? JsonQuote(out) : v.raw());
    }
    options_raw += "}";
  }
  return options_raw;
}

// The "merge" member: which inputs went in (with their invocation keys, so a
// merged directory still tells where each part ran) and the duplicate counts.
std::string MergeRecordJson(const std::vector<Meta>& metas,
                            const MergeSummary& summary,
                            const std::vector<std::string>& keys = {
                                "shard", "machine", "jobs", "start_time",
                                "end_time", "wall_s", "runs_selected",
                                "runs_executed", "runs_resumed", "complete"}) {
  std::string merge = "{\"inputs\":[";
  for (std::size_t k = 0; k < metas.size(); ++k) {
    const Meta& m = metas[k];
    if (k) merge += ",";
    merge += "{\"meta\":" + JsonQuote(m.path);
    for (const std::string& key : keys) {
      const std::string* v = m.Get(key);
      merge += std::string(",") + JsonQuote(key) + ":" + (v ? *v : "null");
    }
    merge += "}";
  }
  merge += "],\"duplicates\":" + std::to_string(summary.duplicates) +
           ",\"differing_duplicates\":" + std::to_string(summary.differing) +
           ",\"hosts\":[";
  for (std::size_t k = 0; k < summary.hosts.size(); ++k)
    merge += (k ? "," : "") + JsonQuote(summary.hosts[k]);
  merge += "]}";
  return merge;
}

// meta.json: the members of a complete input (else the first), with the
// invocation keys recomputed for the merged whole, and "merge". Shard and
// mpi keys describe one input only, so they are dropped.
void WriteMergedMeta(const fs::path& out, const std::vector<Meta>& metas,
                     const MergeOptions& options, const MergeSummary& summary,
                     std::size_t runs_selected) {
  const Meta* tmpl = &metas[0];
  for (const Meta& m : metas)
    if (m.complete()) {
      tmpl = &m;
      break;
    }
  const MergedInvocation inv = SumInvocations(metas);
  const std::string options_raw = MergedOptionsJson(*tmpl, options.out);
  std::map<std::string, std::string> replaced = {
      {"options", options_raw},
      {"start_time", inv.start_time.empty() ? "null" : inv.start_time},
      {"end_time", inv.end_time},
      {"wall_s", JsonWriter().Value(inv.wall).str()},
      {"runs_selected", std::to_string(runs_selected)},
      {"runs_executed", std::to_string(inv.executed)},
      {"runs_resumed", std::to_string(inv.resumed)},
      {"failures", std::to_string(summary.failures)},
      {"complete", "true"}};
  if (options_raw.empty()) replaced.erase("options");
  std::string meta = "{";
  std::set<std::string> emitted;
  auto emit = [&](const std::string& k, const std::string& v) {
    if (meta.size() > 1) meta += ",";
    meta += JsonQuote(k) + ":" + v;
    emitted.insert(k);
  };
  for (const auto& [k, v] : tmpl->doc.members()) {
    if (k == "shard" || k == "merge" || k == "mpi") continue;
    const auto it = replaced.find(k);
    emit(k, it == replaced.end() ? v.raw() : it->second);
  }
  for (const char* k :
       {"start_time", "end_time", "wall_s", "runs_selected", "runs_executed",
        "runs_resumed", "failures", "complete"})
    if (!emitted.count(k) && replaced.count(k)) emit(k, replaced[k]);
  emit("merge", MergeRecordJson(metas, summary));
  meta += "}\n";
  AtomicWriteFile((out / "meta.json").string(), meta);
}

// ---------------------------------------------------------- atlases ----

// The atlas outputs to merge: an input's shards/*/meta.json when it has
// any (its own meta.json is then an earlier merge's), else its meta.json.
std::vector<Meta> AtlasInputs(const std::vector<Meta>& metas) {
  std::set<std::string> with_shards;
  for (const Meta& m : metas) {
    const fs::path dir = fs::path(m.path).parent_path();
    if (dir.parent_path().filename() == "shards")
      with_shards.insert(dir.parent_path().parent_path().string());
  }
  std::vector<Meta> inputs;
  for (const Meta& m : metas) {
    if (m.Str("kind") != "atlas")
      throw SceneError("merge: " + m.path + " is not an atlas's meta.json (" +
                       metas[0].path +
                       " is): merge atlases and suites separately");
    const fs::path dir = fs::path(m.path).parent_path();
    if (dir.parent_path().filename() != "shards" &&
        with_shards.count(dir.string()))
      continue;
    inputs.push_back(m);
  }
  return inputs;
}

// Rows of every input's atlas.csv by cell index; a cell in two inputs is an
// error naming both files (shards of different counts in one directory?).
std::map<std::int64_t, std::string> CollectAtlasRows(
    const std::vector<Meta>& inputs, std::int64_t cells, std::FILE* log) {
  std::map<std::int64_t, std::string> rows;
  std::map<std::int64_t, std::string> source;
  for (const Meta& m : inputs) {
    const fs::path csv = fs::path(m.path).parent_path() / "atlas.csv";
    std::string text;
    if (!ReadTextFile(csv.string(), &text)) {
      if (log)
        std::fprintf(log,
                     "merge: warning: %s is missing (shard not finished?); "
                     "its cells count as missing\n",
                     csv.c_str());
      continue;
    }
    std::istringstream in(text);
    std::string line;
    std::getline(in, line);
    if (line != AtlasCsvHeader())
      throw SceneError("merge: " + csv.string() +
                       " has other columns than this quasiroll writes (made "
                       "by another version?)");
    while (std::getline(in, line)) {
      const std::int64_t index = std::stoll(SplitCsvLine(line).at(0));
      if (index < 0 || index >= cells)
        throw SceneError("merge: " + csv.string() + ": cell " +
                         std::to_string(index) + " outside the grid's " +
                         std::to_string(cells) + " cells");
      const auto [it, inserted] = rows.emplace(index, line);
      if (!inserted)
        throw SceneError("merge: cell " + std::to_string(index) +
                         " is in both " + source[index] + " and " +
                         csv.string() +
                         " (shards of different counts? merge one set)");
      source[index] = csv.string();
    }
  }
  return rows;
}

// An atlas (docs/cluster.md, "Atlas"): the inputs agree on the grid and the
// commit, every cell has exactly one row; then the steps of a one-process
// atlas's end (FinishAtlasOutput: atlas.csv, the edge study, meta.json,
// terrain.json), so the result is that of one process but for wall_s.
MergeSummary MergeAtlas(const MergeOptions& options,
                        const std::vector<Meta>& metas) {
  const std::vector<Meta> inputs = AtlasInputs(metas);
  CheckAgreement(inputs, {"key", "commit"});
  const AtlasSpec spec = SpecFromAtlasMeta(inputs[0].doc, inputs[0].path);
  const std::int64_t cells = spec.CellCount();
  const auto rows = CollectAtlasRows(inputs, cells, options.log);
  if (static_cast<std::int64_t>(rows.size()) < cells) {
    std::int64_t first = 0;
    while (rows.count(first)) ++first;
    throw SceneError(
        "merge: " +
        std::to_string(cells - static_cast<std::int64_t>(rows.size())) +
        " of " + std::to_string(cells) +
        " atlas cells have no row in the inputs (first: " +
        std::to_string(first) +
        "); run the shards that hold them again with --resume, then merge");
  }
  AtlasSummary s;
  MergeSummary summary;
  std::set<std::string> hosts;
  for (const Meta& m : inputs) {
    s.computed += static_cast<std::int64_t>(NumberOr(m.Get("computed"), 0));
    s.reused += static_cast<std::int64_t>(NumberOr(m.Get("reused"), 0));
    s.wall_seconds += NumberOr(m.Get("wall_s"), 0);
    hosts.insert(m.Str("host"));
  }
  summary.hosts.assign(hosts.begin(), hosts.end());
  summary.metas = static_cast<int>(inputs.size());
  AtlasOutputInfo info;
  info.jobs = static_cast<int>(NumberOr(inputs[0].Get("jobs"), 1));
  info.extra_meta = {
      {"merge", MergeRecordJson(inputs, summary,
                                {"shard", "host", "jobs", "wall_s", "cells",
                                 "computed", "reused"})}};
  fs::create_directories(options.out);
  const AtlasSummary done = FinishAtlasOutput(spec, options.out, rows, s, info);
  summary.runs = static_cast<int>(done.cells);
  summary.failures = static_cast<int>(done.cells - done.ok);
  summary.atlas = true;
  return summary;
}

}  // namespace

MergeSummary MergeOutputs(const MergeOptions& options) {
  if (options.inputs.empty()) throw SceneError("merge: no input directory");
  const std::vector<Meta> metas = CollectMetas(options.inputs);
  if (metas[0].Str("kind") == "atlas") return MergeAtlas(options, metas);
  CheckAgreement(metas, {"suite_hash", "commit", "build", "library_versions",
                         "numerical_libraries", "reference", "filter"});
  MergeSummary summary;
  summary.metas = static_cast<int>(metas.size());

  // The suite, checked against the inputs' hash, gives the grid to merge.
  const std::string suite_path = ResolveSuitePath(options, metas);
  CheckSuiteHash(suite_path, metas[0].Str("suite_hash"));
  const Suite suite = LoadSuite(suite_path);
  HarnessOptions selection;
  selection.filter = metas[0].Str("filter");
  const SuitePlan plan = PlanSuite(suite, selection);
  WarnIncompleteInputs(metas, options.log);

  const MergedRows rows = CollectRows(options, plan, &summary);
  const fs::path out(options.out);
  WriteMergedRuns(out, plan, rows, options, &summary);
  WriteMergedMeta(out, metas, options, summary, rows.rows.size());
  return summary;
}

}  // namespace quasiroll::bench
