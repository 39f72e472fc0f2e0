// `quasiroll atlas` (docs/atlas.md): the traversability atlas of a scene's
// terrain, from a spec file or from flags.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace quasiroll::cli {

struct AtlasArgs {
  std::string spec;          // atlas spec YAML ("" = from the flags below)
  std::string scene;         // with the flags
  std::vector<double> x, y;  // lo hi count
  std::optional<int> headings;
  std::vector<std::string> modes;
  std::optional<int> edge_cells;  // overrides the spec's edge_cells
  std::string out = "out/atlas";
  std::optional<int> jobs;  // default: hardware concurrency
  bool resume = false;
  std::string progress = "auto";
  std::string shard;  // "I/N" (docs/cluster.md), "" = the whole atlas
};

class AtlasCommand {
 public:
  // Adds the `atlas` subcommand; when parsed it stores its action in
  // *selected.
  void Register(CLI::App& app, std::function<int()>* selected);

 private:
  AtlasArgs args_;
};

int RunAtlasCommand(const AtlasArgs& args);

}  // namespace quasiroll::cli
