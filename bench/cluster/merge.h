// `quasiroll merge DIR [DIR...] --out DIR` (docs/cluster.md): joins the
// output of shards (bench --shard), partial runs (--filter) and MPI runs of
// one suite into the runs.csv and meta.json a one-machine run writes; and
// the shards of an atlas (atlas --shard) into its atlas.csv.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace quasiroll::bench {

struct MergeOptions {
  std::vector<std::string> inputs;  // output directories of quasiroll bench
  std::string out;                  // may be one of the inputs
  // The suite file; "" = the one the inputs' meta.json name
  // (suite.absolute_path). Its text must hash to the inputs' suite_hash.
  std::string suite;
  std::FILE* log = stderr;  // warnings (differing duplicates, incomplete)
};

struct MergeSummary {
  int runs = 0;        // rows of the merged runs.csv
  int metas = 0;       // meta.json files read
  int duplicates = 0;  // rows found in more than one input (one kept)
  int differing = 0;   // of those, rows differing outside the timing/host
                       // columns (a warning each)
  int failures = 0;    // rows whose status is not "success"
  std::vector<std::string> hosts;  // distinct `host` values of the rows
  // The inputs were atlas outputs (quasiroll atlas --shard, quasiroll-mpi
  // atlas): `runs` counts cells, `failures` cells not "ok", and OUT has
  // atlas.csv, meta.json and (with an edge study) edge.csv.
  bool atlas = false;
};

// meta.json keys that describe how, where and when a run was made, not what
// it computed: they differ between a merged and a one-machine run of the same
// suite (docs/cluster.md). Every other key is byte-identical.
const std::vector<std::string>& InvocationMetaKeys();
// runs.csv columns of timing and of the executing machine; every other
// column is byte-identical between a merged and a one-machine run.
const std::vector<std::string>& TimingAndHostColumns();

// Merges. Atlas directories (meta.json "kind": "atlas") are merged as
// atlases (docs/cluster.md, "Atlas"): same grid key and commit, every cell
// exactly once (else a SceneError naming how many are missing and the
// first), then atlas.csv, edge.csv and meta.json as one process writes them.
// Throws SceneError (one line naming the file, the key and both
// values) when the inputs disagree on the suite hash, commit, library
// versions, numerical libraries, reference settings or filter, when the
// suite file does not match, or when selected runs are missing (naming how
// many and the first); I/O errors propagate as std::runtime_error.
MergeSummary MergeOutputs(const MergeOptions& options);

}  // namespace quasiroll::bench
