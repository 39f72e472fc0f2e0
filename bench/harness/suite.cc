#include "quasiroll/bench/harness/suite.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "quasiroll/bench/harness/run_request.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll::bench {

namespace fs = std::filesystem;
using yaml::Bounds;
using yaml::Child;
using yaml::Fail;
using yaml::JoinIndex;
using yaml::JoinKey;

std::string ReferenceSettings::Nlp() const {
  if (!nlp.empty()) return nlp;
  RegisterBuiltinNlpSolvers();
  return NlpSolverRegistry::WithRole(BackendRole::kReference);
}

std::string ReferenceSettings::Integrator() {
  RegisterBuiltinIntegrators();
  return IntegratorRegistry::WithRole(BackendRole::kReference);
}

std::string ReferenceSettings::Canonical() const {
  std::ostringstream os;
  os << "reference{analytic=" << (analytic ? 1 : 0)
     << ";dt_divisor=" << dt_divisor << ";substeps=" << substeps
     << ";nlp=" << Nlp() << ";residual_tolerance=" << Num(residual_tolerance)
     << ";coupling=coupled;dae=" << Integrator() << ";rk=rk4}";
  return os.str();
}

RunRequest RunSpec::Request() const {
  RunRequest q;
  q.mu = mu;
  q.eps = eps;
  q.nlp = nlp;
  q.dae = dae;
  q.coupling = coupling;
  q.dt = dt;
  q.t_end = t_end;
  q.tol = tol;
  q.atol = atol;
  q.nlp_tol = nlp_tol;
  q.nlp_max_iter = nlp_max_iter;
  q.substeps = substeps;
  q.contact_check = contact_check;
  q.locate_events = locate_events;
  q.event_points = event_points;
  q.event_tolerance = event_tolerance;
  q.locate_switches = locate_switches;
  q.nlp_options = nlp_options_explicit;
  q.dae_options = dae_options_explicit;
  // Where the group gave the integrator option itself, the shorthand field
  // only mirrors it (the suite refuses both at once): not given twice.
  auto mirrored = [this](const std::string& key) {
    for (const IntegratorShorthand& sh : IntegratorShorthands())
      if (key == sh.key) return dae_options_explicit.count(sh.option) > 0;
    return false;
  };
  if (!mirrored("rk_method")) q.rk_method = rk_method;
  if (!mirrored("sigma")) q.sigma = sigma;
  if (!mirrored("dae_index")) q.dae_index = dae_index;
  return q;
}

