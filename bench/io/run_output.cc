#include "quasiroll/bench/io/run_output.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <variant>

#include "quasiroll/bench/io/csv.h"
#include "quasiroll/bench/io/format.h"
#include "quasiroll/core/dae.h"
#include "quasiroll/core/nlp.h"
#include "quasiroll/core/plugin_loader.h"
#include "quasiroll/core/quasi_static_validity.h"
#include "quasiroll/core/slip_regimes.h"
#include "quasiroll_git_commit.h"

namespace quasiroll {

namespace fs = std::filesystem;

bool ReadTextFile(const std::string& path, std::string* text) {
  text->clear();
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream ss;
  ss << in.rdbuf();
  *text = ss.str();
  return true;
}

void AtomicWriteFile(const std::string& path, const std::string& content) {
  const fs::path target(path);
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec)
      throw FileWriteError("cannot create directory '" +
                           target.parent_path().string() +
                           "': " + ec.message());
  }
  std::ostringstream tmp_stream;
  tmp_stream << path << ".tmp." << ::getpid() << "."
             << std::hash<std::thread::id>{}(std::this_thread::get_id());
  const std::string tmp = tmp_stream.str();
  // POSIX calls rather than a stream: errno says why (ENOSPC, EDQUOT), and
  // close(2) reports what a network file system defers to it.
  const auto fail = [&](const std::string& what, int err) {
    std::error_code ignored;
    fs::remove(tmp, ignored);  // a partial file must not hold the space
    throw FileWriteError("cannot write '" + path + "' (" + what + " '" + tmp +
                         "'): " + std::strerror(err));
  };
  const int fd =
      ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("creating", errno);
  for (std::size_t done = 0; done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      fail("writing", err);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) fail("closing", errno);
  std::error_code ec;
  fs::rename(tmp, target, ec);
  if (ec) fail("renaming", ec.value());
}

namespace {
// printf's "%.17g" (std::to_chars with a precision is specified as printf
// with that conversion, so the bytes are the same), "nan" for every NaN;
// ~10x faster than snprintf, which dominated writing trajectory.csv.
void AppendNumber(std::string* out, double v) {
  if (std::isnan(v)) {
    *out += "nan";
    return;
  }
  char buf[32];
  const std::to_chars_result res =
      std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::general, 17);
  out->append(buf, res.ptr);
}
}  // namespace

std::string TrajectoryCsvHeader() {
  std::string h =
      "t,x,y,z,roll,pitch,yaw,vx,vy,vz,wx,wy,wz,phi1,alpha1,delta2,alpha2,"
      "delta3,alpha3";
  for (int i = 1; i <= 3; ++i) {
    const std::string s = std::to_string(i);
    h += ",c" + s + "_x,c" + s + "_y,c" + s + "_z,n" + s + ",t" + s + "_lon,t" +
         s + "_lat,slip" + s + ",use" + s;
  }
  h += ",drift,gap_max,nlp_status,nlp_iters";
  // Added later, at the end (trajectory.csv changes only additively).
  for (int i = 1; i <= 3; ++i) {
    const std::string s = std::to_string(i);
    h += ",sliding_distance" + s + ",creep_distance" + s;
  }
  return h;
}

std::string TrajectoryCsv(const SimulationResult& result) {
  return TrajectoryCsv(result.samples);
}

