#include "quasiroll/bench/io/terrain_json.h"

#include <numbers>
#include <vector>

#include "quasiroll/bench/io/json_writer.h"

namespace quasiroll::bench {

std::string TerrainJson(const TerrainSpec& spec) {
  JsonWriter w;
  w.BeginObject();
  switch (spec.type) {
    case TerrainSpec::Type::kPlane:
      w.Key("type").Value("plane");
      w.Key("height").Value(spec.height);
      break;
    case TerrainSpec::Type::kIncline:
      w.Key("type").Value("incline");
      w.Key("slope_deg").Value(spec.slope_rad * 180 / std::numbers::pi);
      w.Key("azimuth_deg").Value(spec.azimuth_rad * 180 / std::numbers::pi);
      w.Key("height").Value(spec.height);
      break;
    case TerrainSpec::Type::kGaussians: {
      std::vector<GaussianBump> bumps = spec.bumps;
      if (spec.random) {
        const auto& r = *spec.random;
        bumps = GaussianTerrain::Random(r.seed, r.count, r.amplitude, r.sigma,
                                        r.x, r.y)
                    .bumps();
      }
      w.Key("type").Value("gaussians");
      w.Key("bumps").BeginArray();
      for (const GaussianBump& b : bumps) {
        w.BeginArray();
        w.Value(b.amplitude).Value(b.x).Value(b.y).Value(b.sigma);
        w.EndArray();
      }
      w.EndArray();
      break;
    }
    default:
      return "";
  }
  w.EndObject();
  return w.str() + "\n";
}

}  // namespace quasiroll::bench
