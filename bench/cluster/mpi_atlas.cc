// quasiroll-mpi atlas: the traversability atlas over MPI ranks
// (docs/cluster.md, "Atlas over MPI").
//
//   mpirun -np K quasiroll-mpi atlas --spec FILE --out DIR [--resume]
//
// Rank 0 reads the finished rows (--resume), writes meta.json, then hands
// out chunks of cell indices to whichever worker is free (cell costs differ
// ~10x between a pose that fails early and a bisection); ranks 1..K-1
// evaluate them, append each row flushed to their own partial file
// DIR/atlas.partial.rank-R.csv and send the chunk's rows back. Rank 0 ends
// with FinishAtlasOutput, the step `quasiroll atlas` ends with, so
// atlas.csv is the one-process file but for wall_s.
//
// A rank that dies takes the job down: mpirun sends the others SIGCONT,
// SIGTERM a second later and SIGKILL a second after that (Open MPI 4.1,
// odls_base_sigkill_timeout = 1 s). On the SIGTERM the workers stop writing
// rows and rank 0 reports the cells that are missing (neither returned nor
// in a partial file on disk: count and first indices) before it exits
// non-zero; --resume computes only those.
//
// Test hook: QUASIROLL_TEST_MPI_KILL=R:N makes worker rank R raise SIGKILL
// after writing its N-th row (tests/cluster/mpi_atlas_test.sh).
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "quasiroll/bench/atlas/atlas.h"
#include "quasiroll/bench/cluster/mpi_internal.h"
#include "quasiroll/bench/io/output_lock.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::mpi {
namespace {

namespace fs = std::filesystem;

enum AtlasTag : int { kTagCells = 11, kTagRows = 12, kTagAtlasStats = 13 };

std::string PartialOfRank(const std::string& dir, int rank) {
  return (fs::path(dir) /
          ("atlas.partial.rank-" + std::to_string(rank) + ".csv"))
      .string();
}

// Evaluates `cells` a pose at a time (its modes share the placement) and
// hands each row to `on_row` as soon as its pose is done, so that a rank
// killed mid-chunk has written all but its current pose's rows.
template <typename OnRow>
void EvaluateByPose(const bench::AtlasSpec& spec,
                    const std::vector<std::int64_t>& cells, OnRow on_row) {
  const std::size_t step = spec.modes.size();
  for (std::size_t k = 0; k < cells.size(); k += step) {
    const std::vector<std::int64_t> pose(
        cells.begin() + k, cells.begin() + std::min(k + step, cells.size()));
    for (const bench::AtlasRow& r : bench::EvaluateAtlasCells(spec, pose))
      on_row(r);
  }
}

// ------------------------------------------------------------- worker ----

// Replies "ok\n" + one row per line, or "io_error\n" + the message.
void AtlasWorker(const bench::AtlasSpec& spec, const std::string& dir, int rank,
                 RankStats* stats) {
  std::optional<bench::AtlasPartialFile> partial;
  std::string open_error;
  try {
    partial.emplace(PartialOfRank(dir, rank));
  } catch (const std::exception& e) {
    open_error = e.what();
  }
  const long kill_after = TestKillAfter(rank);
  long written = 0;
  for (;;) {
    MPI_Status st{};
    if (!WaitForMessageUnless(0, kTagCells, stats, &g_terminate, &st)) Linger();
    int count = 0;
    MPI_Get_count(&st, MPI_INT64_T, &count);
    std::vector<std::int64_t> cells(static_cast<std::size_t>(count));
    MPI_Recv(cells.data(), count, MPI_INT64_T, 0, kTagCells, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    if (count == 0) break;  // stop
    const auto t0 = Clock::now();
    std::string reply = "ok\n";
    try {
      if (!open_error.empty()) throw std::runtime_error(open_error);
      EvaluateByPose(spec, cells, [&](const bench::AtlasRow& r) {
        const std::string row = bench::AtlasCsvRow(r);
        if (g_terminate) Linger();
        partial->Append(row);
        if (++written == kill_after) std::raise(SIGKILL);
        reply += row + "\n";
      });
    } catch (const std::exception& e) {  // I/O: the job cannot go on
      reply = std::string("io_error\n") + e.what();
    }
    stats->busy_wall += Seconds(t0);
    ++stats->tasks;
    SendString(reply, 0, kTagRows);
  }
}

// ------------------------------------------------------------- rank 0 ----

// The rows of `cells` (a chunk out at `rank` when the job stopped) that
// the rank wrote to its partial file: at its end, as a worker appends a
// chunk's rows in order, so the last bytes suffice.
void AddRowsOnDisk(const bench::AtlasSpec& spec, const std::string& dir,
                   int rank, const std::vector<std::int64_t>& cells,
                   std::map<std::int64_t, std::string>* rows) {
  std::ifstream in(PartialOfRank(dir, rank), std::ios::binary);
  if (!in) return;
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff tail = std::min<std::streamoff>(
      size, 4096 + 2048 * std::streamoff(cells.size()));
  in.seekg(size - tail);
  std::string text(static_cast<std::size_t>(tail), '\0');
  in.read(text.data(), tail);
  std::map<std::int64_t, std::string> found;
  bench::ParseAtlasRows(spec, std::move(text), &found);
  for (std::int64_t c : cells)
    if (const auto it = found.find(c); it != found.end()) rows->insert(*it);
}

// After SIGTERM (a rank died, or the job was cancelled): what a --resume
// would still have to compute, on stderr, then exit non-zero at once
// (mpirun sends SIGKILL a second later, so this reads only the ends of the
// partial files of the ranks that had a chunk out). A rank still finishing
// a row as they are read makes the count one too high, never too low.
[[noreturn]] void ReportMissingAndExit(
    const bench::AtlasSpec& spec, const std::string& dir,
    std::map<std::int64_t, std::string> rows,
    const std::map<int, std::vector<std::int64_t>>& out) {
  // The workers got their SIGTERM too: let them stop writing first.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (const auto& [rank, cells] : out) {
    try {
      AddRowsOnDisk(spec, dir, rank, cells, &rows);
    } catch (const std::exception&) {  // count those cells as missing
    }
  }
  const std::int64_t n = spec.CellCount();
  std::string first;
  int listed = 0;
  auto it = rows.begin();
  for (std::int64_t i = 0; i < n && listed < 10; ++i) {
    while (it != rows.end() && it->first < i) ++it;
    if (it == rows.end() || it->first != i)
      first += (listed++ ? ", " : "") + std::to_string(i);
  }
  const auto missing = n - static_cast<std::int64_t>(rows.size());
  std::fprintf(stderr,
               "\nerror: quasiroll-mpi atlas: terminated (a rank died or the "
               "job was stopped): %lld of %lld cells missing (first: %s); "
               "%lld finished rows are on disk in %s; rerun with --resume to "
               "compute only the missing cells\n",
               static_cast<long long>(missing), static_cast<long long>(n),
               first.c_str(), static_cast<long long>(rows.size()), dir.c_str());
  std::fflush(stderr);
  std::_Exit(3);
}

// Adds the rows of a worker's reply; throws on a worker's I/O error.
std::int64_t AddRows(const std::string& reply, int source,
                     std::map<std::int64_t, std::string>* rows) {
  std::istringstream in(reply);
  std::string line;
  std::getline(in, line);
  if (line != "ok") {
    std::string message((std::istreambuf_iterator<char>(in)), {});
    throw std::runtime_error("rank " + std::to_string(source) + ": " + message);
  }
  std::int64_t added = 0;
  while (std::getline(in, line)) {
    (*rows)[std::stoll(line.substr(0, line.find(',')))] = line;
    ++added;
  }
  return added;
}

struct Progress {
  bool on = false;
  std::int64_t done = 0, total = 0;
  void Add(std::int64_t n) {
    const std::int64_t before = done;
    done += n;
    if (on && (done / 256 != before / 256 || done == total))
      std::fprintf(stderr, "\ratlas: %lld / %lld cells",
                   static_cast<long long>(done), static_cast<long long>(total));
  }
};

// Hands out `todo` in chunks to ranks 1..size-1 until every row is back.
void Dispatch(const bench::AtlasSpec& spec, const std::string& dir,
              const std::vector<std::int64_t>& todo, std::size_t chunk,
              int size, std::map<std::int64_t, std::string>* rows,
              Progress* progress, RankStats* stats) {
  std::vector<int> idle;
  for (int r = size - 1; r >= 1; --r) idle.push_back(r);
  std::size_t next = 0;
  std::map<int, std::vector<std::int64_t>> out;  // chunks out, by rank
  for (;;) {
    while (!idle.empty() && next < todo.size()) {
      const std::size_t n = std::min(chunk, todo.size() - next);
      MPI_Send(todo.data() + next, static_cast<int>(n), MPI_INT64_T,
               idle.back(), kTagCells, MPI_COMM_WORLD);
      out[idle.back()].assign(todo.begin() + next, todo.begin() + next + n);
      next += n;
      idle.pop_back();
    }
    if (out.empty()) break;
    MPI_Status st{};
    if (!WaitForMessageUnless(MPI_ANY_SOURCE, kTagRows, stats, &g_terminate,
                              &st))
      ReportMissingAndExit(spec, dir, *rows, out);
    const std::string reply = ReceiveString(st);
    out.erase(st.MPI_SOURCE);
    idle.push_back(st.MPI_SOURCE);
    try {
      progress->Add(AddRows(reply, st.MPI_SOURCE, rows));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      MPI_Abort(MPI_COMM_WORLD, 3);
    }
  }
}

// mpirun -np 1: rank 0 computes every cell itself, in order.
void ComputeLocally(const bench::AtlasSpec& spec, const std::string& dir,
                    const std::vector<std::int64_t>& todo,
                    std::map<std::int64_t, std::string>* rows,
                    Progress* progress) {
  bench::AtlasPartialFile partial(PartialOfRank(dir, 0));
  EvaluateByPose(spec, todo, [&](const bench::AtlasRow& r) {
    if (g_terminate) ReportMissingAndExit(spec, dir, *rows, {});
    const std::string row = bench::AtlasCsvRow(r);
    partial.Append(row);
    (*rows)[r.cell.index] = row;
    progress->Add(1);
  });
}

// Rank 0's part: resume, meta.json, dispatch, finish, stop the workers.
int AtlasDriver(const AtlasArgs& args, const bench::AtlasSpec& spec,
                std::map<std::int64_t, std::string> rows, int size,
                RankStats* stats) {
  const auto t_start = Clock::now();
  bench::AtlasSummary s;
  std::vector<std::int64_t> todo;
  for (std::int64_t i = 0; i < spec.CellCount(); ++i)
    if (!rows.count(i)) todo.push_back(i);
  s.reused = spec.CellCount() - static_cast<std::int64_t>(todo.size());
  s.computed = static_cast<std::int64_t>(todo.size());
  Progress progress;
  progress.on = args.progress == "bar" || args.progress == "lines" ||
                (args.progress == "auto" && isatty(STDERR_FILENO));
  progress.total = s.computed;
  if (s.reused > 0)
    std::fprintf(stderr, "resume: %lld of %lld cells already done\n",
                 static_cast<long long>(s.reused),
                 static_cast<long long>(spec.CellCount()));
  // Chunks: ~16 per worker, so the last ones even out the workers' ends;
  // at most 64 cells (~0.3 s), at least 1; whole poses (a multiple of the
  // modes: the modes of a pose share its placement).
  const int workers = std::max(1, size - 1);
  const std::size_t modes = spec.modes.size();
  const std::size_t chunk =
      args.chunk > 0
          ? static_cast<std::size_t>(args.chunk)
          : (std::clamp<std::size_t>(todo.size() / (16 * workers), 1, 64) +
             modes - 1) /
                modes * modes;
  if (size == 1)
    ComputeLocally(spec, args.out, todo, &rows, &progress);
  else
    Dispatch(spec, args.out, todo, chunk, size, &rows, &progress, stats);
  if (progress.on) std::fprintf(stderr, "\n");
  s.wall_seconds = Seconds(t_start);
  bench::AtlasOutputInfo info;
  info.extra_meta = {{"mpi", "{\"ranks\":" + std::to_string(size) +
                                 ",\"chunk\":" + std::to_string(chunk) + "}"}};
  s = bench::FinishAtlasOutput(spec, args.out, rows, s, info);
  // Stop the workers only now: a rank waiting inside MPI_Finalize may spin.
  for (int r = 1; r < size; ++r)
    MPI_Send(nullptr, 0, MPI_INT64_T, r, kTagCells, MPI_COMM_WORLD);
  std::vector<std::string> rank_stats(static_cast<std::size_t>(size));
  for (int r = 1; r < size; ++r)
    rank_stats[static_cast<std::size_t>(r)] =
        ReceiveString(WaitForMessage(r, kTagAtlasStats, stats));
  rank_stats[0] = StatsJson(0, *stats);
  WriteRankStats(args.out, rank_stats);
  std::fprintf(stderr,
               "atlas: %lld cells (%lld computed, %lld kept), %lld ok, %lld "
               "edge solves, %.1f s on %d MPI ranks\n",
               static_cast<long long>(s.cells),
               static_cast<long long>(s.computed),
               static_cast<long long>(s.reused), static_cast<long long>(s.ok),
               static_cast<long long>(s.edge_solves), s.wall_seconds, size);
  std::printf("%s/atlas.csv\n", args.out.c_str());
  return 0;
}

}  // namespace

int Atlas(const AtlasArgs& args, int rank, int size) {
  RankStats stats;
  // Every rank loads the spec (every rank evaluates cells of it).
  std::optional<bench::AtlasSpec> spec;
  if (!LoadOnEveryRank(
          [&] {
            spec.emplace(bench::LoadAtlasSpec(args.spec));
            if (args.edge_cells) spec->edge_cells = *args.edge_cells;
          },
          rank))
    return 2;
  std::map<std::int64_t, std::string> rows;
  std::vector<OutputLock> locks;
  const auto begin = [&] {
    if (args.resume) rows = bench::ReadFinishedAtlasRows(*spec, args.out);
    bench::AtlasOutputInfo info;
    info.extra_meta = {{"mpi", "{\"ranks\":" + std::to_string(size) + "}"}};
    bench::BeginAtlasOutput(*spec, args.out, args.resume, info);
  };
  if (!BeginOutput(rank, args.out, begin, &locks)) return 2;
  if (rank != 0) {
    AtlasWorker(*spec, args.out, rank, &stats);
    SendString(StatsJson(rank, stats), 0, kTagAtlasStats);
    return 0;
  }
  return AtlasDriver(args, *spec, std::move(rows), size, &stats);
}

}  // namespace quasiroll::mpi
