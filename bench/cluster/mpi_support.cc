// Helpers of quasiroll-mpi shared by its commands (bench: mpi_main.cc,
// atlas: mpi_atlas.cc); mpi_internal.h says what each does.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "quasiroll/bench/cluster/mpi_internal.h"
#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/bench/io/run_output.h"
#include "quasiroll/core/scene.h"

namespace quasiroll::mpi {

double Seconds(Clock::time_point since) {
  return std::chrono::duration<double>(Clock::now() - since).count();
}

double CpuSeconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

bool WaitForMessageUnless(int source, int tag, RankStats* stats,
                          const volatile std::sig_atomic_t* stop,
                          MPI_Status* status) {
  const auto t0 = Clock::now();
  const double c0 = CpuSeconds();
  int flag = 0;
  std::chrono::microseconds pause(50);
  for (;;) {
    MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, status);
    if (flag || (stop && *stop)) break;
    std::this_thread::sleep_for(pause);
    pause = std::min(pause * 2, std::chrono::microseconds(2000));
  }
  stats->idle_wall += Seconds(t0);
  stats->idle_cpu += CpuSeconds() - c0;
  return flag != 0;
}

MPI_Status WaitForMessage(int source, int tag, RankStats* stats) {
  MPI_Status status{};
  WaitForMessageUnless(source, tag, stats, nullptr, &status);
  return status;
}

volatile std::sig_atomic_t g_terminate = 0;

namespace {
extern "C" void OnTerminate(int) { g_terminate = 1; }
}  // namespace

void InstallTerminateHandler() { std::signal(SIGTERM, OnTerminate); }

void Linger() {
  std::this_thread::sleep_for(std::chrono::seconds(3));
  std::_Exit(128 + SIGTERM);
}

bool BeginOutput(int rank, const std::string& dir,
                 const std::function<void()>& begin,
                 std::vector<OutputLock>* locks) {
  bool ok = true;
  if (rank == 0) {
    try {
      *locks = LockOutputDirectory(dir, "", "--out");
      begin();
    } catch (const std::invalid_argument& e) {  // bad input, a locked DIR
      std::fprintf(stderr, "error: %s\n", e.what());
      ok = false;
    } catch (const SceneError& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      ok = false;
    }
  }
  if (!AllRanksOk(ok) || !SharedDirectory(dir, rank)) return false;
  InstallTerminateHandler();
  return true;
}

long TestKillAfter(int rank) {
  const char* v = std::getenv("QUASIROLL_TEST_MPI_KILL");
  if (!v) return 0;
  int r = -1;
  long n = 0;
  if (std::sscanf(v, "%d:%ld", &r, &n) != 2 || r != rank) return 0;
  return n;
}

std::string ReceiveString(const MPI_Status& probed) {
  int count = 0;
  MPI_Get_count(&probed, MPI_CHAR, &count);
  std::string text(static_cast<std::size_t>(count), '\0');
  MPI_Recv(text.data(), count, MPI_CHAR, probed.MPI_SOURCE, probed.MPI_TAG,
           MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return text;
}

void SendString(const std::string& text, int dest, int tag) {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, dest, tag,
           MPI_COMM_WORLD);
}

// Every rank reports whether it succeeded; true if all did.
bool AllRanksOk(bool ok) {
  int mine = ok ? 1 : 0, all = 0;
  MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  return all == 1;
}

bool LoadOnEveryRank(const std::function<void()>& load, int rank) {
  std::string error;
  try {
    load();
  } catch (const std::exception& e) {
    error = e.what();
  }
  int rank0_ok = error.empty() ? 1 : 0;
  MPI_Bcast(&rank0_ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
  if (AllRanksOk(error.empty())) return true;
  if (!error.empty() && rank == 0)
    std::fprintf(stderr, "error: %s\n", error.c_str());
  else if (!error.empty() && rank0_ok)
    std::fprintf(stderr, "error: rank %d on %s: %s\n", rank,
                 ThisMachine().hostname.c_str(), error.c_str());
  return false;
}

// Can every rank read a file rank 0 wrote into DIR? (Workers write their
// trajectories there and rank 0 relies on them for --resume.)
bool SharedDirectory(const std::string& dir, int rank) {
  std::string token(32, '\0');
  if (rank == 0) {
    std::random_device rd;
    std::snprintf(token.data(), token.size(), "%08x%08x", rd(), rd());
    AtomicWriteFile(dir + "/.mpi-probe", token);
  }
  MPI_Bcast(token.data(), static_cast<int>(token.size()), MPI_CHAR, 0,
            MPI_COMM_WORLD);
  std::ifstream in(dir + "/.mpi-probe", std::ios::binary);
  std::string seen((std::istreambuf_iterator<char>(in)), {});
  const bool ok = seen == token;
  if (!ok)
    std::fprintf(stderr,
                 "error: rank %d on %s cannot see %s/.mpi-probe that rank 0 "
                 "wrote: --out must be on a file system shared by all ranks\n",
                 rank, ThisMachine().hostname.c_str(), dir.c_str());
  const bool all = AllRanksOk(ok);
  if (rank == 0) std::remove((dir + "/.mpi-probe").c_str());
  return all;
}

void WriteRankStats(const std::string& dir,
                    const std::vector<std::string>& rows) {
  std::string json = "{\"ranks\":[";
  for (std::size_t k = 0; k < rows.size(); ++k)
    json += (k ? "," : "") + rows[k];
  json += "]}\n";
  AtomicWriteFile(dir + "/mpi.json", json);
}

std::string StatsJson(int rank, const RankStats& s) {
  JsonWriter w;
  w.BeginObject();
  w.Key("rank").Value(rank);
  w.Key("host").Value(ThisMachine().hostname);
  w.Key("tasks").Value(s.tasks);
  w.Key("wall_s").Value(Seconds(s.start));
  w.Key("cpu_s").Value(CpuSeconds() - s.cpu_start);
  w.Key("busy_wall_s").Value(s.busy_wall);
  w.Key("idle_wall_s").Value(s.idle_wall);
  w.Key("idle_cpu_s").Value(s.idle_cpu);
  w.EndObject();
  return w.str();
}

}  // namespace quasiroll::mpi
