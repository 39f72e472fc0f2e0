// quasiroll-mpi: `quasiroll bench` over MPI ranks (docs/cluster.md).
//
//   mpirun -np K quasiroll-mpi bench --suite FILE --out DIR [--filter RE]
//                                    [--resume] [--progress MODE]
//
// Rank 0 plans the suite (PlanSuite: filter, resume, references), hands out
// work one task at a time and writes runs.csv and meta.json exactly as
// `quasiroll bench --jobs 1` does; ranks 1..K-1 execute tasks. Tasks are the
// references first (a run waits for its reference), then the runs, biggest
// estimated cost first (bench/harness/shard.h), to whichever worker is free:
// run costs vary 1000x, so a static split would leave ranks idle. A worker
// computes a reference into DIR/references/ and keeps it; a run executes
// with the shared harness step ExecuteRun (row + trajectory + runs/<id>.csv
// written by the worker; DIR must be on a file system every rank sees,
// checked at start) and its row goes back to rank 0. A failing run is a
// row; only an I/O error stops the job (MPI_Abort; --resume continues).
//
// Idle ranks do not spin: Open MPI's blocking receive busy-polls (a waiting
// rank would burn a core), so every wait here is MPI_Iprobe plus a sleep
// that grows from 50 us to 2 ms (measured CPU of idle ranks: DIR/mpi.json,
// docs/cluster.md). Everything MPI stays in this file, the helpers both
// commands share (mpi_support.cc) and the atlas command (mpi_atlas.cc):
//
//   mpirun -np K quasiroll-mpi atlas --spec FILE --out DIR [--resume]
#include <mpi.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "quasiroll/bench/cluster/mpi_internal.h"
#include "quasiroll/bench/harness/harness.h"
#include "quasiroll/bench/harness/shard.h"
#include "quasiroll/bench/harness/suite.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/output_lock.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/initial_configuration.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/plugin_loader.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::mpi {
namespace {

using bench::ReferenceJob;

enum Tag : int { kTagTask = 1, kTagResult = 2, kTagStats = 3 };
enum TaskKind : int { kReference = 0, kRun = 1, kStop = 2 };

void SendTask(int kind, int grid_index, int dest) {
  const int task[2] = {kind, grid_index};
  MPI_Send(task, 2, MPI_INT, dest, kTagTask, MPI_COMM_WORLD);
}

std::string Fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// ------------------------------------------------------------- worker ----

// References this worker has computed or loaded, by key.
class ReferenceCache {
 public:
  ReferenceCache(const bench::Suite& suite, const std::string& dir)
      : suite_(suite), dir_(dir) {}
  const ReferenceJob& For(const bench::RunSpec& run) {
    ReferenceJob job = bench::ReferenceJobFor(suite_, run);
    auto it = jobs_.find(job.key);
    if (it == jobs_.end()) {
      job.Compute(dir_, suite_.reference);  // loads it if already cached
      it = jobs_.emplace(job.key, std::move(job)).first;
    }
    return it->second;
  }