namespace {

std::string ReadFileOrEmpty(const std::string& path) {
  std::string text;
  ReadTextFile(path, &text);  // leaves "" when the file cannot be opened
  return text;
}

bool IsSafeName(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'))
      return false;
  return s != "." && s != "..";
}

std::string ReadSafeName(const YAML::Node& node, const std::string& path) {
  const std::string s = yaml::ReadString(node, path);
  if (!IsSafeName(s))
    Fail(path, "must be 1-64 characters of [A-Za-z0-9_.], got \"" + s + "\"");
  return s;
}

// A scalar or a sequence of scalars, each read by `read`; an empty sequence
// is an error ("empty grid").
template <typename T, typename Reader>
std::vector<T> ReadAxis(const YAML::Node& node, const std::string& path,
                        Reader read) {
  std::vector<T> out;
  if (node.IsSequence()) {
    if (node.size() == 0) Fail(path, "empty grid axis, got []");
    for (std::size_t i = 0; i < node.size(); ++i)
      out.push_back(read(node[i], JoinIndex(path, i)));
  } else if (node.IsScalar()) {
    out.push_back(read(node, path));
  } else {
    Fail(path, "expected a value or a non-empty sequence, got " +
                   yaml::DescribeNode(node));
  }
  return out;
}

void CheckNoDuplicates(const std::vector<std::string>& canon,
                       const std::string& path) {
  std::set<std::string> seen;
  for (std::size_t i = 0; i < canon.size(); ++i)
    if (!seen.insert(canon[i]).second)
      Fail(JoinIndex(path, i), "duplicate grid value, got " + canon[i]);
}

std::vector<double> ReadDoubleAxis(const YAML::Node& map,
                                   const std::string& path,
                                   std::string_view key, const Bounds& b,
                                   std::vector<double> fallback) {
  auto n = Child(map, key);
  if (!n) return fallback;
  const std::string p = JoinKey(path, key);
  std::vector<double> v =
      ReadAxis<double>(*n, p, [&b](const YAML::Node& x, const std::string& xp) {
        return yaml::ReadDouble(x, xp, b);
      });
  std::vector<std::string> canon;
  for (double d : v) canon.push_back(Num(d));
  if (n->IsSequence()) CheckNoDuplicates(canon, p);
  return v;
}

std::vector<std::string> ReadNameAxis(const YAML::Node& map,
                                      const std::string& path,
                                      std::string_view key,
                                      const std::vector<std::string>& known,
                                      std::vector<std::string> fallback) {
  auto n = Child(map, key);
  if (!n) return fallback;
  const std::string p = JoinKey(path, key);
  std::vector<std::string> v = ReadAxis<std::string>(
      *n, p, [&known](const YAML::Node& x, const std::string& xp) {
        const std::string s = yaml::ReadString(x, xp);
        bool ok = false;
        for (const std::string& k : known) ok = ok || k == s;
        if (!ok) {
          std::string list;
          for (const std::string& k : known)
            list += (list.empty() ? "" : ", ") + k;
          Fail(xp, "unknown name (known: " + list + "), got \"" + s + "\"");
        }
        return s;
      });
  if (n->IsSequence()) CheckNoDuplicates(v, p);
  return v;
}

std::vector<std::int64_t> ReadIntAxis(const YAML::Node& map,
                                      const std::string& path,
                                      std::string_view key, std::int64_t lo,
                                      std::int64_t hi,
                                      std::vector<std::int64_t> fallback) {
  auto n = Child(map, key);
  if (!n) return fallback;
  const std::string p = JoinKey(path, key);
  std::vector<std::int64_t> v = ReadAxis<std::int64_t>(
      *n, p, [lo, hi](const YAML::Node& x, const std::string& xp) {
        return yaml::ReadInt(x, xp, lo, hi);
      });
  std::vector<std::string> canon;
  for (auto d : v) canon.push_back(std::to_string(d));
  if (n->IsSequence()) CheckNoDuplicates(canon, p);
  return v;
}

SuiteScene ReadSuiteScene(const YAML::Node& node, const std::string& path,
                          const std::string& base_dir) {
  yaml::CheckKeys(node, path, {"name", "file", "overrides"});
  SuiteScene s;
  s.entry_path = path;
  const YAML::Node file_node = yaml::Require(node, path, "file");
  const std::string file_path = JoinKey(path, "file");
  const std::string rel = yaml::ReadString(file_node, file_path);
  s.file = fs::path(rel).is_absolute() || base_dir.empty()
               ? rel
               : (fs::path(base_dir) / rel).lexically_normal().string();
  const std::string text = ReadFileOrEmpty(s.file);
  {
    std::ifstream probe(s.file);
    if (!probe)
      Fail(file_path, "cannot open scene file, got \"" + s.file + "\"");
  }
  const std::string file_dir = fs::path(s.file).parent_path().string();
  // The file, parsed once as a node so that its terrain spec is available.
  YAML::Node root;
  try {
    root = yaml::ParseYaml(text, s.file);
    s.scene.source_path = s.file;
    s.scene.name = fs::path(s.file).stem().string();
    yaml::ReadSceneNode(root, "", file_dir, &s.scene);
    s.terrain = TerrainSpec{};
    if (auto t = Child(root, "terrain"))
      s.terrain = yaml::ReadTerrainSpec(*t, "terrain", file_dir);
  } catch (const SceneError& e) {
    Fail(file_path, std::string("in \"") + s.file + "\": " + e.what());
  }
  if (auto ov = Child(node, "overrides")) {
    const std::string op = JoinKey(path, "overrides");
    yaml::ReadSceneNode(*ov, op, base_dir, &s.scene);
    if (auto t = Child(*ov, "terrain"))
      s.terrain = yaml::ReadTerrainSpec(*t, JoinKey(op, "terrain"), base_dir);
  }
  if (auto n = Child(node, "name")) {
    s.name = ReadSafeName(*n, JoinKey(path, "name"));
  } else {
    s.name = s.scene.name;
    if (!IsSafeName(s.name))
      Fail(JoinKey(path, "name"),
           "required when the scene's name is not of [A-Za-z0-9_.], got \"" +
               s.name + "\"");
  }
  if (s.terrain.type == TerrainSpec::Type::kHeightmap)
    s.heightmap_digest = Hex64(Fnv1a64(ReadFileOrEmpty(s.terrain.file)));
  return s;
}

ReferenceSettings ReadReference(const YAML::Node& node,
                                const std::string& path) {
  yaml::CheckKeys(
      node, path,
      {"analytic", "dt_divisor", "substeps", "nlp", "residual_tolerance"});
  ReferenceSettings r;
  if (auto n = Child(node, "analytic"))
    r.analytic = yaml::ReadEnum(*n, JoinKey(path, "analytic"),
                                {"true", "false"}) == "true";
  if (auto n = Child(node, "dt_divisor"))
    r.dt_divisor = static_cast<int>(
        yaml::ReadInt(*n, JoinKey(path, "dt_divisor"), 1, 1000));
  if (auto n = Child(node, "substeps"))
    r.substeps =
        static_cast<int>(yaml::ReadInt(*n, JoinKey(path, "substeps"), 1, 1000));
  if (auto n = Child(node, "nlp")) {
    r.nlp = yaml::ReadString(*n, JoinKey(path, "nlp"));
    if (!NlpSolverRegistry::Has(r.nlp))
      Fail(JoinKey(path, "nlp"), "unknown NLP backend, got \"" + r.nlp + "\"");
  }
  yaml::ReadOptionalDouble(node, path, "residual_tolerance",
                           &r.residual_tolerance, Bounds::Positive());
  return r;
}

RunBounds ReadBounds(const YAML::Node& node, const std::string& path,
                     RunBounds bounds) {
  if (!node.IsMap())
    Fail(path,
         "expected a mapping {drift: ..., gap: ..., qs_inertia: ...}, got " +
             yaml::DescribeNode(node));
  yaml::CheckKeys(node, path, {"drift", "gap", "qs_inertia"});
  yaml::ReadOptionalDouble(node, path, "drift", &bounds.drift,
                           Bounds::Positive());
  yaml::ReadOptionalDouble(node, path, "gap", &bounds.gap, Bounds::Positive());
  yaml::ReadOptionalDouble(node, path, "qs_inertia", &bounds.qs_inertia,
                           Bounds::Positive());
  return bounds;
}

std::string CanonicalRunKey(const RunSpec& r) {
  std::ostringstream os;
  os << "group=" << r.group << ";scene=" << r.scene << ";nlp=" << r.nlp
     << ";dae=" << r.dae << ";coupling=" << ToString(r.coupling)
     << ";rk=" << r.rk_method << ";dt=" << Num(r.dt) << ";tol=" << Num(r.tol)
     << ";atol=" << Num(r.atol) << ";nlp_tol=" << Num(r.nlp_tol)
     << ";sigma=" << Num(r.sigma) << ";eps=" << Num(r.eps)
     << ";dae_index=" << r.dae_index << ";substeps=" << r.substeps
     << ";contact_check=" << r.contact_check << ";mu=" << Num(r.mu)
     << ";seed=" << (r.seed ? std::to_string(*r.seed) : "-")
     << ";roughness=" << Num(r.roughness) << ";t_end=" << Num(r.t_end)
     << ";repeats=" << r.repeats;
  // Keys added after the original fixed grid appear only when they differ
  // from their default, and generic axes only when a group has them, so the
  // keys (and run ids) of existing suites stay those of the fixed grid.
  if (r.nlp_max_iter != QuasiStaticOptions{}.max_iterations)
    os << ";nlp_max_iter=" << r.nlp_max_iter;
  const SimulationOptions events;  // the located-stop defaults
  if (r.locate_events != events.locate_events)
    os << ";locate_events=" << (r.locate_events ? 1 : 0);
  if (r.event_points != events.event_points)
    os << ";event_points=" << r.event_points;
  if (r.event_tolerance != events.event_tolerance)
    os << ";event_tolerance=" << Num(r.event_tolerance);
  if (r.locate_switches != events.locate_switches)
    os << ";locate_switches=" << (r.locate_switches ? 1 : 0);
  if (r.exclusive) os << ";exclusive=1";
  for (const auto& [field, value] : r.scene_fields)
    os << ";scene." << field << "=" << value;
  for (const auto& [name, value] : r.nlp_options_explicit)
    os << ";nlp_options." << name << "=" << value;
  for (const auto& [name, value] : r.dae_options_explicit)
    os << ";dae_options." << name << "=" << value;
  // Likewise non-default verdict bounds (they change the row, not the run).
  const RunBounds defaults;
  if (r.bounds.drift != defaults.drift || r.bounds.gap != defaults.gap)
    os << ";bounds=" << Num(r.bounds.drift) << "," << Num(r.bounds.gap);
  if (r.bounds.qs_inertia != defaults.qs_inertia)
    os << ";bounds.qs_inertia=" << Num(r.bounds.qs_inertia);
  if (r.checkpoint_interval != kDefaultCheckpointInterval)
    os << ";checkpoint_interval=" << Num(r.checkpoint_interval);
  return os.str();
}

// ------------------------------------------------------------ grid axes ----
//
// A group's runs are the Cartesian product of its axes, the last axis
// varying fastest. Each axis value carries its canonical text (duplicate
// check) and how it sets a RunSpec.
struct AxisValue {
  std::string canon;
  std::function<void(RunSpec*)> apply;
};
struct Axis {
  std::string key;
  std::vector<AxisValue> values;
};

template <typename T, typename Set>
Axis MakeAxis(std::string key, const std::vector<T>& values, Set set) {
  Axis axis{std::move(key), {}};
  for (const T& v : values)
    axis.values.push_back({std::string(), [set, v](RunSpec* r) { set(r, v); }});
  return axis;
}

// Scene fields that can be swept through `scene_fields` (dotted paths of the
// scene schema, docs/scenes.md). The others have group keys of their own
// (mu, eps, t_end, dt, seed, roughness) or are not numbers of the motion.
const std::vector<std::string>& SweepableSceneFields() {
  static const std::vector<std::string> fields = {"mode",
                                                  "mass",
                                                  "gravity",
                                                  "joint_rates",
                                                  "robot.a",
                                                  "robot.b",
                                                  "robot.track",
                                                  "robot.z_h",
                                                  "robot.major_radius",
                                                  "robot.tube_radius",
                                                  "robot.camber_offset",
                                                  "initial.x",
                                                  "initial.y",
                                                  "initial.yaw",
                                                  "initial.joint_angles"};
  return fields;
}

// {a: {b: value}} for the dotted path "a.b".
YAML::Node SceneFieldNode(const std::string& field, const YAML::Node& value) {
  YAML::Node root(YAML::NodeType::Map);
  const std::size_t dot = field.find('.');
  if (dot == std::string::npos) {
    root[field] = value;
  } else {
    YAML::Node inner(YAML::NodeType::Map);
    inner[field.substr(dot + 1)] = value;
    root[field.substr(0, dot)] = inner;
  }
  return root;
}

std::string FlowText(const YAML::Node& node) {
  YAML::Emitter e;
  e << YAML::Flow << node;
  return e.c_str();
}

// Applies the swept scene fields of a run ("<path>" -> YAML flow text).
void ApplySceneFields(
    const std::vector<std::pair<std::string, std::string>>& fields,
    Scene* scene) {
  for (const auto& [field, text] : fields)
    yaml::ReadSceneNode(SceneFieldNode(field, YAML::Load(text)), "", "", scene);
}

// The `scene_fields` mapping: dotted scene path -> a value or a sequence of
// values (a field whose value is itself a sequence, e.g. joint_rates, is
// swept by a sequence of sequences). One axis per field, in file order.
std::vector<Axis> ReadSceneFieldAxes(const YAML::Node& node,
                                     const std::string& path,
                                     const std::vector<int>& scene_idx,
                                     const Suite& suite) {
  std::vector<Axis> axes;
  auto map = Child(node, "scene_fields");
  if (!map) return axes;
  const std::string mp = JoinKey(path, "scene_fields");
  if (!map->IsMap() || map->size() == 0)
    Fail(mp, "expected a non-empty mapping of scene fields to values, got " +
                 yaml::DescribeNode(*map));
  const auto& allowed = SweepableSceneFields();
  for (auto it = map->begin(); it != map->end(); ++it) {
    const std::string field = it->first.as<std::string>();
    const std::string fp = JoinKey(mp, field);
    if (std::find(allowed.begin(), allowed.end(), field) == allowed.end()) {
      std::string hint;
      if (field == "mu") hint = " (use the group key mu)";
      if (field == "epsilon") hint = " (use the group key eps)";
      if (field == "time.dt" || field == "time.t_end")
        hint = " (use the group keys dt / t_end)";
      if (field.rfind("terrain", 0) == 0)
        hint = " (use seed / roughness, or a scene entry per terrain)";
      std::string list;
      for (const std::string& a : allowed)
        list += (list.empty() ? "" : ", ") + a;
      Fail(fp, "not a sweepable scene field" + hint + " (allowed: " + list +
                   "), got \"" + field + "\"");
    }
    std::vector<YAML::Node> values;
    const YAML::Node v = it->second;
    if (v.IsSequence()) {
      if (v.size() == 0) Fail(fp, "empty grid axis, got []");
      for (std::size_t i = 0; i < v.size(); ++i) values.push_back(v[i]);
    } else if (v.IsScalar()) {
      values.push_back(v);
    } else {
      Fail(fp, "expected a value or a non-empty sequence, got " +
                   yaml::DescribeNode(v));
    }
    Axis axis{"scene_fields." + field, {}};
    std::vector<std::string> canon;
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::string vp = v.IsSequence() ? JoinIndex(fp, i) : fp;
      const std::string text = FlowText(values[i]);
      // Checked on every scene of the group, with the scene loader's rules.
      for (int si : scene_idx) {
        Scene probe = suite.scenes[si].scene;
        try {
          yaml::ReadSceneNode(SceneFieldNode(field, values[i]), "", "", &probe);
        } catch (const SceneError& e) {
          Fail(vp, "for scene \"" + suite.scenes[si].name + "\": " + e.what());
        }
      }
      canon.push_back(text);
      axis.values.push_back({text, [field, text](RunSpec* r) {
                               r->scene_fields.emplace_back(field, text);
                             }});
    }
    if (v.IsSequence()) CheckNoDuplicates(canon, fp);
    axes.push_back(std::move(axis));
  }
  return axes;
}

