// Scene loading (docs/scenes.md documents the schema).
#include "quasiroll/core/scene.h"

#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <system_error>

#include "quasiroll/core/terrains.h"
#include "quasiroll/core/yaml_util.h"

namespace quasiroll {

const char* ToString(ActuationMode mode) {
  switch (mode) {
    case ActuationMode::kPaper:
      return "paper";
    case ActuationMode::kPvc:
      return "pvc";
  }
  return "?";
}

namespace yaml {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string ResolvePath(const std::string& file, const std::string& base_dir) {
  namespace fs = std::filesystem;
  fs::path p(file);
  if (p.is_relative() && !base_dir.empty()) p = fs::path(base_dir) / p;
  return p.lexically_normal().string();
}

// Reads a non-empty sequence of mappings, calling fn(element, element_path).
template <typename Fn>
void ForEachMapping(const YAML::Node& node, const std::string& path,
                    const char* what, Fn fn) {
  if (!node.IsSequence() || node.size() == 0) {
    Fail(path, std::string("expected a non-empty sequence of ") + what +
                   ", got " + DescribeNode(node));
  }
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string p = JoinIndex(path, i);
    if (!node[i].IsMap()) {
      Fail(p, "expected a mapping, got " + DescribeNode(node[i]));
    }
    fn(node[i], p);
  }
}

SinusoidComponent ReadComponent(const YAML::Node& node,
                                const std::string& path) {
  SinusoidComponent c;
  const Bounds wavelength = Bounds::Positive().AllowInf();
  c.amplitude =
      ReadDouble(Require(node, path, "amplitude"), JoinKey(path, "amplitude"));
  ReadOptionalDouble(node, path, "wavelength_x", &c.wavelength_x, wavelength);
  ReadOptionalDouble(node, path, "wavelength_y", &c.wavelength_y, wavelength);
  ReadOptionalDouble(node, path, "phase_x", &c.phase_x);
  ReadOptionalDouble(node, path, "phase_y", &c.phase_y);
  return c;
}

Interval ToInterval(const std::pair<double, double>& p) {
  return Interval{p.first, p.second};
}

// One reader per terrain type: each checks the keys its type allows and fills
// the fields of `spec` that type uses, so the dispatcher below stays a table.

void ReadInclineTerrain(const YAML::Node& node, const std::string& path,
                        TerrainSpec* spec) {
  CheckKeys(node, path, {"type", "slope_deg", "azimuth_deg", "height"});
  double slope_deg = 0.0, azimuth_deg = 0.0;
  ReadOptionalDouble(node, path, "slope_deg", &slope_deg,
                     Bounds{}.Gt(-89.0).Lt(89.0));
  ReadOptionalDouble(node, path, "azimuth_deg", &azimuth_deg);
  ReadOptionalDouble(node, path, "height", &spec->height);
  // The file speaks degrees (readable by hand); the terrain wants radians.
  spec->slope_rad = slope_deg * kDeg;
  spec->azimuth_rad = azimuth_deg * kDeg;
}

// An explicit list of bumps, each fully specified.
void ReadGaussianBumps(const YAML::Node& bumps, const std::string& path,
                       TerrainSpec* spec) {
  ForEachMapping(bumps, JoinKey(path, "bumps"), "bumps",
                 [&](const YAML::Node& b, const std::string& p) {
                   CheckKeys(b, p, {"amplitude", "x", "y", "sigma"});
                   GaussianBump bump;
                   bump.amplitude = ReadDouble(Require(b, p, "amplitude"),
                                               JoinKey(p, "amplitude"));
                   bump.x = ReadDouble(Require(b, p, "x"), JoinKey(p, "x"));
                   bump.y = ReadDouble(Require(b, p, "y"), JoinKey(p, "y"));
                   bump.sigma =
                       ReadDouble(Require(b, p, "sigma"), JoinKey(p, "sigma"),
                                  Bounds::Positive());
                   spec->bumps.push_back(bump);
                 });
}

// A seeded random field of bumps: only seed and count are required, the
// ranges default so that a short spec gives a realistic terrain.
TerrainSpec::Random ReadRandomGaussians(const YAML::Node& random,
                                        const std::string& path) {
  const std::string p = JoinKey(path, "random");
  if (!random.IsMap()) {
    Fail(p, "expected a mapping, got " + DescribeNode(random));
  }
  CheckKeys(random, p, {"seed", "count", "amplitude", "sigma", "x", "y"});
  TerrainSpec::Random r;
  r.seed = ReadUint64(Require(random, p, "seed"), JoinKey(p, "seed"));
  r.count = static_cast<int>(
      ReadInt(Require(random, p, "count"), JoinKey(p, "count"), 1, 100000));
  // Defaults: roughly the statistics of the reference terrain R1.
  r.amplitude = {-0.04, 0.04};
  r.sigma = {0.25, 0.45};
  r.x = {-0.5, 2.5};
  r.y = {-1.2, 1.2};
  if (auto n = Child(random, "amplitude")) {
    r.amplitude = ToInterval(ReadInterval(*n, JoinKey(p, "amplitude")));
  }
  if (auto n = Child(random, "sigma")) {
    r.sigma =
        ToInterval(ReadInterval(*n, JoinKey(p, "sigma"), Bounds::Positive()));
  }
  if (auto n = Child(random, "x")) {
    r.x = ToInterval(ReadInterval(*n, JoinKey(p, "x")));
  }
  if (auto n = Child(random, "y")) {
    r.y = ToInterval(ReadInterval(*n, JoinKey(p, "y")));
  }
  return r;
}

// Exactly one of 'bumps' and 'random': a mix would leave it unclear which
// bumps the terrain has.
void ReadGaussiansTerrain(const YAML::Node& node, const std::string& path,
                          TerrainSpec* spec) {
  CheckKeys(node, path, {"type", "bumps", "random"});
  const std::optional<YAML::Node> bumps = Child(node, "bumps");
  const std::optional<YAML::Node> random = Child(node, "random");
  if (bumps && random) {
    Fail(JoinKey(path, "random"),
         "not allowed together with " + JoinKey(path, "bumps"));
  }
  if (!bumps && !random) {
    Fail(path, "gaussians needs either 'bumps' or 'random', got neither");
  }
  if (bumps) {
    ReadGaussianBumps(*bumps, path, spec);
  } else {
    spec->random = ReadRandomGaussians(*random, path);
  }
}

// Either a list of 'components' or one component inline on the terrain node;
// inline component keys next to 'components' would be silently ignored, so
// they are an error.
void ReadSinusoidTerrain(const YAML::Node& node, const std::string& path,
                         TerrainSpec* spec) {
  CheckKeys(node, path,
            {"type", "height", "amplitude", "wavelength_x", "wavelength_y",
             "phase_x", "phase_y", "components"});
  ReadOptionalDouble(node, path, "height", &spec->height);
  if (std::optional<YAML::Node> comps = Child(node, "components")) {
    for (const char* k :
         {"amplitude", "wavelength_x", "wavelength_y", "phase_x", "phase_y"}) {
      if (Child(node, k)) {
        Fail(JoinKey(path, k),
             "not allowed together with " + JoinKey(path, "components"));
      }
    }
    ForEachMapping(*comps, JoinKey(path, "components"), "components",
                   [&](const YAML::Node& c, const std::string& p) {
                     CheckKeys(c, p,
                               {"amplitude", "wavelength_x", "wavelength_y",
                                "phase_x", "phase_y"});
                     spec->components.push_back(ReadComponent(c, p));
                   });
  } else {
    if (!node.IsMap()) Fail(JoinKey(path, "amplitude"), "required key missing");
    spec->components.push_back(ReadComponent(node, path));
  }
}

// The file is resolved against the scene's directory so that scenes can be
// moved together with their heightmaps.
void ReadHeightmapTerrain(const YAML::Node& node, const std::string& path,
                          const std::string& base_dir, TerrainSpec* spec) {
  CheckKeys(node, path, {"type", "file"});
  if (!node.IsMap()) Fail(JoinKey(path, "file"), "required key missing");
  const std::string file =
      ReadString(Require(node, path, "file"), JoinKey(path, "file"));
  if (file.empty()) Fail(JoinKey(path, "file"), "must not be empty, got \"\"");
  spec->file = ResolvePath(file, base_dir);
}

}  // namespace