 private:
  const bench::Suite& suite_;
  std::string dir_;
  std::map<std::string, ReferenceJob> jobs_;
};

void Worker(const bench::Suite& suite, const std::string& dir, int rank,
            RankStats* stats) {
  ReferenceCache references(suite, dir);
  const long kill_after = TestKillAfter(rank);
  for (long runs = 0;;) {
    MPI_Status st{};
    if (!WaitForMessageUnless(0, kTagTask, stats, &g_terminate, &st)) Linger();
    int task[2] = {0, 0};
    MPI_Recv(task, 2, MPI_INT, st.MPI_SOURCE, kTagTask, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    if (task[0] == kStop) break;
    const auto t0 = Clock::now();
    const bench::RunSpec& run =
        suite.runs.at(static_cast<std::size_t>(task[1]));
    std::string reply =
        std::to_string(task[0]) + "\n" + std::to_string(task[1]) + "\n";
    try {
      const ReferenceJob& ref = references.For(run);
      if (task[0] == kReference) {
        reply += "ok\n" + ref.error;
      } else {
        // Test hook: die holding a run it will never finish (so at least
        // that one is missing whatever the other workers do meanwhile).
        if (runs++ == kill_after && kill_after > 0) std::raise(SIGKILL);
        const bench::RunOutcome out = bench::ExecuteRun(
            suite, run, bench::TerrainId(run, suite.scenes[run.scene_index]),
            ref, dir);
        reply += "ok\n" + out.status + "\n" + Fmt(out.t_reached) + "\n" +
                 Fmt(out.wall_seconds) + "\n" + out.row;
      }
    } catch (const std::exception& e) {  // I/O: the job cannot go on
      reply += std::string("io_error\n") + e.what();
    }
    stats->busy_wall += Seconds(t0);
    ++stats->tasks;
    SendString(reply, 0, kTagResult);
  }
}

// ------------------------------------------------------------- rank 0 ----

struct Task {
  int kind;
  int grid_index;  // the run (kRun), or a run whose reference it is
  double cost;
};

class Dispatcher {
 public:
  Dispatcher(const bench::Suite& suite, bench::SuitePlan* plan,
             bench::Progress* progress)
      : plan_(*plan), progress_(*progress) {
    for (std::size_t i = 0; i < plan_.selected.size(); ++i)
      selected_of_grid_[plan_.selected[i]->index] = static_cast<int>(i);
    waiting_.resize(plan_.references.size());
    for (int i : plan_.pending) waiting_[plan_.run_reference[i]].push_back(i);
    for (std::size_t r = 0; r < plan_.references.size(); ++r) {
      const ReferenceJob& j = plan_.references[r];
      references_.push_back({kReference,
                             plan_.selected[waiting_[r].front()]->index,
                             bench::EstimatedReferenceCost(
                                 j.scene.dt, j.scene.t_end, suite.reference)});
    }
    SortBiggestFirst(&references_);
  }

  // Next task, or false if none is ready now. A run of an exclusive group
  // (suite key `exclusive`) is handed out only when no other task is out,
  // and nothing else while it is: it runs alone on the whole job (ranks may
  // share a node), after the shared runs that are ready.
  bool Next(Task* task) {
    if (alone_out_) return false;
    if (!references_.empty()) {
      *task = references_.back();
      references_.pop_back();
    } else if (!ready_.empty()) {
      *task = ready_.back();
      ready_.pop_back();
    } else if (!alone_.empty() && out_ == 0) {
      *task = alone_.back();
      alone_.pop_back();
      alone_out_ = true;
    } else {
      return false;
    }
    ++out_;
    return true;
  }

  // Handles a worker's reply; throws on a worker's I/O error.
  void Result(const std::string& reply) {
    --out_;
    alone_out_ = false;
    std::istringstream in(reply);
    std::string kind, grid, verdict;
    std::getline(in, kind);
    std::getline(in, grid);
    std::getline(in, verdict);
    const int i = selected_of_grid_.at(std::stoi(grid));
    if (verdict != "ok") {
      std::string message((std::istreambuf_iterator<char>(in)), {});
      throw std::runtime_error("run " + plan_.selected[i]->run_id + ": " +
                               message);
    }
    if (std::stoi(kind) == kReference) {
      const int r = plan_.run_reference[i];
      std::string error((std::istreambuf_iterator<char>(in)), {});
      if (!error.empty())
        progress_.Message("reference for scene " + plan_.references[r].label +
                          " failed: " + error);
      for (int k : waiting_[r])
        (plan_.selected[k]->exclusive ? alone_ : ready_)
            .push_back({kRun, plan_.selected[k]->index,
                        bench::EstimatedRunCost(*plan_.selected[k])});
      SortBiggestFirst(&ready_);
      SortBiggestFirst(&alone_);
      return;
    }
    std::string status, t_reached, wall, row;
    std::getline(in, status);
    std::getline(in, t_reached);
    std::getline(in, wall);
    std::getline(in, row);
    plan_.rows[i] = row;
    ++runs_done_;
    progress_.Done(plan_.selected[i]->run_id, status, std::stod(t_reached),
                   std::stod(wall));
  }

  bool AllRunsDone() const {
    return runs_done_ == static_cast<int>(plan_.pending.size());
  }

 private:
  // Ascending, so that back() is the biggest; ties: lower grid index last
  // (taken first).
  static void SortBiggestFirst(std::vector<Task>* tasks) {
    std::stable_sort(tasks->begin(), tasks->end(),
                     [](const Task& a, const Task& b) {
                       if (a.cost != b.cost) return a.cost < b.cost;
                       return a.grid_index > b.grid_index;
                     });
  }

  bench::SuitePlan& plan_;
  bench::Progress& progress_;
  std::map<int, int> selected_of_grid_;
  std::vector<std::vector<int>> waiting_;  // per reference: selected runs
  std::vector<Task> references_, ready_, alone_;  // alone_: exclusive runs
  int out_ = 0;             // tasks handed out, not yet answered
  bool alone_out_ = false;  // the task out is an exclusive run
  int runs_done_ = 0;
};

// Runs the plan on rank 0 alone (mpirun -np 1): the same steps in order.
void RunLocally(const bench::Suite& suite, bench::SuitePlan* plan,
                const std::string& dir, bench::Progress* progress) {
  for (ReferenceJob& j : plan->references) {
    j.Compute(dir, suite.reference);
    if (!j.error.empty())
      progress->Message("reference for scene " + j.label +
                        " failed: " + j.error);
  }
  for (int i : plan->pending) {
    const bench::RunOutcome out =
        bench::ExecuteRun(suite, *plan->selected[i], plan->terrain_ids[i],
                          plan->references[plan->run_reference[i]], dir);
    plan->rows[i] = out.row;
    progress->Done(plan->selected[i]->run_id, out.status, out.t_reached,
                   out.wall_seconds);
  }
}

// ------------------------------------------------------------------ CLI ----

struct Args {
  std::string suite, out, filter, progress = "auto";
  bool resume = false;
};

// After SIGTERM on rank 0: the selected runs without a finished row on disk
// (what --resume will compute; a worker still writing makes the count one
// too high, never too low), on stderr; exit 3.
[[noreturn]] void ReportMissingRunsAndExit(const bench::SuitePlan& plan,
                                           const std::string& dir) {
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  int missing = 0;
  std::string first;
  for (int i : plan.pending) {
    const std::string& id = plan.selected[static_cast<std::size_t>(i)]->run_id;
    std::string row;
    if (ReadTextFile(dir + "/runs/" + id + ".csv", &row) && !row.empty() &&
        row.back() == '\n')
      continue;
    if (missing++ < 5) first += (first.empty() ? "" : ", ") + id;
  }
  std::fprintf(stderr,
               "\nerror: quasiroll-mpi bench: terminated (a rank died or the "
               "job was stopped): %d of %zu runs missing (first: %s); the "
               "finished runs are on disk in %s; rerun with --resume to "
               "compute only the missing runs\n",
               missing, plan.pending.size(), first.c_str(), dir.c_str());
  std::fflush(stderr);
  std::_Exit(3);
}

int Bench(const Args& args, int rank, int size) {
  RankStats stats;
  // Every rank loads the suite (deterministic: same runs, same order).
  std::optional<bench::Suite> suite;
  if (!LoadOnEveryRank([&] { suite.emplace(bench::LoadSuite(args.suite)); },
                       rank))
    return 2;

  bench::HarnessOptions options;
  options.out_dir = args.out;
  options.filter = args.filter;
  options.resume = args.resume;
  options.jobs = 1;  // one run at a time per rank
  options.mpi_ranks = size;
  options.progress = args.progress == "auto"    ? -1
                     : args.progress == "none"  ? 0
                     : args.progress == "lines" ? 1
                                                : 2;
  const auto t_start = Clock::now();
  const std::string start_time = IsoTimeNow();
  std::optional<bench::SuitePlan> plan;
  std::vector<OutputLock> locks;
  const auto begin = [&] {
    plan.emplace(bench::PlanSuite(*suite, options));
    bench::BeginSuiteOutput(*suite, options, *plan, options.jobs, start_time);
  };
  if (!BeginOutput(rank, args.out, begin, &locks)) return 2;

  if (rank != 0) {
    Worker(*suite, args.out, rank, &stats);
    SendString(StatsJson(rank, stats), 0, kTagStats);
    return 0;
  }

  bench::Progress progress(options.log, options.progress,
                           static_cast<int>(plan->pending.size()));
  if (plan->resumed > 0)
    progress.Message("resume: " + std::to_string(plan->resumed) + " of " +
                     std::to_string(plan->selected.size()) +
                     " runs already done");
  if (size == 1) {
    RunLocally(*suite, &*plan, args.out, &progress);
  } else {
    Dispatcher dispatcher(*suite, &*plan, &progress);
    std::vector<int> idle;
    for (int r = 1; r < size; ++r) idle.push_back(r);
    int busy = 0;
    for (;;) {
      Task task{};
      while (!idle.empty() && dispatcher.Next(&task)) {
        SendTask(task.kind, task.grid_index, idle.back());
        idle.pop_back();
        ++busy;
      }
      if (busy == 0) break;  // nothing running, nothing ready: all done
      MPI_Status st{};
      if (!WaitForMessageUnless(MPI_ANY_SOURCE, kTagResult, &stats,
                                &g_terminate, &st))
        ReportMissingRunsAndExit(*plan, args.out);
      const std::string reply = ReceiveString(st);
      --busy;
      idle.push_back(st.MPI_SOURCE);
      try {
        dispatcher.Result(reply);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "error: rank %d: %s\n", st.MPI_SOURCE, e.what());
        MPI_Abort(MPI_COMM_WORLD, 3);
      }
    }
    if (!dispatcher.AllRunsDone()) {
      std::fprintf(stderr, "internal error: runs left undispatched\n");
      MPI_Abort(MPI_COMM_WORLD, 3);
    }
  }
  const bench::HarnessSummary s = bench::FinishSuiteOutput(
      *suite, options, *plan, options.jobs, start_time, Seconds(t_start));
  // Stop the workers only now: a rank waiting inside MPI_Finalize may spin.
  for (int r = 1; r < size; ++r) SendTask(kStop, 0, r);
  std::vector<std::string> rank_stats(static_cast<std::size_t>(size));
  for (int r = 1; r < size; ++r) {
    const MPI_Status st = WaitForMessage(r, kTagStats, &stats);
    rank_stats[static_cast<std::size_t>(r)] = ReceiveString(st);
  }
  rank_stats[0] = StatsJson(0, stats);
  WriteRankStats(args.out, rank_stats);
  std::fprintf(stderr,
               "suite %s: %d runs (%d selected, %d executed, %d resumed), %d "
               "not successful, %.1f s on %d MPI ranks\n",
               suite->name.c_str(), s.total, s.selected, s.executed, s.resumed,
               s.failures, s.wall_seconds, size);
  std::printf("%s/runs.csv\n", args.out.c_str());
  return 0;
}

}  // namespace
}  // namespace quasiroll::mpi

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  CLI::App app{
      "quasiroll-mpi: quasiroll bench and quasiroll atlas over MPI ranks "
      "(mpirun -np K quasiroll-mpi bench|atlas ...); rank 0 dispatches, "
      "ranks 1..K-1 run"};
  app.require_subcommand(1);
  quasiroll::mpi::Args args;
  CLI::App* bench = app.add_subcommand(
      "bench", "Run a benchmark suite; writes DIR/runs.csv as quasiroll bench");
  bench->add_option("--suite", args.suite, "Suite YAML file")->required();
  std::vector<std::string> plugins;
  bench->add_option("--plugin", plugins,
                    "Load backends from a plugin library (repeatable; also "
                    "$QUASIROLL_PLUGIN_PATH; docs/plugins.md)");
  bench
      ->add_option("--out", args.out,
                   "Output directory (on a file system all ranks share)")
      ->required();
  bench->add_option(
      "--filter", args.filter,
      "Keep only runs whose run_id matches this regex (ECMAScript)");
  bench->add_flag("--resume", args.resume,
                  "Skip runs already finished in DIR/runs/");
  bench
      ->add_option("--progress", args.progress,
                   "auto (bar on a TTY, else lines) | bar | lines | none")
      ->check(CLI::IsMember({"auto", "bar", "lines", "none"}))
      ->capture_default_str();
  quasiroll::mpi::AtlasArgs atlas_args;
  CLI::App* atlas = app.add_subcommand(
      "atlas",
      "The traversability atlas of a spec; writes DIR/atlas.csv as "
      "quasiroll atlas (docs/cluster.md)");
  atlas->add_option("--spec", atlas_args.spec, "Atlas spec YAML")->required();
  atlas->add_option("--plugin", plugins,
                    "Load backends from a plugin library (the edge study's "
                    "NLP backends; repeatable)");
  atlas
      ->add_option("--out", atlas_args.out,
                   "Output directory (on a file system all ranks share)")
      ->required();
  atlas->add_flag("--resume", atlas_args.resume,
                  "Keep the finished rows in DIR (atlas.csv and the partial "
                  "files of every rank) and compute only the missing cells");
  atlas
      ->add_option("--edge-cells", atlas_args.edge_cells,
                   "Cells of the edge-reliability study (overrides the "
                   "spec's edge_cells; 0 = none)")
      ->check(CLI::Range(0, 100000));
  atlas
      ->add_option("--chunk", atlas_args.chunk,
                   "Cells per task (default: about 16 tasks per worker, "
                   "1 to 64 cells)")
      ->check(CLI::Range(1, 1000000));
  atlas
      ->add_option("--progress", atlas_args.progress,
                   "auto (on a TTY) | bar | lines | none")
      ->check(CLI::IsMember({"auto", "bar", "lines", "none"}))
      ->capture_default_str();
  int code = 0;
  quasiroll::SetInvocation(argc, argv);
  try {
    app.parse(argc, argv);
    // Every rank loads the same plugins before the suite names backends.
    quasiroll::RegisterBuiltinNlpSolvers();
    quasiroll::RegisterBuiltinIntegrators();
    bool plugins_loaded = true;
    try {
      quasiroll::LoadPlugins(plugins);
    } catch (const std::exception& e) {  // bad input: exit 2, as quasiroll
      if (rank == 0) std::cerr << "error: " << e.what() << "\n";
      plugins_loaded = false;
      code = 2;
    }
    if (plugins_loaded)
      code = atlas->parsed() ? quasiroll::mpi::Atlas(atlas_args, rank, size)
                             : quasiroll::mpi::Bench(args, rank, size);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) {
      if (rank == 0) app.exit(e);
    } else {
      if (rank == 0) std::cerr << "error: " << e.what() << "\n";
      code = 2;
    }
  } catch (const std::exception& e) {
    std::cerr << "internal error (rank " << rank << "): " << e.what() << "\n";
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  MPI_Finalize();
  return code;
}