// Option tables of backends by registry name (created once per load).
class OptionTables {
 public:
  const OptionTable& Nlp(const std::string& name) {
    return Find<NlpSolverRegistry>(name, &nlp_);
  }
  const OptionTable& Dae(const std::string& name) {
    return Find<IntegratorRegistry>(name, &dae_);
  }

 private:
  template <typename Registry>
  static const OptionTable& Find(const std::string& name,
                                 std::map<std::string, OptionTable>* tables) {
    auto it = tables->find(name);
    if (it == tables->end())
      it = tables->emplace(name, Registry::Create(name)->option_table()).first;
    return it->second;
  }

  std::map<std::string, OptionTable> nlp_, dae_;
};

// The `nlp_options` / `dae_options` mapping of a group: option name -> a
// value or a sequence of values (an axis). Every option must be in the table
// of every backend of the group, and every value valid for each of them.
std::vector<Axis> ReadOptionAxes(
    const YAML::Node& node, const std::string& path, const std::string& key,
    const std::vector<std::string>& backends,
    const std::function<const OptionTable&(const std::string&)>& table_of,
    const std::string& kind) {
  std::vector<Axis> axes;
  auto map = Child(node, key);
  if (!map) return axes;
  const std::string mp = JoinKey(path, key);
  if (!map->IsMap() || map->size() == 0)
    Fail(mp, "expected a non-empty mapping of option names to values, got " +
                 yaml::DescribeNode(*map));
  const bool nlp = key == "nlp_options";
  for (auto it = map->begin(); it != map->end(); ++it) {
    const std::string name = it->first.as<std::string>();
    const std::string op = JoinKey(mp, name);
    for (const std::string& b : backends) {
      if (FindOption(table_of(b), name) == nullptr) {
        const std::string known = OptionNames(table_of(b));
        Fail(op, "unknown option of " + kind + " '" + b +
                     "' (known: " + (known.empty() ? "none" : known) +
                     "), got \"" + name + "\"");
      }
    }
    const YAML::Node v = it->second;
    std::vector<std::string> texts;
    if (v.IsSequence()) {
      if (v.size() == 0) Fail(op, "empty grid axis, got []");
      for (std::size_t i = 0; i < v.size(); ++i)
        texts.push_back(yaml::ReadString(v[i], JoinIndex(op, i)));
    } else {
      texts.push_back(yaml::ReadString(v, op));
    }
    Axis axis{key + "." + name, {}};
    for (std::size_t i = 0; i < texts.size(); ++i) {
      const std::string vp = v.IsSequence() ? JoinIndex(op, i) : op;
      for (const std::string& b : backends) {
        try {
          ParseOptionValue(*FindOption(table_of(b), name), texts[i],
                           kind + " '" + b + "'");
        } catch (const std::invalid_argument& e) {
          Fail(vp, e.what());
        }
      }
      const std::string text = texts[i];
      axis.values.push_back({text, [nlp, name, text](RunSpec* r) {
                               (nlp ? r->nlp_options_explicit
                                    : r->dae_options_explicit)[name] = text;
                             }});
    }
    if (v.IsSequence()) CheckNoDuplicates(texts, op);
    axes.push_back(std::move(axis));
  }
  return axes;
}

