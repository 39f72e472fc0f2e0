#include "quasiroll/bench/atlas/atlas.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "quasiroll/bench/atlas/edge.h"
#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/format.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/output_lock.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/bench/io/terrain_json.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/quasi_static.h"
#include "quasiroll/core/so3.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll::bench {

namespace fs = std::filesystem;

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

void Fail(const std::string& key, const std::string& what) {
  throw std::invalid_argument(key + ": " + what);
}

AtlasAxis ReadAxisNode(const YAML::Node& node, const std::string& path) {
  if (!node.IsSequence() || node.size() != 3)
    throw SceneError(path + ": must be [lo, hi, count], got " +
                     yaml::DescribeNode(node));
  AtlasAxis a;
  a.lo = yaml::ReadDouble(node[0], yaml::JoinIndex(path, 0), {});
  a.hi = yaml::ReadDouble(node[1], yaml::JoinIndex(path, 1), {});
  a.count = static_cast<int>(
      yaml::ReadInt(node[2], yaml::JoinIndex(path, 2), 1, 100000));
  return a;
}
}  // namespace

double AtlasAxis::Value(int i) const {
  return count == 1 ? lo : lo + (hi - lo) * i / (count - 1);
}

std::int64_t AtlasSpec::CellCount() const {
  return static_cast<std::int64_t>(x.count) * y.count * headings *
         static_cast<std::int64_t>(modes.size());
}

void AtlasSpec::Validate() const {
  for (const auto& [name, a] : {std::pair<const char*, AtlasAxis>{"x", x},
                                std::pair<const char*, AtlasAxis>{"y", y}}) {
    if (!std::isfinite(a.lo) || !std::isfinite(a.hi) || a.hi < a.lo)
      Fail(name, "must be a finite range lo <= hi, got [" + Num(a.lo) + ", " +
                     Num(a.hi) + "]");
    if (a.count < 1 || a.count > 100000)
      Fail(name,
           "count must be in [1, 100000], got " + std::to_string(a.count));
  }
  if (headings < 1 || headings > 100000)
    Fail("headings", "must be in [1, 100000], got " + std::to_string(headings));
  if (modes.empty()) Fail("modes", "must name at least one mode, got none");
  if (edge_cells < 0 || edge_cells > 100000)
    Fail("edge_cells",
         "must be in [0, 100000], got " + std::to_string(edge_cells));
  if (modes.size() == 2 && modes[0] == modes[1])
    Fail("modes",
         "a mode is named twice, got " + std::string(ToString(modes[0])));
}

