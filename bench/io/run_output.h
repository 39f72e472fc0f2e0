// Files written by `quasiroll run` and the benchmark harness (docs/formats.md):
// trajectory.csv, run.json, and the metadata every result carries.
#pragma once

#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "quasiroll/bench/io/json_writer.h"
#include "quasiroll/core/scene.h"
#include "quasiroll/core/simulator.h"

namespace quasiroll {

// A file could not be written (a full disk, no permission): an I/O failure
// that stops a suite, never a result of one run or reference.
class FileWriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Writes `content` to `path` atomically: a temporary file in the same
// directory, then rename(2); a reader sees the old file or the whole new one,
// also after the process is killed. Creates parent directories. Throws
// FileWriteError naming the path and the system's reason ("No space left on
// device") on I/O failure, after removing the temporary file.
void AtomicWriteFile(const std::string& path, const std::string& content);
// The whole file, bytes as they are, into *text; false (and *text empty) if
// it cannot be opened.
bool ReadTextFile(const std::string& path, std::string* text);

// trajectory.csv: the header line (no trailing newline) and the whole file.
std::string TrajectoryCsvHeader();
std::string TrajectoryCsv(const SimulationResult& result);
// The same format for any samples (e.g. SimulationResult::checkpoints).
std::string TrajectoryCsv(const std::vector<TrajectorySample>& samples);

// switches/<run_id>.csv: the located stick/slide switches, a row each
// (t, wheel, from, to, located, t_lower, t_upper; docs/formats.md).
std::string SwitchesCsv(const std::vector<SwitchEvent>& switches);

// Short commit hash the binary was built from ("unknown" when built outside
// a git checkout), with "-dirty" when the tree had uncommitted changes to
// tracked files at build time (cmake/QuasirollGitCommit.cmake).
std::string GitCommit();
// {"eigen": "3.4.0", ...}: versions seen at configure time.
void WriteLibraryVersions(JsonWriter* json);
// The files the process's BLAS (ddot_) and LAPACK (dsytrf_) calls bind to, or
// "none": {"blas": "/usr/lib/.../blas/libblas.so.3", "lapack": ...}. Which
// implementation is loaded can change Ipopt's last digits
// (docs/performance.md).
void WriteNumericalLibraries(JsonWriter* json);
// The machine this process runs on (read once, then cached).
struct MachineInfo {
  std::string hostname;  // gethostname(2)
  std::string cpu;       // first "model name" of /proc/cpuinfo, or "unknown"
  int hardware_threads = 0;
  // First "cpu MHz" of /proc/cpuinfo (the clock when the process started;
  // NaN if absent) and the rated maximum of cpufreq's cpuinfo_max_freq
  // (NaN without cpufreq, e.g. in most virtual machines).
  double cpu_mhz = std::numeric_limits<double>::quiet_NaN();
  double cpu_max_mhz = std::numeric_limits<double>::quiet_NaN();
};
const MachineInfo& ThisMachine();
// How this binary was built: {"type": CMAKE_BUILD_TYPE, "cxx_flags": ...,
// "options": "QUASIROLL_WITH_IPOPT=ON,..."} (anything that can change the
// numbers; `quasiroll merge` requires it to agree).
void WriteBuildOptions(JsonWriter* json);
// Host name, CPU model, clock (cpu_mhz, cpu_max_mhz: null when unknown),
// core count.
void WriteMachine(JsonWriter* json);
// The registered backends with their BackendInfo (core/backend_info.h):
// {"nlp": [{"name", "description", "family", "library", "library_version",
// "thread_safe", "roles": [...]}, ...], "dae": [...]}, in name order.
void WriteBackends(JsonWriter* json);
// The plugins loaded into this process (core/plugin_loader.h): [{"file",
// "path", "sha256", "version", "nlp": [...], "dae": [...]}, ...].
void WritePlugins(JsonWriter* json);
// The program's command line, recorded once by main() (shell-quoted words;
// "" when none was recorded, e.g. in the library's own tests).
void SetInvocation(int argc, const char* const* argv);
const std::string& Invocation();
std::string IsoTimeNow();

// run.json's "event" (docs/formats.md): null when the run met no physical
// limit, else {"limit", "wheel", "located", "t", "t_lower", "t_upper",
// "tolerance", "indicators": {"tread_angle", "relative_curvature",
// "second_contact"}, "mu_min", "min_normal_force"}.
void WriteStopEvent(const StopEvent& event, JsonWriter* json);

// run.json of `quasiroll run`.
std::string RunJson(const Scene& scene, const SimulationOptions& options,
                    double dt, double t_end, const SimulationResult& result);

}  // namespace quasiroll
