// libFuzzer target: scene YAML text -> LoadSceneFromString.
//
// Contract (core/scene.h): any bad input is a SceneError with a one-line
// message naming the key; any other exception (std::bad_alloc, yaml-cpp's
// own exceptions, std::out_of_range, ...) escaping the loader is a bug and
// aborts. A scene that loads must be usable: finite parameters, a terrain
// whose height at the start is finite.
//
// Heightmaps: if the input contains a line "#csv", everything after it is
// written to grid.csv in a private temporary directory that relative
// heightmap paths resolve against, so `terrain: {type: heightmap, file:
// grid.csv}` fuzzes the CSV reader and the spline too.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <typeinfo>

#include "quasiroll/core/scene.h"

namespace {
char g_work_dir[] = "/tmp/quasiroll-fuzz-scene.XXXXXX";

// At exit (the fuzzer's and the corpus replay's): /tmp keeps nothing.
void RemoveWorkDir() {
  std::remove((std::string(g_work_dir) + "/grid.csv").c_str());
  ::rmdir(g_work_dir);
}

const std::string& WorkDir() {
  static const std::string dir = [] {
    if (::mkdtemp(g_work_dir) == nullptr) std::abort();
    std::atexit(RemoveWorkDir);
    return std::string(g_work_dir);
  }();
  return dir;
}

[[noreturn]] void Bug(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_scene: %s: %s\n", what, detail.c_str());
  std::abort();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data,
                                      std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  // Heightmap files are opened by path: keep the fuzzer away from device and
  // proc files (an endless /dev/zero is not a loader bug). Relative paths
  // resolve against a directory that does not exist.
  if (text.find("/dev") != std::string::npos ||
      text.find("/proc") != std::string::npos ||
      text.find("/sys") != std::string::npos)
    return 0;
  const std::string dir = WorkDir();
  const std::size_t marker = text.find("\n#csv\n");
  {
    std::ofstream csv(dir + "/grid.csv", std::ios::binary | std::ios::trunc);
    if (marker != std::string::npos) {
      csv << text.substr(marker + 6);
      text.resize(marker + 1);
    }
  }
  try {
    const quasiroll::Scene scene =
        quasiroll::LoadSceneFromString(text, dir + "/scene.yaml");
    if (!scene.terrain) Bug("loaded scene without terrain", scene.name);
    if (!(std::isfinite(scene.mu) && scene.mu > 0 && std::isfinite(scene.dt) &&
          scene.dt > 0 && std::isfinite(scene.t_end) &&
          std::isfinite(scene.epsilon)))
      Bug("loaded scene with invalid numbers", scene.name);
    const double h = scene.terrain->Height(scene.x0, scene.y0);
    if (!std::isfinite(h))
      Bug("non-finite terrain height at the start", scene.name);
  } catch (const quasiroll::SceneError&) {
    // Expected for bad input.
  } catch (const std::exception& e) {
    Bug(typeid(e).name(), e.what());
  }
  return 0;
}