AtlasSpec LoadAtlasSpec(const std::string& path) {
  const YAML::Node root = yaml::LoadYamlFile(path);
  yaml::CheckKeys(root, "",
                  {"scene", "x", "y", "headings", "modes", "edge_cells"});
  AtlasSpec spec;
  const std::string scene =
      yaml::ReadString(yaml::Require(root, "", "scene"), "scene");
  spec.scene_path =
      fs::path(scene).is_absolute()
          ? scene
          : (fs::path(path).parent_path() / scene).lexically_normal().string();
  spec.x = ReadAxisNode(yaml::Require(root, "", "x"), "x");
  spec.y = ReadAxisNode(yaml::Require(root, "", "y"), "y");
  if (auto n = yaml::Child(root, "headings"))
    spec.headings = static_cast<int>(yaml::ReadInt(*n, "headings", 1, 100000));
  if (auto n = yaml::Child(root, "modes")) {
    spec.modes.clear();
    if (!n->IsSequence())
      throw SceneError("modes: must be a sequence, got " +
                       yaml::DescribeNode(*n));
    for (std::size_t i = 0; i < n->size(); ++i) {
      const std::string p = yaml::JoinIndex("modes", i);
      spec.modes.push_back(yaml::ReadEnum((*n)[i], p, {"paper", "pvc"}) == "pvc"
                               ? ActuationMode::kPvc
                               : ActuationMode::kPaper);
    }
  }
  if (auto n = yaml::Child(root, "edge_cells"))
    spec.edge_cells =
        static_cast<int>(yaml::ReadInt(*n, "edge_cells", 0, 100000));
  spec.scene = LoadScene(spec.scene_path);
  try {
    spec.Validate();
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
  return spec;
}

std::string CanonicalAtlasKey(const AtlasSpec& spec) {
  std::ostringstream os;
  os << "atlas{scene=" << spec.scene.name << ";mu=" << Num(spec.scene.mu)
     << ";x=" << Num(spec.x.lo) << ":" << Num(spec.x.hi) << ":" << spec.x.count
     << ";y=" << Num(spec.y.lo) << ":" << Num(spec.y.hi) << ":" << spec.y.count
     << ";headings=" << spec.headings << ";modes=";
  for (std::size_t i = 0; i < spec.modes.size(); ++i)
    os << (i ? "," : "") << ToString(spec.modes[i]);
  os << "}";
  return os.str();
}

AtlasCell CellAt(const AtlasSpec& spec, std::int64_t index) {
  AtlasCell c;
  c.index = index;
  const auto nm = static_cast<std::int64_t>(spec.modes.size());
  c.mode = spec.modes[index % nm];
  std::int64_t rest = index / nm;
  const int h = static_cast<int>(rest % spec.headings);
  rest /= spec.headings;
  const int j = static_cast<int>(rest % spec.y.count);
  const int i = static_cast<int>(rest / spec.y.count);
  c.x = spec.x.Value(i);
  c.y = spec.y.Value(j);
  c.heading = 2.0 * kPi * h / spec.headings;
  return c;
}

Scene SceneAt(const AtlasSpec& spec, const AtlasCell& cell) {
  Scene scene = spec.scene;
  scene.mode = cell.mode;
  scene.x0 = cell.x;
  scene.y0 = cell.y;
  scene.yaw0 = cell.heading;
  return scene;
}

namespace {

using SteadyClock = std::chrono::steady_clock;

double SecondsSince(SteadyClock::time_point start) {
  return std::chrono::duration<double>(SteadyClock::now() - start).count();
}

// A pose's placement and its checks (steps 1-2 of docs/atlas.md, "What one
// cell does"): they depend on (x, y, heading) only, not on the mode.
struct Placement {
  std::string status, detail;  // status "" = placed and valid
  Configuration theta;
  double z = kNaN, roll = kNaN, pitch = kNaN;
};

Placement PlaceAt(const KinematicModel& model, const Scene& scene) {
  Placement pl;
  try {
    pl.theta = SolveInitialConfiguration(model, scene);
  } catch (const GeometryError& e) {
    pl.status = "no_contact";
    pl.detail = e.what();
    return pl;
  }
  Mat3 r;
  Vec3 p;
  model.PlatformPose(pl.theta, &r, &p);
  const Vec3 rpy = RpyFromRotation(r);
  pl.z = p(2);
  pl.roll = rpy(0);
  pl.pitch = rpy(1);
  const ValidityReport validity = CheckValidity(model, pl.theta, true);
  if (!validity.ok()) {
    pl.status = "degenerate_contact";
    pl.detail = validity.Describe();
  }
  return pl;
}

// Steps 3-4 for one mode at a placement (wall_s left 0).
AtlasRow RowAt(const AtlasSpec& spec, const AtlasCell& cell,
               const KinematicModel& model, const Placement& pl) {
  AtlasRow row;
  row.cell = cell;
  row.mu = spec.scene.mu;
  row.mu_min = row.margin = row.min_normal_force = kNaN;
  row.z = pl.z;
  row.roll = pl.roll;
  row.pitch = pl.pitch;
  if (!pl.status.empty()) {
    row.status = pl.status;
    row.detail = pl.detail;
    return row;
  }
  const Scene scene = SceneAt(spec, cell);
  QuasiStaticProblem problem(model, QuasiStaticParameters::FromScene(scene));
  problem.SetConfiguration(pl.theta);
  if (!problem.StaticsFullRank()) {
    row.status = "singular_statics";
    row.detail = "the statics rows are rank deficient";
    return row;
  }
  int critical = -1;
  double fn_min = kNaN;
  row.mu_min = problem.MinimumFriction(&critical, &fn_min);
  row.critical_wheel = critical >= 0 ? critical + 1 : 0;
  row.min_normal_force = fn_min;
  if (std::isinf(row.mu_min)) {
    row.mu_min = kNaN;
    row.status = "lift_off";
    row.detail = "no statically admissible force without pulling";
    return row;
  }
  row.margin = scene.mu - row.mu_min;
  row.status = "ok";
  return row;
}

}  // namespace

AtlasRow EvaluateAtlasCell(const AtlasSpec& spec, const AtlasCell& cell) {
  const auto start = SteadyClock::now();
  const Scene scene = SceneAt(spec, cell);
  const KinematicModel model(scene.geometry, scene.terrain);
  AtlasRow row = RowAt(spec, cell, model, PlaceAt(model, scene));
  row.wall_s = SecondsSince(start);
  return row;
}

std::vector<AtlasRow> EvaluateAtlasCells(
    const AtlasSpec& spec, const std::vector<std::int64_t>& cells) {
  const auto nm = static_cast<std::int64_t>(spec.modes.size());
  std::vector<AtlasRow> rows;
  rows.reserve(cells.size());
  for (std::size_t k = 0; k < cells.size();) {
    // cells[k, end): consecutive cells of one pose.
    std::size_t end = k + 1;
    while (end < cells.size() && cells[end] / nm == cells[k] / nm) ++end;
    const auto start = SteadyClock::now();
    const AtlasCell first = CellAt(spec, cells[k]);
    const Scene scene = SceneAt(spec, first);
    const KinematicModel model(scene.geometry, scene.terrain);
    const Placement pl = PlaceAt(model, scene);
    const double shared = SecondsSince(start) / static_cast<double>(end - k);
    for (; k < end; ++k) {
      const auto own = SteadyClock::now();
      rows.push_back(RowAt(spec, CellAt(spec, cells[k]), model, pl));
      rows.back().wall_s = shared + SecondsSince(own);
    }
  }
  return rows;
}

std::string AtlasCsvHeader() {
  return "cell,x,y,heading,mode,status,detail,mu_min,critical_wheel,mu,"
         "margin,min_normal_force,z,roll,pitch,wall_s";
}

std::string AtlasCsvRow(const AtlasRow& row) {
  // Num: the shortest text that reads back to the same double.
  return JoinCsvRow(
      {std::to_string(row.cell.index), Num(row.cell.x), Num(row.cell.y),
       Num(row.cell.heading), ToString(row.cell.mode), row.status, row.detail,
       Num(row.mu_min), std::to_string(row.critical_wheel), Num(row.mu),
       Num(row.margin), Num(row.min_normal_force), Num(row.z), Num(row.roll),
       Num(row.pitch), Num(row.wall_s)});
}

AtlasCellRange ShardCells(std::int64_t cells, int index, int count) {
  // q cells each, the first r shards one more: no product beyond `cells`.
  const std::int64_t q = cells / count, r = cells % count;
  const auto at = [&](std::int64_t i) { return i * q + std::min(i, r); };
  return {at(index), at(index + 1)};
}

std::string AtlasShardDir(const std::string& out, int index, int count) {
  return (fs::path(out) / "shards" /
          (std::to_string(index) + "-of-" + std::to_string(count)))
      .string();
}

namespace {

// This process's partial file; MPI workers write atlas.partial.rank-R.csv
// (quasiroll-mpi). Every atlas.partial*.csv of a directory is read on
// resume and removed when atlas.csv is complete.
constexpr const char* kPartialName = "atlas.partial.csv";
// atlas.csv's `status` column (AtlasCsvHeader).
constexpr std::size_t kStatusColumn = 5;

std::vector<fs::path> PartialFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("atlas.partial", 0) == 0 && name.size() > 4 &&
        name.compare(name.size() - 4, 4, ".csv") == 0)
      files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// Drops a last line without its newline (torn by an interruption).
void WholeLines(std::string* text) {
  const std::size_t end = text->rfind('\n');
  text->erase(end == std::string::npos ? 0 : end + 1);
}

// Is `fields` the row of cell `index` (its position columns as CellAt
// writes them)? Guards against a torn line glued to the next row.
bool RowOfCell(const AtlasSpec& spec, std::int64_t index,
               const std::vector<std::string>& fields) {
  const AtlasCell c = CellAt(spec, index);
  return fields[1] == Num(c.x) && fields[2] == Num(c.y) &&
         fields[3] == Num(c.heading) && fields[4] == ToString(c.mode);
}

}  // namespace