std::string TrajectoryCsv(const std::vector<TrajectorySample>& samples) {
  std::string out = TrajectoryCsvHeader();
  out += '\n';
  // 66 fields of at most 24 characters each.
  out.reserve(out.size() + samples.size() * 66 * 25);
  for (const TrajectorySample& s : samples) {
    bool first = true;
    auto add = [&out, &first](double v) {
      if (!first) out += ',';
      first = false;
      AppendNumber(&out, v);
    };
    add(s.t);
    for (int k = 0; k < 3; ++k) add(s.position(k));
    for (int k = 0; k < 3; ++k) add(s.rpy(k));
    for (int k = 0; k < 3; ++k) add(s.velocity(k));
    for (int k = 0; k < 3; ++k) add(s.angular_velocity(k));
    for (double j : s.joints) add(j);
    for (const ContactSample& c : s.contacts) {
      for (int k = 0; k < 3; ++k) add(c.point(k));
      add(c.normal_force);
      add(c.traction_lon);
      add(c.traction_lat);
      add(c.slip);
      add(c.friction_use);
    }
    add(s.drift);
    add(s.gap_max);
    out += ',';
    out += s.nlp_status;
    out += ',';
    char buf[16];
    out.append(buf,
               std::to_chars(buf, buf + sizeof(buf), s.nlp_iterations).ptr);
    for (const ContactSample& c : s.contacts) {
      add(c.sliding_distance);
      add(c.creep_distance);
    }
    out += '\n';
  }
  return out;
}

std::string GitCommit() { return QUASIROLL_GIT_COMMIT; }

void WriteLibraryVersions(JsonWriter* json) {
  json->BeginObject();
#ifdef QUASIROLL_LIBRARY_VERSIONS
  // "name=version,name=version,..." from CMake.
  std::stringstream ss(QUASIROLL_LIBRARY_VERSIONS);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) continue;
    json->Key(item.substr(0, eq)).Value(item.substr(eq + 1));
  }
#endif
  json->Key("compiler")
      .Value(
#if defined(__clang__)
          std::string("clang ") + __clang_version__
#elif defined(__GNUC__)
          std::string("gcc ") + __VERSION__
#else
          std::string("unknown")
#endif
      );
  json->EndObject();
}

void WriteBuildOptions(JsonWriter* json) {
  json->BeginObject();
#ifdef QUASIROLL_BUILD_TYPE
  json->Key("type").Value(QUASIROLL_BUILD_TYPE);
  json->Key("cxx_flags").Value(QUASIROLL_CXX_FLAGS);
  json->Key("options").Value(QUASIROLL_BUILD_OPTIONS);
#endif
  json->EndObject();
}

namespace {
template <typename RegistryT>
void WriteBackendList(JsonWriter* json) {
  json->BeginArray();
  for (const std::string& name : RegistryT::Names()) {
    const BackendInfo info = RegistryT::Info(name);
    json->BeginObject();
    json->Key("name").Value(name);
    json->Key("description").Value(info.description);
    json->Key("family").Value(info.family);
    json->Key("library").Value(info.library);
    json->Key("library_version").Value(info.library_version);
    json->Key("thread_safe").Value(info.thread_safe);
    json->Key("roles").BeginArray();
    for (BackendRole role : info.roles) json->Value(ToString(role));
    json->EndArray();
    json->EndObject();
  }
  json->EndArray();
}
}  // namespace

void WriteBackends(JsonWriter* json) {
  json->BeginObject();
  json->Key("nlp");
  WriteBackendList<NlpSolverRegistry>(json);
  json->Key("dae");
  WriteBackendList<IntegratorRegistry>(json);
  json->EndObject();
}

void WritePlugins(JsonWriter* json) {
  json->BeginArray();
  for (const LoadedPlugin& p : LoadedPlugins()) {
    json->BeginObject();
    json->Key("file").Value(p.file);
    json->Key("path").Value(p.path);
    json->Key("sha256").Value(p.sha256);
    json->Key("version").Value(p.version);
    json->Key("nlp").BeginArray();
    for (const std::string& n : p.nlp_backends) json->Value(n);
    json->EndArray();
    json->Key("dae").BeginArray();
    for (const std::string& n : p.integrators) json->Value(n);
    json->EndArray();
    json->EndObject();
  }
  json->EndArray();
}

namespace {
std::string& InvocationText() {
  static std::string text;
  return text;
}
// A word as a POSIX shell reads it back.
std::string ShellQuoted(const std::string& word) {
  if (!word.empty() &&
      word.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVW"
                             "XYZ0123456789_-+=./,:@%") == std::string::npos)
    return word;
  std::string out = "'";
  for (char c : word)
    out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}
}  // namespace

