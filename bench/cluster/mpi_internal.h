// Internal to quasiroll-mpi (not installed: it includes <mpi.h>): the
// message helpers its commands share (mpi_support.cc) and the atlas command
// (mpi_atlas.cc). docs/cluster.md, "MPI driver".
#pragma once

#include <mpi.h>

#include <chrono>
#include <csignal>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "quasiroll/bench/io/output_lock.h"

namespace quasiroll::mpi {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since);
// CPU time of this process (all threads), getrusage(RUSAGE_SELF).
double CpuSeconds();

// Time and CPU time of this rank, in total and while waiting for messages.
struct RankStats {
  Clock::time_point start = Clock::now();
  double cpu_start = CpuSeconds();
  double idle_wall = 0, idle_cpu = 0;
  int tasks = 0;
  double busy_wall = 0;
};

// Waits for a message from `source` with `tag` without spinning: MPI_Iprobe,
// then sleep 50 us, doubling up to 2 ms (Open MPI's blocking receive
// busy-polls). Returns its status.
MPI_Status WaitForMessage(int source, int tag, RankStats* stats);
// The same, but gives up when *stop becomes non-zero (a signal handler's
// flag): true with *status set when a message is there, false if stopped.
bool WaitForMessageUnless(int source, int tag, RankStats* stats,
                          const volatile std::sig_atomic_t* stop,
                          MPI_Status* status);

std::string ReceiveString(const MPI_Status& probed);
void SendString(const std::string& text, int dest, int tag);

// Every rank reports whether it succeeded; true if all did.
bool AllRanksOk(bool ok);
// Runs `load` (reading the input every rank needs) on every rank; true if
// it succeeded everywhere. A failure is reported once on stderr: by rank 0,
// or by the ranks that failed alone (naming rank and host).
bool LoadOnEveryRank(const std::function<void()>& load, int rank);
// Can every rank read a file rank 0 wrote into DIR? Reports the ranks that
// cannot (stderr) and returns false then, on every rank.
bool SharedDirectory(const std::string& dir, int rank);

// Set by SIGTERM once InstallTerminateHandler() ran: mpirun's signal when a
// rank died or the job was stopped (then SIGKILL about a second later).
extern volatile std::sig_atomic_t g_terminate;
void InstallTerminateHandler();
// A worker told to terminate writes nothing more and lingers: mpirun
// SIGKILLs it a second after its SIGTERM. Measured with Open MPI 4.1: when a
// worker died of the SIGTERM instead, mpirun killed rank 0 before its
// report in 1 of ~5 runs; with lingering workers in none of 12. Alone (a
// SIGTERM not from mpirun) it exits after 3 s, and the job ends as above.
[[noreturn]] void Linger();

// Test hook (docs/cluster.md): QUASIROLL_TEST_MPI_KILL=R:N makes worker rank
// R raise SIGKILL after its N-th row (atlas) or when given its (N+1)-th run
// (bench: that run is never done); returns N for
// this rank, 0 otherwise (no kill).
long TestKillAfter(int rank);

// The start of a command writing DIR: rank 0 locks DIR for the lifetime of
// *locks (bench/io/output_lock.h) and runs `begin` (plan, resume read, first
// output); bad input there (std::invalid_argument or std::runtime_error
// subclasses the caller names: a scene error, a locked directory) is
// reported once. Then every rank checks that it sees DIR, and SIGTERM is
// caught (g_terminate). False on every rank when anything failed (exit 2).
bool BeginOutput(int rank, const std::string& dir,
                 const std::function<void()>& begin,
                 std::vector<OutputLock>* locks);

// DIR/mpi.json: {"ranks": [StatsJson of each rank]}.
void WriteRankStats(const std::string& dir,
                    const std::vector<std::string>& rows);
std::string StatsJson(int rank, const RankStats& s);

// `quasiroll-mpi atlas` (mpi_atlas.cc).
struct AtlasArgs {
  std::string spec, out, progress = "auto";
  bool resume = false;
  std::optional<int> edge_cells;  // overrides the spec's
  int chunk = 0;                  // cells per task, 0 = automatic
};
int Atlas(const AtlasArgs& args, int rank, int size);

}  // namespace quasiroll::mpi