void ParseAtlasRows(const AtlasSpec& spec, std::string text,
                    std::map<std::int64_t, std::string>* rows) {
  WholeLines(&text);
  std::istringstream in(text);
  std::string line;
  const std::int64_t n = spec.CellCount();
  const std::size_t columns = SplitCsvLine(AtlasCsvHeader()).size();
  while (std::getline(in, line)) {
    if (line.empty() || line == AtlasCsvHeader()) continue;
    const std::vector<std::string> fields = SplitCsvLine(line);
    if (fields.size() != columns || fields[0].empty() ||
        fields[0].find_first_not_of("0123456789") != std::string::npos)
      continue;
    const std::int64_t index = std::stoll(fields[0]);
    if (index < n && RowOfCell(spec, index, fields)) (*rows)[index] = line;
  }
}

namespace {

void WriteAtlasMeta(const AtlasSpec& spec, const fs::path& out,
                    const AtlasSummary& s, const AtlasOutputInfo& info) {
  JsonWriter j;
  j.BeginObject();
  j.Key("kind").Value("atlas");
  j.Key("key").Value(CanonicalAtlasKey(spec));
  j.Key("scene").Value(spec.scene_path);
  j.Key("commit").Value(GitCommit());
  j.Key("cells").Value(static_cast<double>(s.cells));
  j.Key("cells_ok").Value(static_cast<double>(s.ok));
  j.Key("computed").Value(static_cast<double>(s.computed));
  j.Key("reused").Value(static_cast<double>(s.reused));
  j.Key("edge_cells").Value(spec.edge_cells);
  j.Key("edge_solves").Value(static_cast<double>(s.edge_solves));
  j.Key("jobs").Value(info.jobs);
  j.Key("wall_s").Value(s.wall_seconds);
  j.Key("host").Value(ThisMachine().hostname);
  j.Key("cpu_model").Value(ThisMachine().cpu);
  j.Key("library_versions");
  WriteLibraryVersions(&j);
  std::string text = j.str();  // members below are JSON text already
  text += ",\"spec\":" + AtlasSpecJson(spec);
  if (info.shard_count > 1) {
    const AtlasCellRange r =
        ShardCells(spec.CellCount(), info.shard_index, info.shard_count);
    text += ",\"shard\":{\"index\":" + std::to_string(info.shard_index) +
            ",\"count\":" + std::to_string(info.shard_count) +
            ",\"first_cell\":" + std::to_string(r.begin) +
            ",\"end_cell\":" + std::to_string(r.end) + "}";
  }
  for (const auto& [key, json] : info.extra_meta)
    text += "," + JsonQuote(key) + ":" + json;
  AtomicWriteFile((out / "meta.json").string(), text + "}\n");
}

// OUT/terrain.json for the maps' contours (the scene file's terrain; none
// for a scene without one, i.e. the plane z = 0, or a type the report does
// not draw).
void WriteAtlasTerrain(const AtlasSpec& spec, const fs::path& out) {
  const YAML::Node root = yaml::LoadYamlFile(spec.scene_path);
  TerrainSpec terrain;  // default: the plane z = 0
  if (auto n = yaml::Child(root, "terrain"))
    terrain = yaml::ReadTerrainSpec(
        *n, "terrain", fs::path(spec.scene_path).parent_path().string());
  const std::string json = TerrainJson(terrain);
  if (!json.empty()) AtomicWriteFile((out / "terrain.json").string(), json);
}

AtlasAxis AxisFromJson(const JsonValue* v, const std::string& path,
                       const char* key) {
  if (!v || !v->is_array() || v->items().size() != 3)
    throw SceneError(path + ": spec." + key + ": [lo, hi, count] expected");
  return {v->items()[0].number(), v->items()[1].number(),
          static_cast<int>(v->items()[2].number())};
}

}  // namespace