void SetInvocation(int argc, const char* const* argv) {
  std::string text;
  for (int i = 0; i < argc; ++i) text += (i ? " " : "") + ShellQuoted(argv[i]);
  InvocationText() = text;
}

const std::string& Invocation() { return InvocationText(); }

namespace {
std::string LoadedLibraryProviding(const char* symbol) {
  void* address = ::dlsym(RTLD_DEFAULT, symbol);
  Dl_info where{};
  if (address == nullptr || ::dladdr(address, &where) == 0 ||
      where.dli_fname == nullptr)
    return "none";
  return where.dli_fname;
}
}  // namespace

void WriteNumericalLibraries(JsonWriter* json) {
  json->BeginObject();
  json->Key("blas").Value(LoadedLibraryProviding("ddot_"));
  json->Key("lapack").Value(LoadedLibraryProviding("dsytrf_"));
  json->EndObject();
}

const MachineInfo& ThisMachine() {
  static const MachineInfo info = [] {
    MachineInfo m;
    char host[256] = {0};
    if (::gethostname(host, sizeof(host) - 1) != 0) host[0] = 0;
    m.hostname = host;
    m.cpu = "unknown";
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    bool have_model = false;
    while (std::getline(cpuinfo, line) &&
           !(have_model && !std::isnan(m.cpu_mhz))) {
      const auto colon = line.find(':');
      if (colon == std::string::npos || colon + 2 > line.size()) continue;
      if (!have_model && line.rfind("model name", 0) == 0) {
        m.cpu = line.substr(colon + 2);
        have_model = true;
      } else if (std::isnan(m.cpu_mhz) && line.rfind("cpu MHz", 0) == 0) {
        m.cpu_mhz = std::strtod(line.c_str() + colon + 2, nullptr);
      }
    }
    std::ifstream max_freq(
        "/sys/devices/system/cpu/cpu0/cpufreq/cpuinfo_max_freq");
    double khz = 0;
    if (max_freq >> khz && khz > 0) m.cpu_max_mhz = khz / 1000;
    m.hardware_threads = static_cast<int>(std::thread::hardware_concurrency());
    return m;
  }();
  return info;
}

void WriteMachine(JsonWriter* json) {
  const MachineInfo& m = ThisMachine();
  json->BeginObject();
  json->Key("hostname").Value(m.hostname);
  json->Key("cpu").Value(m.cpu);
  json->Key("cpu_mhz").Value(m.cpu_mhz);
  json->Key("cpu_max_mhz").Value(m.cpu_max_mhz);
  json->Key("hardware_threads").Value(m.hardware_threads);
  json->EndObject();
}

std::string IsoTimeNow() {
  const std::time_t now =
      std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&now, &tm);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

void WriteStopEvent(const StopEvent& e, JsonWriter* json) {
  JsonWriter& j = *json;
  if (e.limit.empty()) {
    j.Null();
    return;
  }
  j.BeginObject();
  j.Key("limit").Value(e.limit);
  j.Key("wheel");
  e.wheel > 0 ? (void)j.Value(e.wheel) : (void)j.Null();
  j.Key("located").Value(e.located);
  j.Key("t").Value(e.t);
  j.Key("t_lower").Value(e.t_lower);
  j.Key("t_upper").Value(e.t_upper);
  j.Key("tolerance").Value(e.tolerance);
  j.Key("indicators").BeginObject();
  j.Key("tread_angle").Array(e.indicators.tread_angle);
  j.Key("relative_curvature").Array(e.indicators.relative_curvature);
  j.Key("second_contact").Array(e.indicators.second_contact);
  j.EndObject();
  j.Key("mu_min").Value(e.mu_min);
  j.Key("min_normal_force").Value(e.min_normal_force);
  j.EndObject();
}