// The suite's side of the shorthand keys (rk_method, sigma, dae_index):
// they have defaults that are part of every run key, so a shorthand given
// as a group key and also as its integrator option is refused here (the
// request would see the default as given too), and an explicit integrator
// option sets the shorthand's field so that the runs.csv column keeps its
// meaning. Mapping them onto the options is ResolveRunRequest's.
void ReconcileShorthands(const YAML::Node& group_node, const std::string& path,
                         RunSpec* r) {
  for (const IntegratorShorthand& sh : IntegratorShorthands()) {
    const auto it = r->dae_options_explicit.find(sh.option);
    if (it == r->dae_options_explicit.end()) continue;
    const std::string key = sh.key;
    if (Child(group_node, key))
      Fail(JoinKey(JoinKey(path, "dae_options"), sh.option),
           "given twice: also as the group key " + key + ", got \"" +
               it->second + "\"");
    if (key == "rk_method") r->rk_method = it->second;
    if (key == "sigma") r->sigma = std::stod(it->second);
    if (key == "dae_index") r->dae_index = std::stoi(it->second);
  }
}

// The run's request resolved as every front end resolves one; a problem
// is a SceneError naming the group's keys.
ResolvedRun ResolveGroupRun(const std::string& path, const Scene& base,
                            const RunSpec& r) {
  try {
    return ResolveRunRequest(base, r.Request(), [&path](const std::string& k) {
      return JoinKey(path, k);
    });
  } catch (const std::invalid_argument& e) {
    throw SceneError(e.what());
  }
}

// The group's own keys, read once: the value lists of the grid axes plus the
// per-group settings. An empty dts / epss / mus means "the scene's value".
struct GroupSpec {
  std::vector<int> scene_idx;
  std::vector<std::string> nlps, daes, couplings, rks;
  std::vector<double> tols;
  double atol_ratio = 1e-2;
  std::vector<double> nlp_tols, sigmas;
  std::vector<std::int64_t> dae_indices, substeps, contact_checks;
  std::vector<std::int64_t> nlp_max_iters;
  std::vector<std::string> locate_events;
  std::vector<std::int64_t> event_points;
  std::vector<double> event_tolerances;
  std::vector<std::string> locate_switches;
  std::vector<double> roughness;
  std::vector<double> dts, epss, mus;
  std::vector<std::uint64_t> seeds;
  double t_end_override = 0;
  int repeats = 1;
  bool exclusive = false;
  std::vector<Axis> generic_axes;  // scene_fields, nlp_options, dae_options
  RunBounds bounds;
  double checkpoint_interval = kDefaultCheckpointInterval;
};