std::map<std::int64_t, std::string> ReadFinishedAtlasRows(
    const AtlasSpec& spec, const std::string& dir) {
  std::map<std::int64_t, std::string> rows;
  const fs::path out(dir);
  std::string text, meta;
  const bool have_csv = ReadTextFile((out / "atlas.csv").string(), &text);
  const std::vector<fs::path> partials = PartialFiles(out);
  if (!have_csv && partials.empty()) return rows;
  if (!ReadTextFile((out / "meta.json").string(), &meta) ||
      meta.find(JsonQuote(CanonicalAtlasKey(spec))) == std::string::npos)
    throw std::invalid_argument(
        "--resume: " + (out / "atlas.csv").string() +
        " belongs to another atlas grid (meta.json key differs from " +
        CanonicalAtlasKey(spec) + ")");
  // A row is the same text in atlas.csv (with a header) and in a partial
  // file (rows as they were finished, none).
  ParseAtlasRows(spec, std::move(text), &rows);
  for (const fs::path& p : partials) {
    std::string partial;
    if (ReadTextFile(p.string(), &partial))
      ParseAtlasRows(spec, std::move(partial), &rows);
  }
  return rows;
}

AtlasPartialFile::AtlasPartialFile(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (fs::is_regular_file(path_, ec)) {
    std::string text;
    if (ReadTextFile(path_, &text) && !text.empty() && text.back() != '\n') {
      WholeLines(&text);
      fs::resize_file(path_, text.size());
    }
  }
  out_.open(path_, std::ios::app);
  if (!out_) throw std::runtime_error(path_ + ": cannot open for writing");
}

