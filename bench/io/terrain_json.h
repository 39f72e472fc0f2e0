// The JSON description of a terrain that the report reads
// (DIR/terrains/<id>.json of a suite, DIR/terrain.json of an atlas;
// reports/quasiroll_report/terrain.py evaluates it).
#pragma once

#include <string>

#include "quasiroll/core/terrains.h"

namespace quasiroll::bench {

// {"type": "plane"|"incline"|"gaussians", ...} with a trailing newline; ""
// for types it does not cover (sinusoid, heightmap). Random Gaussian
// terrains are written as their drawn bumps.
std::string TerrainJson(const TerrainSpec& spec);

}  // namespace quasiroll::bench