TerrainSpec ReadTerrainSpec(const YAML::Node& node, const std::string& path,
                            const std::string& base_dir) {
  TerrainSpec spec;
  if (!node.IsNull() && !node.IsMap()) {
    Fail(path, "expected a mapping, got " + DescribeNode(node));
  }
  if (std::optional<YAML::Node> t = Child(node, "type")) {
    const std::string type =
        ReadEnum(*t, JoinKey(path, "type"),
                 {"plane", "incline", "gaussians", "sinusoid", "heightmap"});
    spec.type = *TerrainTypeFromString(type);
  }
  switch (spec.type) {
    case TerrainSpec::Type::kPlane:
      CheckKeys(node, path, {"type", "height"});
      ReadOptionalDouble(node, path, "height", &spec.height);
      break;
    case TerrainSpec::Type::kIncline:
      ReadInclineTerrain(node, path, &spec);
      break;
    case TerrainSpec::Type::kGaussians:
      ReadGaussiansTerrain(node, path, &spec);
      break;
    case TerrainSpec::Type::kSinusoid:
      ReadSinusoidTerrain(node, path, &spec);
      break;
    case TerrainSpec::Type::kHeightmap:
      ReadHeightmapTerrain(node, path, base_dir, &spec);
      break;
  }
  return spec;
}