void AtlasPartialFile::Append(const std::string& row) {
  out_ << row << '\n' << std::flush;
  if (!out_) throw std::runtime_error(path_ + ": write failed (disk full?)");
}

void BeginAtlasOutput(const AtlasSpec& spec, const std::string& dir,
                      bool resume, const AtlasOutputInfo& info) {
  const fs::path out(dir);
  fs::create_directories(out);
  if (!resume) {  // rows of an earlier run must not be taken for this one's
    // (only files hold rows: a device stays, e.g. /dev/full in a test)
    for (const fs::path& p : PartialFiles(out))
      if (fs::is_regular_file(p)) fs::remove(p);
    fs::remove(out / "atlas.csv");
    fs::remove(out / "edge.csv");
  }
  AtlasSummary s;
  s.cells = spec.CellCount();
  WriteAtlasMeta(spec, out, s, info);  // the key, for a resume
}

AtlasSummary FinishAtlasOutput(const AtlasSpec& spec, const std::string& dir,
                               const std::map<std::int64_t, std::string>& rows,
                               AtlasSummary s, const AtlasOutputInfo& info) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(dir);
  const AtlasCellRange range =
      ShardCells(spec.CellCount(), info.shard_index, info.shard_count);
  std::string csv = AtlasCsvHeader() + "\n";
  std::vector<std::int64_t> ok_cells;
  std::int64_t missing = 0, first_missing = -1;
  for (std::int64_t i = range.begin; i < range.end; ++i) {
    const auto it = rows.find(i);
    if (it == rows.end()) {
      if (missing++ == 0) first_missing = i;
      continue;
    }
    csv += it->second + "\n";
    if (SplitCsvLine(it->second)[kStatusColumn] == "ok") ok_cells.push_back(i);
  }
  if (missing > 0)
    throw std::invalid_argument(
        "atlas: " + std::to_string(missing) + " of " +
        std::to_string(range.end - range.begin) +
        " cells have no row (first: " + std::to_string(first_missing) + ")");
  s.cells = range.end - range.begin;
  s.ok = static_cast<std::int64_t>(ok_cells.size());
  AtomicWriteFile((out / "atlas.csv").string(), csv);
  for (const fs::path& p : PartialFiles(out)) fs::remove(p);
  if (spec.edge_cells > 0 && info.shard_count == 1) {
    EdgeOptions edge;
    edge.cells = spec.edge_cells;
    std::string text = EdgeCsvHeader() + "\n";
    for (const EdgeRow& row :
         RunEdgeStudy(spec, ChooseEdgeCells(ok_cells, edge.cells), edge)) {
      text += EdgeCsvRow(row) + "\n";
      ++s.edge_solves;
    }
    AtomicWriteFile((out / "edge.csv").string(), text);
  }
  s.wall_seconds +=
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  WriteAtlasMeta(spec, out, s, info);
  WriteAtlasTerrain(spec, out);
  return s;
}

std::string AtlasSpecJson(const AtlasSpec& spec) {
  JsonWriter j;
  j.BeginObject();
  j.Key("scene").Value(
      fs::absolute(spec.scene_path).lexically_normal().string());
  for (const auto& [key, a] :
       {std::pair<const char*, AtlasAxis>{"x", spec.x},
        std::pair<const char*, AtlasAxis>{"y", spec.y}}) {
    j.Key(key).BeginArray().Value(a.lo).Value(a.hi).Value(a.count).EndArray();
  }
  j.Key("headings").Value(spec.headings);
  j.Key("modes").BeginArray();
  for (ActuationMode m : spec.modes) j.Value(ToString(m));
  j.EndArray();
  j.Key("edge_cells").Value(spec.edge_cells);
  j.EndObject();
  return j.str();
}