namespace {
// "stop_retry": SimulationResult::stop_retry, the twist at or just before
// the stop solved after the run (model.md §8.8, the breakaway); null when
// there is none.
void WriteStopRetry(const std::optional<TrajectorySample>& retry,
                    JsonWriter* json) {
  JsonWriter& j = *json;
  j.Key("stop_retry");
  if (!retry) {
    j.Null();
    return;
  }
  j.BeginObject();
  j.Key("t").Value(retry->t);
  j.Key("speed").Value(retry->velocity.norm());
  j.Key("angular_speed").Value(retry->angular_velocity.norm());
  j.EndObject();
}
}  // namespace

// The located stick/slide switches (core/switch_events.h, docs/formats.md).
void WriteSwitches(const std::vector<SwitchEvent>& switches, JsonWriter* json) {
  JsonWriter& j = *json;
  j.BeginArray();
  for (const SwitchEvent& e : switches) {
    j.BeginObject();
    j.Key("time").Value(e.t);
    j.Key("wheel").Value(e.wheel);
    j.Key("from").Value(RegimeName(e.from_sliding));
    j.Key("to").Value(RegimeName(e.to_sliding));
    j.Key("located").Value(e.located);
    j.Key("t_lower").Value(e.t_lower);
    j.Key("t_upper").Value(e.t_upper);
    j.Key("kind").Value(SwitchKindName(e));
    j.EndObject();
  }
  j.EndArray();
}

std::string SwitchesCsv(const std::vector<SwitchEvent>& switches) {
  std::string out = "t,wheel,from,to,located,t_lower,t_upper,kind\n";
  for (const SwitchEvent& e : switches)
    out += JoinCsvRow({bench::Num(e.t), std::to_string(e.wheel),
                       RegimeName(e.from_sliding), RegimeName(e.to_sliding),
                       e.located ? "true" : "false", bench::Num(e.t_lower),
                       bench::Num(e.t_upper), SwitchKindName(e)}) +
           "\n";
  return out;
}