std::shared_ptr<const Terrain> ReadTerrain(const YAML::Node& node,
                                           const std::string& path,
                                           const std::string& base_dir) {
  const TerrainSpec spec = ReadTerrainSpec(node, path, base_dir);
  try {
    return MakeTerrain(spec);
  } catch (const SceneError& e) {
    // Heightmap messages start with the file path; others with a sub-key.
    const std::string where = spec.type == TerrainSpec::Type::kHeightmap
                                  ? JoinKey(path, "file")
                                  : path;
    Fail(where, e.what());
  }
}

void ReadSceneNode(const YAML::Node& node, const std::string& path,
                   const std::string& base_dir, Scene* scene) {
  CheckKeys(node, path,
            {"name", "mode", "mass", "gravity", "mu", "epsilon", "joint_rates",
             "robot", "initial", "time", "terrain"});
  if (auto n = Child(node, "name"))
    scene->name = ReadString(*n, JoinKey(path, "name"));
  if (auto n = Child(node, "mode")) {
    scene->mode =
        ReadEnum(*n, JoinKey(path, "mode"), {"paper", "pvc"}) == "paper"
            ? ActuationMode::kPaper
            : ActuationMode::kPvc;
  }
  ReadOptionalDouble(node, path, "mass", &scene->mass, Bounds::Positive());
  ReadOptionalDouble(node, path, "gravity", &scene->gravity,
                     Bounds::Positive());
  ReadOptionalDouble(node, path, "mu", &scene->mu, Bounds::Positive());
  ReadOptionalDouble(node, path, "epsilon", &scene->epsilon,
                     Bounds::Positive());
  if (auto n = Child(node, "joint_rates")) {
    scene->joint_rates = ReadArray<6>(*n, JoinKey(path, "joint_rates"));
  }

  if (auto robot = Child(node, "robot")) {
    const std::string p = JoinKey(path, "robot");
    CheckKeys(*robot, p,
              {"a", "b", "track", "z_h", "major_radius", "tube_radius",
               "camber_offset"});
    RobotGeometry& g = scene->geometry;
    ReadOptionalDouble(*robot, p, "a", &g.a, Bounds::Positive());
    ReadOptionalDouble(*robot, p, "b", &g.b, Bounds::Positive());
    ReadOptionalDouble(*robot, p, "track", &g.track, Bounds::Positive());
    ReadOptionalDouble(*robot, p, "z_h", &g.z_h, Bounds::NonNegative());
    ReadOptionalDouble(*robot, p, "major_radius", &g.major_radius,
                       Bounds::Positive());
    ReadOptionalDouble(*robot, p, "tube_radius", &g.tube_radius,
                       Bounds::Positive());
    ReadOptionalDouble(*robot, p, "camber_offset", &g.camber_offset);
  }
  if (!(scene->geometry.tube_radius < scene->geometry.major_radius)) {
    Fail(JoinKey(path, "robot.tube_radius"),
         "must be < " + JoinKey(path, "robot.major_radius") + " (" +
             FormatNumber(scene->geometry.major_radius) + "), got " +
             FormatNumber(scene->geometry.tube_radius));
  }

  if (auto initial = Child(node, "initial")) {
    const std::string p = JoinKey(path, "initial");
    CheckKeys(*initial, p, {"x", "y", "yaw", "joint_angles"});
    ReadOptionalDouble(*initial, p, "x", &scene->x0);
    ReadOptionalDouble(*initial, p, "y", &scene->y0);
    ReadOptionalDouble(*initial, p, "yaw", &scene->yaw0);
    if (auto n = Child(*initial, "joint_angles")) {
      scene->joint_angles = ReadArray<6>(*n, JoinKey(p, "joint_angles"));
    }
  }

  if (auto time = Child(node, "time")) {
    const std::string p = JoinKey(path, "time");
    CheckKeys(*time, p, {"t_end", "dt"});
    ReadOptionalDouble(*time, p, "t_end", &scene->t_end, Bounds::Positive());
    ReadOptionalDouble(*time, p, "dt", &scene->dt, Bounds::Positive());
  }
  if (!(scene->dt <= scene->t_end)) {
    Fail(JoinKey(path, "time.dt"), "must be <= " + JoinKey(path, "time.t_end") +
                                       " (" + FormatNumber(scene->t_end) +
                                       "), got " + FormatNumber(scene->dt));
  }

  if (auto terrain = Child(node, "terrain")) {
    scene->terrain = ReadTerrain(*terrain, JoinKey(path, "terrain"), base_dir);
  }
  if (!scene->terrain) scene->terrain = std::make_shared<PlaneTerrain>(0.0);
  if (!scene->terrain->Contains(scene->x0, scene->y0)) {
    Fail(JoinKey(path, "initial"),
         "start (x, y) must lie inside the terrain domain (" +
             scene->terrain->Describe() + "), got (" + FormatNumber(scene->x0) +
             ", " + FormatNumber(scene->y0) + ")");
  }
}

}  // namespace yaml

Scene LoadSceneFromString(const std::string& yaml_text,
                          const std::string& origin) {
  namespace fs = std::filesystem;
  const YAML::Node root = yaml::ParseYaml(yaml_text, origin);
  Scene scene;
  scene.source_path = origin;
  std::string base_dir;
  if (!origin.empty()) {
    std::error_code ec;
    base_dir = fs::is_directory(origin, ec)
                   ? origin
                   : fs::path(origin).parent_path().string();
    const std::string stem = fs::path(origin).stem().string();
    if (!stem.empty() && !fs::is_directory(origin, ec)) scene.name = stem;
  }
  yaml::ReadSceneNode(root, "", base_dir, &scene);
  return scene;
}

Scene LoadScene(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return LoadSceneFromString(ss.str(), path);
}

}  // namespace quasiroll