AtlasSpec SpecFromAtlasMeta(const JsonValue& meta, const std::string& path) {
  const JsonValue* v = meta.Find("spec");
  const JsonValue* key = meta.Find("key");
  if (!v || !v->is_object() || !key || !key->is_string())
    throw SceneError(path +
                     ": no atlas spec or key (made by an older quasiroll?)");
  AtlasSpec spec;
  try {
    spec.scene_path = v->Find("scene") ? v->Find("scene")->str() : "";
    spec.x = AxisFromJson(v->Find("x"), path, "x");
    spec.y = AxisFromJson(v->Find("y"), path, "y");
    spec.headings = static_cast<int>(v->Find("headings")->number());
    spec.modes.clear();
    for (const JsonValue& m : v->Find("modes")->items())
      spec.modes.push_back(m.str() == "pvc" ? ActuationMode::kPvc
                                            : ActuationMode::kPaper);
    spec.edge_cells = static_cast<int>(v->Find("edge_cells")->number());
  } catch (const JsonError& e) {
    throw SceneError(path + ": spec: " + e.what());
  }
  spec.scene = LoadScene(spec.scene_path);
  const std::string k = CanonicalAtlasKey(spec);
  if (k != key->str())
    throw SceneError(path + ": key: the spec it records gives " + k +
                     " now (scene file " + spec.scene_path +
                     " changed?), meta.json has " + key->str());
  return spec;
}

AtlasSummary RunAtlas(const AtlasSpec& spec, const AtlasOptions& options) {
  spec.Validate();
  if (options.jobs < 1)
    Fail("--jobs", "must be >= 1, got " + std::to_string(options.jobs));
  if (options.shard_count < 1 || options.shard_index < 0 ||
      options.shard_index >= options.shard_count)
    Fail("--shard", "must be I/N with 0 <= I < N, got " +
                        std::to_string(options.shard_index) + "/" +
                        std::to_string(options.shard_count));
  const auto start = std::chrono::steady_clock::now();
  AtlasOutputInfo info;
  info.jobs = options.jobs;
  info.shard_index = options.shard_index;
  info.shard_count = options.shard_count;
  const std::string out =
      options.shard_count > 1
          ? AtlasShardDir(options.out_dir, options.shard_index,
                          options.shard_count)
          : options.out_dir;
  const AtlasCellRange range =
      ShardCells(spec.CellCount(), options.shard_index, options.shard_count);
  // One writer per directory (bench/io/output_lock.h), held to the end and
  // taken before a resume reads: DIR, or DIR shared and the shard's own.
  const std::vector<OutputLock> locks = LockOutputDirectory(
      options.out_dir, options.shard_count > 1 ? out : "", "--out");
  std::map<std::int64_t, std::string> done;
  if (options.resume) done = ReadFinishedAtlasRows(spec, out);
  BeginAtlasOutput(spec, out, options.resume, info);
  AtlasSummary s;
  std::vector<std::int64_t> todo;
  for (std::int64_t i = range.begin; i < range.end; ++i)
    if (done.count(i))
      ++s.reused;
    else
      todo.push_back(i);
  // Units of work: the cells of one pose (they share its placement).
  const auto nm = static_cast<std::int64_t>(spec.modes.size());
  std::vector<std::vector<std::int64_t>> units;
  for (std::int64_t i : todo)
    if (units.empty() || units.back().back() / nm != i / nm)
      units.push_back({i});
    else
      units.back().push_back(i);
  std::map<std::int64_t, std::string> computed;
  std::atomic<std::size_t> next{0};
  std::int64_t finished = 0;
  std::mutex mutex;
  AtlasPartialFile partial((fs::path(out) / kPartialName).string());
  std::string write_error;
  auto worker = [&] {
    for (std::size_t u = next++; u < units.size(); u = next++) {
      const std::vector<AtlasRow> rows = EvaluateAtlasCells(spec, units[u]);
      std::lock_guard<std::mutex> lock(mutex);
      for (const AtlasRow& row : rows) {
        if (!write_error.empty()) return;
        const std::string& line = computed[row.cell.index] = AtlasCsvRow(row);
        try {
          partial.Append(line);
        } catch (const std::runtime_error& e) {
          write_error = e.what();
          return;
        }
        ++finished;
        if (options.progress &&
            (finished % 256 == 0 || finished == (std::int64_t)todo.size()))
          std::fprintf(stderr, "\ratlas: %lld / %zu cells", (long long)finished,
                       todo.size());
      }
    }
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < options.jobs; ++t) threads.emplace_back(worker);
  worker();
  for (std::thread& t : threads) t.join();
  if (options.progress) std::fprintf(stderr, "\n");
  if (!write_error.empty()) throw std::runtime_error(write_error);
  done.merge(computed);
  s.computed = static_cast<std::int64_t>(todo.size());
  s.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  return FinishAtlasOutput(spec, out, done, s, info);
}

}  // namespace quasiroll::bench
