#include "quasiroll/bench/cli/atlas_command.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <thread>
#include <utility>

#include "quasiroll/bench/atlas/atlas.h"
#include "quasiroll/bench/cli/cli_support.h"
#include "quasiroll/bench/harness/shard.h"

namespace quasiroll::cli {

namespace {

// [lo, hi, count] from a flag's three numbers.
bench::AtlasAxis AxisFromFlag(const std::vector<double>& v,
                              const std::string& flag) {
  if (v.size() != 3 || v[2] != std::floor(v[2]))
    throw std::invalid_argument(flag +
                                ": must be three numbers LO HI COUNT (COUNT "
                                "an integer)");
  bench::AtlasAxis a;
  a.lo = v[0];
  a.hi = v[1];
  a.count = static_cast<int>(v[2]);
  return a;
}

bench::AtlasSpec SpecFromArgs(const AtlasArgs& args) {
  if (!args.spec.empty()) {
    if (!args.scene.empty() || !args.x.empty() || !args.y.empty() ||
        args.headings || !args.modes.empty())
      throw std::invalid_argument(
          "--spec: give either a spec file or --scene/--x/--y/--headings/"
          "--modes, got both");
    return bench::LoadAtlasSpec(args.spec);
  }
  if (args.scene.empty())
    throw std::invalid_argument("--scene: required without --spec");
  bench::AtlasSpec spec;
  spec.scene_path = args.scene;
  spec.scene = LoadScene(args.scene);
  spec.x = args.x.empty() ? bench::AtlasAxis{spec.scene.x0, spec.scene.x0, 1}
                          : AxisFromFlag(args.x, "--x");
  spec.y = args.y.empty() ? bench::AtlasAxis{spec.scene.y0, spec.scene.y0, 1}
                          : AxisFromFlag(args.y, "--y");
  if (args.headings) spec.headings = *args.headings;
  if (!args.modes.empty()) {
    spec.modes.clear();
    for (const std::string& m : args.modes)
      spec.modes.push_back(m == "pvc" ? ActuationMode::kPvc
                                      : ActuationMode::kPaper);
  }
  spec.Validate();
  return spec;
}

}  // namespace

void AtlasCommand::Register(CLI::App& app, std::function<int()>* selected) {
  CLI::App* atlas = app.add_subcommand(
      "atlas",
      "mu_min over a grid of poses (x, y, heading) and modes; writes "
      "DIR/atlas.csv and DIR/meta.json (docs/atlas.md)");
  atlas->add_option("--spec", args_.spec, "Atlas spec YAML (docs/atlas.md)");
  atlas->add_option("--scene", args_.scene, "Scene YAML file (without --spec)");
  atlas->add_option("--x", args_.x, "LO HI COUNT of the x positions [m]")
      ->expected(3);
  atlas->add_option("--y", args_.y, "LO HI COUNT of the y positions [m]")
      ->expected(3);
  atlas
      ->add_option("--headings", args_.headings,
                   "Headings evenly spaced over [0, 2 pi) (default: 16)")
      ->check(IntegerIn(1, 100000));
  atlas->add_option("--modes", args_.modes, "paper and/or pvc (default: both)")
      ->check(OneOf({"paper", "pvc"}));
  atlas
      ->add_option("--edge-cells", args_.edge_cells,
                   "Cells of the edge-reliability study (every NLP backend "
                   "at mu = mu_min (1 + d); DIR/edge.csv); 0 = none")
      ->check(IntegerIn(0, 100000));
  atlas->add_option("--out", args_.out, "Output directory")
      ->capture_default_str();
  atlas
      ->add_option("--jobs", args_.jobs,
                   "Worker threads (default: hardware concurrency)")
      ->check(IntegerIn(1, 4096));
  atlas->add_flag("--resume", args_.resume,
                  "Keep the rows of an existing atlas.csv of the same grid "
                  "and compute only the missing cells");
  atlas->add_option(
      "--shard", args_.shard,
      "I/N: compute slice I (from 0) of N of the cells into "
      "DIR/shards/I-of-N/; `quasiroll merge DIR --out DIR` joins them "
      "(docs/cluster.md)");
  atlas->add_option("--progress", args_.progress, "auto | bar | none")
      ->check(OneOf({"auto", "bar", "none"}))
      ->capture_default_str();
  atlas->callback([this, selected] {
    *selected = [this] { return RunAtlasCommand(args_); };
  });
}

int RunAtlasCommand(const AtlasArgs& args) {
  // Checked first: a bad value runs nothing (exit 2 naming --shard).
  const auto [shard_index, shard_count] = args.shard.empty()
                                              ? std::pair<int, int>{0, 1}
                                              : bench::ParseShard(args.shard);
  bench::AtlasSpec spec = SpecFromArgs(args);
  if (args.edge_cells) spec.edge_cells = *args.edge_cells;
  bench::AtlasOptions options;
  options.out_dir = args.out;
  options.resume = args.resume;
  options.shard_index = shard_index;
  options.shard_count = shard_count;
  options.jobs = args.jobs.value_or(
      static_cast<int>(std::max(1u, std::thread::hardware_concurrency())));
  options.progress = args.progress == "bar" ||
                     (args.progress == "auto" && isatty(STDERR_FILENO));
  const bench::AtlasSummary s = bench::RunAtlas(spec, options);
  const std::string out =
      shard_count > 1 ? bench::AtlasShardDir(args.out, shard_index, shard_count)
                      : args.out;
  const std::string shard =
      shard_count > 1 ? "shard " + args.shard + ": " : std::string();
  std::printf(
      "atlas: %s%lld cells (%lld computed, %lld kept), %lld ok, %lld edge "
      "solves, %.1f s -> %s/atlas.csv\n",
      shard.c_str(), static_cast<long long>(s.cells),
      static_cast<long long>(s.computed), static_cast<long long>(s.reused),
      static_cast<long long>(s.ok), static_cast<long long>(s.edge_solves),
      s.wall_seconds, out.c_str());
  return kExitOk;
}

}  // namespace quasiroll::cli
