// A scene: robot, terrain, actuation and time span. Loaded from YAML
// (docs/scenes.md documents every key and default); a scene names only what it
// needs and everything else takes the default below (model.md §1.5).
#pragma once

#include <array>
#include <memory>
#include <stdexcept>
#include <string>

#include "quasiroll/core/terrain.h"

namespace quasiroll {

// Bad scene/suite input. what() is one line: "<key.path>: <problem>, got
// <value>".
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RobotGeometry {
  double a = 0.25;             // COM to front axle along x_P [m]
  double b = 0.25;             // COM to rear axle [m]
  double track = 0.40;         // rear track t [m]
  double z_h = 0.05;           // wheel centres below the COM [m]
  double major_radius = 0.08;  // torus major radius R [m]
  double tube_radius = 0.02;   // torus tube radius r [m], 0 < r < R
  double camber_offset = 0.0;  // e_i: wheel centre offset from camber axis [m]

  double rho() const { return major_radius + tube_radius; }  // upright radius
  double wheelbase() const { return a + b; }
};

enum class ActuationMode { kPaper, kPvc };
const char* ToString(ActuationMode mode);

struct Scene {
  std::string name = "unnamed";
  std::string source_path;  // file it was loaded from ("" if built in code)

  RobotGeometry geometry;
  double mass = 5.0;     // [kg]
  double gravity = 9.8;  // [m/s^2]
  double mu = 0.5;       // Coulomb friction coefficient, > 0
  ActuationMode mode = ActuationMode::kPaper;
  // Prescribed joint rates (phi1, alpha1, delta2, alpha2, delta3, alpha3)
  // [rad/s]; in pvc mode the passive entries (alpha1, delta2, delta3) are
  // ignored.
  std::array<double, 6> joint_rates = {0.0, 0.6, 0.0, 0.6, 0.0, 0.6};

  // Initial planar placement of the platform COM and joint angles [m, rad].
  double x0 = 0.0, y0 = 0.0, yaw0 = 0.0;
  std::array<double, 6> joint_angles = {0, 0, 0, 0, 0, 0};

  // Never null after LoadScene(); defaults to the plane z = 0.
  std::shared_ptr<const Terrain> terrain;

  double t_end = 20.0;  // [s]
  double dt = 0.05;     // hold interval of the quasi-static solve [s]
  // Regularisation velocity of the Coulomb law [m/s] (model.md §7.2).
  double epsilon = 1e-8;
};

// Parses a scene file. Throws SceneError naming the key path and the value for
// every problem (missing file, syntax, unknown key, wrong type, out of range,
// non-finite). Relative heightmap paths are resolved against the scene's
// directory.
Scene LoadScene(const std::string& path);
// Same, from YAML text; `origin` is used in messages and to resolve relative
// paths ("" = current directory).
Scene LoadSceneFromString(const std::string& yaml_text,
                          const std::string& origin = "");

}  // namespace quasiroll