std::string RunJson(const Scene& scene, const SimulationOptions& options,
                    double dt, double t_end, const SimulationResult& r) {
  JsonWriter j;
  j.BeginObject();
  j.Key("status").Value(r.status);
  j.Key("stop_reason").Value(r.stop_reason);
  j.Key("t_reached").Value(r.t_reached);
  j.Key("mu_min_at_stop").Value(r.mu_min_at_stop);
  j.Key("critical_wheel");  // 1-based, null if none (docs/formats.md)
  r.critical_contact > 0 ? (void)j.Value(r.critical_contact) : (void)j.Null();
  if (!r.success()) j.Key("stop_configuration").Array(r.stop_configuration);
  j.Key("samples").Value(static_cast<int>(r.samples.size()));
  j.Key("counters").BeginObject();
  j.Key("nlp_solves").Value(r.nlp_solves);
  j.Key("nlp_iterations").Value(r.nlp_iterations);
  j.Key("rhs_evaluations").Value(r.rhs_evaluations);
  j.Key("jacobian_evaluations").Value(r.jacobian_evaluations);
  j.Key("steps").Value(r.steps);
  j.Key("rejected_steps").Value(r.rejected_steps);
  j.Key("nlp_iterations_native").Value(r.nlp_iterations_native);
  j.EndObject();
  j.Key("wall_s").Value(r.wall_seconds);
  j.Key("kkt_residual").Value(r.kkt_residual);
  j.Key("step_drift_max").Value(r.step_drift_max);
  j.Key("qs_inertia_ratio").Value(QuasiStaticInertiaRatio(r, scene));
  WriteStopRetry(r.stop_retry, &j);
  const SlipDistances slip = TotalSlipDistances(r.samples);
  j.Key("sliding_distance").Value(slip.sliding);
  j.Key("creep_distance").Value(slip.creep);
  j.Key("event");  // the physical limit the run stopped on (model.md §8.6)
  WriteStopEvent(r.event, &j);
  j.Key("switches");  // stick/slide switches (model.md §8.6)
  WriteSwitches(r.switches, &j);
  j.Key("scene").BeginObject();
  j.Key("name").Value(scene.name);
  j.Key("file").Value(scene.source_path);
  j.Key("mode").Value(ToString(scene.mode));
  j.Key("mu").Value(scene.mu);
  j.Key("epsilon").Value(scene.epsilon);
  j.Key("terrain").Value(scene.terrain ? scene.terrain->Describe() : "");
  j.EndObject();
  j.Key("options").BeginObject();
  j.Key("nlp").Value(options.nlp);
  j.Key("dae").Value(options.dae);
  j.Key("coupling").Value(ToString(options.coupling));
  j.Key("dt").Value(dt);
  j.Key("t_end").Value(t_end);
  // rk_method, sigma, projection_tolerance and dae_index are integrator
  // options now; these keys keep their meaning for the integrators that have
  // them and show the former defaults for the others (dae_options.used is
  // the complete record).
  const OptionValues& dae_used = r.dae_options;
  j.Key("rk_method")
      .Value(dae_used.Has("rk_method") ? dae_used.GetString("rk_method")
                                       : std::string("rk4"));
  j.Key("step").Value(options.integrator.step > 0 ? options.integrator.step
                                                  : dt);
  j.Key("rtol").Value(options.integrator.rtol);
  j.Key("atol").Value(options.integrator.atol);
  j.Key("sigma").Value(dae_used.Has("baumgarte_sigma")
                           ? dae_used.GetDouble("baumgarte_sigma")
                           : 5.0);
  j.Key("projection_tolerance")
      .Value(dae_used.Has("projection_tolerance")
                 ? dae_used.GetDouble("projection_tolerance")
                 : 1e-12);
  j.Key("dae_index")
      .Value(dae_used.Has("dae_index")
                 ? static_cast<int>(dae_used.GetInt("dae_index"))
                 : 2);
  j.Key("nlp_residual_tolerance")
      .Value(options.quasi_static.residual_tolerance);
  // How stops are located (model.md §8.6): every method, by the simulator.
  j.Key("events").BeginObject();
  j.Key("locate").Value(options.locate_events);
  j.Key("method").Value(options.locate_events ? "dense_output_bisection"
                                              : "samples_only");
  j.Key("points").Value(options.event_points);
  j.Key("tolerance").Value(options.event_tolerance);
  // Switches (model.md §8.6): located and recorded in both couplings; the
  // interval restarted at them in coupled mode.
  j.Key("switches").Value(options.locate_switches);
  j.EndObject();
  // Backend options: as given, and as used (every option of the table).
  auto write_options = [&j](const char* key, const GivenOptions& given,
                            const OptionValues& used) {
    j.Key(key).BeginObject();
    j.Key("given").BeginObject();
    for (const auto& [name, text] : given) j.Key(name).Value(text);
    j.EndObject();
    j.Key("used").BeginObject();
    for (const auto& [name, value] : used.values()) {
      j.Key(name);
      if (std::holds_alternative<bool>(value)) {
        j.Value(std::get<bool>(value));
      } else if (std::holds_alternative<long long>(value)) {
        j.Value(std::get<long long>(value));
      } else if (std::holds_alternative<double>(value)) {
        j.Value(std::get<double>(value));
      } else {
        j.Value(std::get<std::string>(value));
      }
    }
    j.EndObject();
    j.EndObject();
  };
  write_options("nlp_options", options.nlp_options, r.nlp_options);
  write_options("dae_options", options.dae_options, r.dae_options);
  j.EndObject();
  j.Key("commit").Value(GitCommit());
  j.Key("library_versions");
  WriteLibraryVersions(&j);
  j.Key("numerical_libraries");
  WriteNumericalLibraries(&j);
  j.Key("machine");
  WriteMachine(&j);
  j.Key("written_at").Value(IsoTimeNow());
  j.EndObject();
  return j.str() + "\n";
}

}  // namespace quasiroll