// Scenes of the group (default: all of the suite's), as suite indices in the
// order the group names them.
std::vector<int> ReadGroupScenes(const YAML::Node& node,
                                 const std::string& path, const Suite& suite) {
  std::vector<int> scene_idx;
  if (auto n = Child(node, "scenes")) {
    std::vector<std::string> names;
    for (const SuiteScene& s : suite.scenes) names.push_back(s.name);
    for (const std::string& s : ReadNameAxis(node, path, "scenes", names, {})) {
      for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i] == s) scene_idx.push_back(static_cast<int>(i));
    }
  } else {
    for (std::size_t i = 0; i < suite.scenes.size(); ++i)
      scene_idx.push_back(static_cast<int>(i));
  }
  if (scene_idx.empty()) Fail(JoinKey(path, "scenes"), "no scenes, got none");
  return scene_idx;
}

// Method axes with fixed defaults (backends, tolerances, integrator knobs).
void ReadMethodAxes(const YAML::Node& node, const std::string& path,
                    GroupSpec* g) {
  g->nlps = ReadNameAxis(node, path, "nlp", NlpSolverRegistry::Names(),
                         {NlpSolverRegistry::WithRole(BackendRole::kDefault)});
  g->daes = ReadNameAxis(node, path, "dae", IntegratorRegistry::Names(),
                         {IntegratorRegistry::WithRole(BackendRole::kDefault)});
  g->couplings =
      ReadNameAxis(node, path, "coupling", {"zoh", "coupled"}, {"zoh"});
  g->rks =
      ReadNameAxis(node, path, "rk_method", {"rk4", "dp54", "bs32"}, {"rk4"});
  g->tols = ReadDoubleAxis(node, path, "tol", Bounds::Positive(), {1e-8});
  yaml::ReadOptionalDouble(node, path, "atol_ratio", &g->atol_ratio,
                           Bounds::Positive());
  g->nlp_tols =
      ReadDoubleAxis(node, path, "nlp_tol", Bounds::Positive(), {1e-12});
  g->sigmas = ReadDoubleAxis(node, path, "sigma", Bounds::NonNegative(), {5.0});
  g->dae_indices = ReadIntAxis(node, path, "dae_index", 1, 2, {2});
  g->substeps = ReadIntAxis(node, path, "substeps", 1, 100000, {1});
  g->contact_checks = ReadIntAxis(node, path, "contact_check", 0, 1000000, {0});
  g->nlp_max_iters = ReadIntAxis(node, path, "nlp_max_iter", 1, 1000000,
                                 {QuasiStaticOptions{}.max_iterations});
  const SimulationOptions defaults;
  g->locate_events =
      ReadNameAxis(node, path, "locate_events", {"true", "false"}, {"true"});
  g->locate_switches =
      ReadNameAxis(node, path, "locate_switches", {"true", "false"}, {"true"});
  g->event_points =
      ReadIntAxis(node, path, "event_points", 0, 1000, {defaults.event_points});
  g->event_tolerances =
      ReadDoubleAxis(node, path, "event_tolerance", Bounds::Positive(),
                     {defaults.event_tolerance});
  g->roughness =
      ReadDoubleAxis(node, path, "roughness", Bounds::NonNegative(), {1.0});
}

// Axes and settings whose default depends on the scene (empty = scene's),
// then the repeat count. Duplicate seeds are rejected like any axis's.
void ReadSceneDefaultedAxes(const YAML::Node& node, const std::string& path,
                            GroupSpec* g) {
  g->dts = ReadDoubleAxis(node, path, "dt", Bounds::Positive(), {});
  g->epss = ReadDoubleAxis(node, path, "eps", Bounds::Positive(), {});
  g->mus = ReadDoubleAxis(node, path, "mu", Bounds::Positive(), {});
  if (auto n = Child(node, "seed")) {
    const std::string p = JoinKey(path, "seed");
    g->seeds = ReadAxis<std::uint64_t>(
        *n, p, [](const YAML::Node& x, const std::string& xp) {
          return yaml::ReadUint64(x, xp);
        });
    std::vector<std::string> canon;
    for (auto s : g->seeds) canon.push_back(std::to_string(s));
    if (n->IsSequence()) CheckNoDuplicates(canon, p);
  }
  yaml::ReadOptionalDouble(node, path, "t_end", &g->t_end_override,
                           Bounds::Positive());
  if (auto n = Child(node, "repeats"))
    g->repeats =
        static_cast<int>(yaml::ReadInt(*n, JoinKey(path, "repeats"), 1, 1000));
  if (auto n = Child(node, "exclusive"))
    g->exclusive = yaml::ReadEnum(*n, JoinKey(path, "exclusive"),
                                  {"true", "false"}) == "true";
}

// Generic axes in file order: scene fields, then backend options (validated
// against the option tables of every backend of the group).
void ReadGenericAxes(const YAML::Node& node, const std::string& path,
                     const Suite& suite, OptionTables* tables, GroupSpec* g) {
  g->generic_axes = ReadSceneFieldAxes(node, path, g->scene_idx, suite);
  // The NLP, then the integrator options.
  struct OptionAxes {
    const char* key;
    const std::vector<std::string>& backends;
    const OptionTable& (OptionTables::*table)(const std::string&);
    const char* role;
  };
  for (const OptionAxes& k :
       {OptionAxes{"nlp_options", g->nlps, &OptionTables::Nlp, "NLP backend"},
        OptionAxes{"dae_options", g->daes, &OptionTables::Dae, "integrator"}}) {
    auto table = [&](const std::string& b) -> const OptionTable& {
      return (tables->*k.table)(b);
    };
    for (Axis& a : ReadOptionAxes(node, path, k.key, k.backends, table, k.role))
      g->generic_axes.push_back(std::move(a));
  }
}

// Reads and checks every key of a group. The order of the reads is the order
// in which errors are reported, so it is part of the behaviour.
// A backend option named like a run setting would act next to the run's own
// setting (run_request.h): such a backend cannot be run.
void RequireNoShadowedRunSettings(const std::string& path, const GroupSpec& g,
                                  OptionTables* tables) {
  auto check = [&](const char* key, const std::string& name,
                   const OptionTable& table) {
    const std::string shadowed = ShadowedRunSetting(table);
    if (!shadowed.empty())
      Fail(JoinKey(path, key),
           "backend '" + name +
               "' declares an option named like the run "
               "setting " +
               shadowed +
               " (a backend option may not shadow a run setting), got '" +
               shadowed + "'");
  };
  for (const std::string& n : g.nlps) check("nlp", n, tables->Nlp(n));
  for (const std::string& n : g.daes) check("dae", n, tables->Dae(n));
}

