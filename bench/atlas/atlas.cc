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

AtlasRow EvaluateAtlasCell(const AtlasSpec& spec, const AtlasCell& cell) {
  const auto start = std::chrono::steady_clock::now();
  AtlasRow row;
  row.cell = cell;
  row.mu = spec.scene.mu;
  row.mu_min = row.margin = row.min_normal_force = kNaN;
  row.z = row.roll = row.pitch = kNaN;
  const Scene scene = SceneAt(spec, cell);
  const KinematicModel model(scene.geometry, scene.terrain);
  auto finish = [&](const char* status, std::string detail) {
    row.status = status;
    row.detail = std::move(detail);
    row.wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
            .count();
    return row;
  };
  Configuration theta;
  try {
    theta = SolveInitialConfiguration(model, scene);
  } catch (const GeometryError& e) {
    return finish("no_contact", e.what());
  }
  Mat3 r;
  Vec3 p;
  model.PlatformPose(theta, &r, &p);
  const Vec3 rpy = RpyFromRotation(r);
  row.z = p(2);
  row.roll = rpy(0);
  row.pitch = rpy(1);
  const ValidityReport validity = CheckValidity(model, theta, true);
  if (!validity.ok()) return finish("degenerate_contact", validity.Describe());
  QuasiStaticProblem problem(model, QuasiStaticParameters::FromScene(scene));
  problem.SetConfiguration(theta);
  if (!problem.StaticsFullRank())
    return finish("singular_statics", "the statics rows are rank deficient");
  int critical = -1;
  double fn_min = kNaN;
  row.mu_min = problem.MinimumFriction(&critical, &fn_min);
  row.critical_wheel = critical >= 0 ? critical + 1 : 0;
  row.min_normal_force = fn_min;
  if (std::isinf(row.mu_min)) {
    row.mu_min = kNaN;
    return finish("lift_off", "no statically admissible force without pulling");
  }
  row.margin = scene.mu - row.mu_min;
  return finish("ok", "");
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

namespace {

// Rows appended as cells finish, so that a killed atlas resumes from them;
// removed once atlas.csv is complete.
constexpr const char* kPartialName = "atlas.partial.csv";
// atlas.csv's `status` column (AtlasCsvHeader).
constexpr std::size_t kStatusColumn = 5;

// Rows of an existing atlas.csv (cell index -> the row's text), when its
// meta.json names the same grid; throws when it names another.
std::map<std::int64_t, std::string> ReadFinishedRows(const AtlasSpec& spec,
                                                     const fs::path& out) {
  std::map<std::int64_t, std::string> rows;
  std::string text, partial, meta;
  const bool have_csv = ReadTextFile((out / "atlas.csv").string(), &text);
  const bool have_partial =
      ReadTextFile((out / kPartialName).string(), &partial);
  if (!have_csv && !have_partial) return rows;
  if (!ReadTextFile((out / "meta.json").string(), &meta) ||
      meta.find(CanonicalAtlasKey(spec)) == std::string::npos)
    throw std::invalid_argument(
        "--resume: " + (out / "atlas.csv").string() +
        " belongs to another atlas grid (meta.json key differs from " +
        CanonicalAtlasKey(spec) + ")");
  // Every row is written with its newline: a last line without one was torn
  // by the interruption and is dropped.
  auto whole_lines = [](std::string* t) {
    const std::size_t end = t->rfind('\n');
    t->erase(end == std::string::npos ? 0 : end + 1);
  };
  whole_lines(&text);
  whole_lines(&partial);
  // atlas.csv has a header, the partial file (rows as they were finished)
  // none; a row is the same text in both.
  std::istringstream in(text + partial);
  std::string line;
  const std::int64_t n = spec.CellCount();
  const std::size_t columns = SplitCsvLine(AtlasCsvHeader()).size();
  while (std::getline(in, line)) {
    if (line.empty() || line == AtlasCsvHeader()) continue;
    const std::vector<std::string> fields = SplitCsvLine(line);
    if (fields.size() != columns) continue;
    const std::int64_t index = std::stoll(fields[0]);
    if (index >= 0 && index < n) rows[index] = line;
  }
  return rows;
}

void WriteAtlasMeta(const AtlasSpec& spec, const fs::path& out,
                    const AtlasSummary& s, int jobs) {
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
  j.Key("jobs").Value(jobs);
  j.Key("wall_s").Value(s.wall_seconds);
  j.Key("host").Value(ThisMachine().hostname);
  j.Key("cpu_model").Value(ThisMachine().cpu);
  j.Key("library_versions");
  WriteLibraryVersions(&j);
  j.EndObject();
  AtomicWriteFile((out / "meta.json").string(), j.str() + "\n");
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

}  // namespace

AtlasSummary RunAtlas(const AtlasSpec& spec, const AtlasOptions& options) {
  spec.Validate();
  if (options.jobs < 1)
    Fail("--jobs", "must be >= 1, got " + std::to_string(options.jobs));
  const auto start = std::chrono::steady_clock::now();
  const fs::path out(options.out_dir);
  fs::create_directories(out);
  // One writer per directory (bench/io/output_lock.h), held to the end.
  const auto lock = LockOutputDirectory(out.string(), "", "--out");
  AtlasSummary s;
  s.cells = spec.CellCount();
  std::map<std::int64_t, std::string> done;
  if (options.resume) done = ReadFinishedRows(spec, out);
  s.reused = static_cast<std::int64_t>(done.size());
  std::vector<std::int64_t> todo;
  for (std::int64_t i = 0; i < s.cells; ++i)
    if (!done.count(i)) todo.push_back(i);
  std::vector<std::string> computed(todo.size());
  std::atomic<std::size_t> next{0};
  std::atomic<std::int64_t> finished{0};
  std::mutex progress_mutex;
  WriteAtlasMeta(spec, out, s, options.jobs);  // the key, for a resume
  const std::string partial_path = (out / kPartialName).string();
  std::ofstream partial(partial_path, std::ios::app);
  std::string write_error;
  auto worker = [&] {
    for (std::size_t k = next++; k < todo.size(); k = next++) {
      computed[k] = AtlasCsvRow(EvaluateAtlasCell(spec, CellAt(spec, todo[k])));
      {
        std::lock_guard<std::mutex> lock(progress_mutex);
        partial << computed[k] << '\n' << std::flush;
        if (!partial && write_error.empty())
          write_error = partial_path + ": write failed (disk full?)";
      }
      const std::int64_t f = ++finished;
      if (options.progress &&
          (f % 256 == 0 || f == (std::int64_t)todo.size())) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        std::fprintf(stderr, "\ratlas: %lld / %zu cells", (long long)f,
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
  for (std::size_t k = 0; k < todo.size(); ++k) done[todo[k]] = computed[k];
  s.computed = static_cast<std::int64_t>(todo.size());
  std::string csv = AtlasCsvHeader() + "\n";
  std::vector<std::int64_t> ok_cells;
  for (const auto& [index, line] : done) {
    csv += line + "\n";
    if (SplitCsvLine(line)[kStatusColumn] == "ok") ok_cells.push_back(index);
  }
  s.ok = static_cast<std::int64_t>(ok_cells.size());
  AtomicWriteFile((out / "atlas.csv").string(), csv);
  partial.close();
  fs::remove(partial_path);
  if (spec.edge_cells > 0) {
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
  s.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
          .count();
  WriteAtlasMeta(spec, out, s, options.jobs);
  WriteAtlasTerrain(spec, out);
  return s;
}

}  // namespace quasiroll::bench