GroupSpec ReadGroupSpec(const YAML::Node& node, const std::string& path,
                        const Suite& suite, OptionTables* tables) {
  yaml::CheckKeys(node, path,
                  {"description",
                   "scenes",
                   "nlp",
                   "dae",
                   "coupling",
                   "rk_method",
                   "dt",
                   "tol",
                   "atol_ratio",
                   "nlp_tol",
                   "sigma",
                   "eps",
                   "mu",
                   "seed",
                   "roughness",
                   "dae_index",
                   "substeps",
                   "contact_check",
                   "t_end",
                   "repeats",
                   "scene_fields",
                   "nlp_options",
                   "dae_options",
                   "bounds",
                   "nlp_max_iter",
                   "locate_events",
                   "event_points",
                   "event_tolerance",
                   "checkpoint_interval",
                   "locate_switches",
                   "exclusive"});
  if (auto n = Child(node, "description"))
    yaml::ReadString(*n, JoinKey(path, "description"));
  GroupSpec g;
  g.scene_idx = ReadGroupScenes(node, path, suite);
  ReadMethodAxes(node, path, &g);
  RequireNoShadowedRunSettings(path, g, tables);
  ReadSceneDefaultedAxes(node, path, &g);
  ReadGenericAxes(node, path, suite, tables, &g);
  g.bounds = suite.bounds;
  if (auto n = Child(node, "bounds"))
    g.bounds = ReadBounds(*n, JoinKey(path, "bounds"), g.bounds);
  g.checkpoint_interval = suite.checkpoint_interval;
  yaml::ReadOptionalDouble(node, path, "checkpoint_interval",
                           &g.checkpoint_interval, Bounds::Positive());
  return g;
}

// The group's scene-defaulted axes resolved for one scene.
struct SceneAxes {
  double t_end = 0;
  std::vector<double> dts, eps, mu;
  std::vector<std::optional<std::uint64_t>> seeds;
};

// Resolves the scene-defaulted axes for `sc` and rejects settings the scene
// cannot take (a seed without a random terrain, roughness without gaussians,
// a step longer than the run).
SceneAxes ResolveSceneAxes(const std::string& path, const GroupSpec& g,
                           const SuiteScene& sc, const std::string& scene_ref) {
  if (!g.seeds.empty() && !sc.random_terrain())
    Fail(JoinKey(path, "seed"), scene_ref +
                                    " has no random gaussian terrain, got " +
                                    std::to_string(g.seeds.front()));
  for (double r : g.roughness)
    if (r != 1.0 && !sc.gaussian_terrain())
      Fail(JoinKey(path, "roughness"),
           scene_ref + " has no gaussian terrain (roughness must be 1), got " +
               Num(r));
  SceneAxes s;
  s.t_end = g.t_end_override > 0 ? g.t_end_override : sc.scene.t_end;
  s.dts = g.dts.empty() ? std::vector<double>{sc.scene.dt} : g.dts;
  for (std::size_t i = 0; i < s.dts.size(); ++i)
    if (s.dts[i] > s.t_end)
      Fail(g.dts.empty() ? JoinKey(path, "t_end")
                         : JoinIndex(JoinKey(path, "dt"), i),
           "dt must be <= t_end (" + Num(s.t_end) + ") of " + scene_ref +
               ", got " + Num(s.dts[i]));
  s.eps = g.epss.empty() ? std::vector<double>{sc.scene.epsilon} : g.epss;
  s.mu = g.mus.empty() ? std::vector<double>{sc.scene.mu} : g.mus;
  if (!g.seeds.empty()) {
    for (auto seed : g.seeds) s.seeds.emplace_back(seed);
  } else if (sc.random_terrain()) {
    s.seeds.emplace_back(sc.terrain.random->seed);
  } else {
    s.seeds.emplace_back(std::nullopt);
  }
  return s;
}

// Axes in grid order (docs/harness.md): the order of the original nested
// loops, then the generic axes in file order. The order fixes run indices and
// so is part of the output.
std::vector<Axis> GridAxes(const GroupSpec& g, const SceneAxes& s) {
  std::vector<Axis> axes;
  axes.push_back(MakeAxis("mu", s.mu, [](RunSpec* r, double v) { r->mu = v; }));
  axes.push_back(MakeAxis(
      "seed", s.seeds,
      [](RunSpec* r, const std::optional<std::uint64_t>& v) { r->seed = v; }));
  axes.push_back(MakeAxis("roughness", g.roughness,
                          [](RunSpec* r, double v) { r->roughness = v; }));
  axes.push_back(
      MakeAxis("eps", s.eps, [](RunSpec* r, double v) { r->eps = v; }));
  axes.push_back(MakeAxis(
      "nlp", g.nlps, [](RunSpec* r, const std::string& v) { r->nlp = v; }));
  axes.push_back(MakeAxis(
      "dae", g.daes, [](RunSpec* r, const std::string& v) { r->dae = v; }));
  axes.push_back(
      MakeAxis("coupling", g.couplings, [](RunSpec* r, const std::string& v) {
        r->coupling = CouplingFromString(v);
      }));
  axes.push_back(
      MakeAxis("rk_method", g.rks,
               [](RunSpec* r, const std::string& v) { r->rk_method = v; }));
  axes.push_back(MakeAxis(
      "dae_index", g.dae_indices,
      [](RunSpec* r, std::int64_t v) { r->dae_index = static_cast<int>(v); }));
  axes.push_back(
      MakeAxis("sigma", g.sigmas, [](RunSpec* r, double v) { r->sigma = v; }));
  const double atol_ratio = g.atol_ratio;
  axes.push_back(MakeAxis("tol", g.tols, [atol_ratio](RunSpec* r, double v) {
    r->tol = v;
    r->atol = v * atol_ratio;
  }));
  axes.push_back(MakeAxis("nlp_tol", g.nlp_tols,
                          [](RunSpec* r, double v) { r->nlp_tol = v; }));
  axes.push_back(
      MakeAxis("dt", s.dts, [](RunSpec* r, double v) { r->dt = v; }));
  axes.push_back(MakeAxis(
      "substeps", g.substeps,
      [](RunSpec* r, std::int64_t v) { r->substeps = static_cast<int>(v); }));
  axes.push_back(MakeAxis("contact_check", g.contact_checks,
                          [](RunSpec* r, std::int64_t v) {
                            r->contact_check = static_cast<int>(v);
                          }));
  axes.push_back(
      MakeAxis("nlp_max_iter", g.nlp_max_iters, [](RunSpec* r, std::int64_t v) {
        r->nlp_max_iter = static_cast<int>(v);
      }));
  axes.push_back(MakeAxis("locate_events", g.locate_events,
                          [](RunSpec* r, const std::string& v) {
                            r->locate_events = v == "true";
                          }));
  axes.push_back(
      MakeAxis("event_points", g.event_points, [](RunSpec* r, std::int64_t v) {
        r->event_points = static_cast<int>(v);
      }));
  axes.push_back(
      MakeAxis("event_tolerance", g.event_tolerances,
               [](RunSpec* r, double v) { r->event_tolerance = v; }));
  axes.push_back(MakeAxis("locate_switches", g.locate_switches,
                          [](RunSpec* r, const std::string& v) {
                            r->locate_switches = v == "true";
                          }));
  for (const Axis& a : g.generic_axes) axes.push_back(a);
  return axes;
}

// Appends one run per point of the grid spanned by `axes` to suite->runs,
// each completed (options, key, id) and checked.
void AppendGridRuns(const YAML::Node& node, const std::string& path,
                    const RunSpec& base, const std::string& scene_ref,
                    const std::vector<Axis>& axes, Suite* suite) {
  std::vector<std::size_t> at(axes.size(), 0);
  for (bool more = true; more;) {
    RunSpec r = base;
    for (std::size_t k = 0; k < axes.size(); ++k)
      axes[k].values[at[k]].apply(&r);
    r.index = static_cast<int>(suite->runs.size());
    ReconcileShorthands(node, path, &r);
    const ResolvedRun resolved =
        ResolveGroupRun(path, suite->scenes.at(r.scene_index).scene, r);
    r.nlp_options = resolved.options.nlp_options;
    r.dae_options = resolved.options.dae_options;
    r.key = CanonicalRunKey(r);
    r.run_id = base.group + "-" + base.scene + "-" + r.nlp + "-" + r.dae + "-" +
               ToString(r.coupling) + "-" + Hex64(Fnv1a64(r.key)).substr(0, 8);
    std::string why;
    if (!resolved.options.IsValid(&why))
      Fail(path, "invalid method options (" + why + ") for " + scene_ref +
                     ", got " + r.key);
    suite->runs.push_back(std::move(r));
    // Odometer step: the last axis varies fastest.
    more = false;
    for (std::size_t k = axes.size(); k-- > 0;) {
      if (++at[k] < axes[k].values.size()) {
        more = true;
        break;
      }
      at[k] = 0;
    }
  }
}

// Expands one group of the suite file into runs: reads the group, then for
// each of its scenes resolves the scene-dependent axes and appends the grid.
void ExpandGroup(const YAML::Node& node, const std::string& path,
                 const std::string& group, Suite* suite, OptionTables* tables) {
  const GroupSpec g = ReadGroupSpec(node, path, *suite, tables);
  for (int si : g.scene_idx) {
    const SuiteScene& sc = suite->scenes[si];
    const std::string scene_ref = "scene \"" + sc.name + "\"";
    const SceneAxes s = ResolveSceneAxes(path, g, sc, scene_ref);
    const std::vector<Axis> axes = GridAxes(g, s);
    RunSpec base;
    base.group = group;
    base.scene_index = si;
    base.scene = sc.name;
    base.t_end = s.t_end;
    base.repeats = g.repeats;
    base.exclusive = g.exclusive;
    base.bounds = g.bounds;
    base.checkpoint_interval = g.checkpoint_interval;
    AppendGridRuns(node, path, base, scene_ref, axes, suite);
  }
}

}  // namespace

Suite LoadSuiteFromString(const std::string& text, const std::string& origin,
                          const std::string& base_dir) {
  RegisterBuiltinNlpSolvers();
  RegisterBuiltinIntegrators();
  Suite suite;
  suite.path = origin;
  suite.text_hash = Fnv1a64(text);
  const YAML::Node root = yaml::ParseYaml(text, origin);
  yaml::CheckKeys(root, "",
                  {"name", "description", "reference", "bounds",
                   "checkpoint_interval", "scenes", "groups"});
  suite.name = origin.empty() ? "suite" : fs::path(origin).stem().string();
  if (auto n = Child(root, "name")) suite.name = yaml::ReadString(*n, "name");
  if (auto n = Child(root, "description"))
    suite.description = yaml::ReadString(*n, "description");
  if (auto n = Child(root, "reference"))
    suite.reference = ReadReference(*n, "reference");
  if (auto n = Child(root, "bounds"))
    suite.bounds = ReadBounds(*n, "bounds", suite.bounds);
  yaml::ReadOptionalDouble(root, "", "checkpoint_interval",
                           &suite.checkpoint_interval, Bounds::Positive());

  const YAML::Node scenes = yaml::Require(root, "", "scenes");
  if (!scenes.IsSequence() || scenes.size() == 0)
    Fail("scenes", "expected a non-empty sequence of scene entries, got " +
                       yaml::DescribeNode(scenes));
  std::set<std::string> scene_names;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    const std::string p = JoinIndex("scenes", i);
    SuiteScene s = ReadSuiteScene(scenes[i], p, base_dir);
    if (!scene_names.insert(s.name).second)
      Fail(JoinKey(p, "name"), "duplicate scene name, got \"" + s.name + "\"");
    suite.scenes.push_back(std::move(s));
  }

  const YAML::Node groups = yaml::Require(root, "", "groups");
  if (!groups.IsMap() || groups.size() == 0)
    Fail("groups", "expected a non-empty mapping of named groups, got " +
                       yaml::DescribeNode(groups));
  std::set<std::string> run_ids, group_names;
  OptionTables tables;
  for (auto it = groups.begin(); it != groups.end(); ++it) {
    const std::string raw = it->first.as<std::string>();
    const std::string p = JoinKey("groups", raw);
    if (!IsSafeName(raw))
      Fail(p, "group names must be 1-64 characters of [A-Za-z0-9_.], got \"" +
                  raw + "\"");
    if (!group_names.insert(raw).second)
      Fail(p, "duplicate group, got \"" + raw + "\"");
    suite.groups.push_back(raw);
    const std::size_t first = suite.runs.size();
    ExpandGroup(it->second, p, raw, &suite, &tables);
    if (suite.runs.size() == first) Fail(p, "empty grid, got 0 runs");
    for (std::size_t k = first; k < suite.runs.size(); ++k)
      if (!run_ids.insert(suite.runs[k].run_id).second)
        Fail(p, "duplicate grid point (run id collision), got " +
                    suite.runs[k].run_id);
  }
  return suite;
}

Suite LoadSuite(const std::string& path) {
  std::string text;
  if (!ReadTextFile(path, &text))
    throw SceneError(path + ": cannot open suite file");
  Suite s =
      LoadSuiteFromString(text, path, fs::path(path).parent_path().string());
  s.path = path;
  return s;
}

// --------------------------------------------------- effective scenes ----

TerrainSpec SweptTerrain(const SuiteScene& scene,
                         std::optional<std::uint64_t> seed, double roughness) {
  TerrainSpec spec = scene.terrain;
  if (seed && (!spec.random || spec.random->seed != *seed)) {
    if (!scene.random_terrain())
      throw SceneError("seed: scene \"" + scene.name +
                       "\" has no random gaussian terrain, got " +
                       std::to_string(*seed));
    spec.random->seed = *seed;
  }
  if (roughness != 1.0) {
    if (!scene.gaussian_terrain())
      throw SceneError("roughness: scene \"" + scene.name +
                       "\" has no gaussian terrain, got " + Num(roughness));
    if (spec.random) {
      const auto& r = *spec.random;
      spec.bumps = GaussianTerrain::Random(r.seed, r.count, r.amplitude,
                                           r.sigma, r.x, r.y)
                       .bumps();
      spec.random.reset();
    }
    for (GaussianBump& b : spec.bumps) b.amplitude *= roughness;
  }
  return spec;
}

namespace {
Scene SweptScene(const Suite& suite, const RunSpec& run) {
  const SuiteScene& sc = suite.scenes.at(run.scene_index);
  Scene s = sc.scene;
  ApplySceneFields(run.scene_fields, &s);
  s.mu = run.mu;
  s.t_end = run.t_end;
  if (s.dt > s.t_end) s.dt = run.dt;
  const TerrainSpec spec = SweptTerrain(sc, run.seed, run.roughness);
  if (run.roughness != 1.0 ||
      (run.seed && sc.random_terrain() && *run.seed != sc.terrain.random->seed))
    s.terrain = MakeTerrain(spec);
  return s;
}
}  // namespace

Scene ReferenceScene(const Suite& suite, const RunSpec& run) {
  return SweptScene(suite, run);
}

Scene RunScene(const Suite& suite, const RunSpec& run) {
  return ResolveRun(suite, run).scene;
}

ResolvedRun ResolveRun(const Suite& suite, const RunSpec& run) {
  return ResolveGroupRun("run " + run.run_id, ReferenceScene(suite, run), run);
}

std::string SceneCanonicalText(const Scene& scene, const TerrainSpec& t,
                               const std::string& heightmap_digest) {
  std::ostringstream os;
  const RobotGeometry& g = scene.geometry;
  os << "robot{a=" << Num(g.a) << ";b=" << Num(g.b) << ";track=" << Num(g.track)
     << ";z_h=" << Num(g.z_h) << ";R=" << Num(g.major_radius)
     << ";r=" << Num(g.tube_radius) << ";e=" << Num(g.camber_offset) << "}";
  os << ";mass=" << Num(scene.mass) << ";gravity=" << Num(scene.gravity)
     << ";mu=" << Num(scene.mu) << ";epsilon=" << Num(scene.epsilon)
     << ";mode=" << ToString(scene.mode) << ";rates=[";
  for (double r : scene.joint_rates) os << Num(r) << ",";
  os << "];initial{x=" << Num(scene.x0) << ";y=" << Num(scene.y0)
     << ";yaw=" << Num(scene.yaw0) << ";joints=[";
  for (double a : scene.joint_angles) os << Num(a) << ",";
  os << "]};time{t_end=" << Num(scene.t_end) << ";dt=" << Num(scene.dt) << "}";
  os << ";terrain{type=" << ToString(t.type);
  switch (t.type) {
    case TerrainSpec::Type::kPlane:
      os << ";height=" << Num(t.height);
      break;
    case TerrainSpec::Type::kIncline:
      os << ";slope=" << Num(t.slope_rad) << ";azimuth=" << Num(t.azimuth_rad)
         << ";height=" << Num(t.height);
      break;
    case TerrainSpec::Type::kGaussians:
      if (t.random) {
        const auto& r = *t.random;
        os << ";random{seed=" << r.seed << ";count=" << r.count << ";A=["
           << Num(r.amplitude.lo) << "," << Num(r.amplitude.hi) << "];s=["
           << Num(r.sigma.lo) << "," << Num(r.sigma.hi) << "];x=["
           << Num(r.x.lo) << "," << Num(r.x.hi) << "];y=[" << Num(r.y.lo) << ","
           << Num(r.y.hi) << "]}";
      } else {
        os << ";bumps=[";
        for (const GaussianBump& b : t.bumps)
          os << "(" << Num(b.amplitude) << "," << Num(b.x) << "," << Num(b.y)
             << "," << Num(b.sigma) << ")";
        os << "]";
      }
      break;
    case TerrainSpec::Type::kSinusoid:
      os << ";height=" << Num(t.height) << ";components=[";
      for (const SinusoidComponent& c : t.components)
        os << "(" << Num(c.amplitude) << "," << Num(c.wavelength_x) << ","
           << Num(c.wavelength_y) << "," << Num(c.phase_x) << ","
           << Num(c.phase_y) << ")";
      os << "]";
      break;
    case TerrainSpec::Type::kHeightmap:
      os << ";file=" << t.file << ";digest=" << heightmap_digest;
      break;
  }
  os << "}";
  return os.str();
}

std::string TerrainId(const RunSpec& run, const SuiteScene& scene) {
  const bool seeded = run.seed && scene.random_terrain() &&
                      *run.seed != scene.terrain.random->seed;
  if (!seeded && run.roughness == 1.0) return scene.name;
  std::string id = scene.name;
  if (run.seed && scene.random_terrain())
    id += "_s" + std::to_string(*run.seed);
  if (run.roughness != 1.0) id += "_r" + Num(run.roughness);
  return id;
}

}  // namespace quasiroll::bench
