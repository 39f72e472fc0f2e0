#include "quasiroll/bench/cli/ipopt_timer_elision.h"

#include <dlfcn.h>
#include <link.h>
#include <sys/resource.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace quasiroll {
namespace {

// Ipopt 3.11 times every phase of every iteration (TimedTask::Start/End in
// IpTimedTask.hpp) with two getrusage(RUSAGE_SELF) system calls each, and
// has no option to stop it (3.14 added timing_statistics). On this machine
// those calls were two thirds of a warm paper-scene solve (1.61 -> 0.54 ms,
// docs/performance.md), and under `bench --jobs 2` two threads' calls also
// contend: RUSAGE_SELF sums over all threads of the process under a lock.
// quasiroll never reads Ipopt's timers (wall_s is its own steady_clock) and
// never sets max_cpu_time, the only behaviour they feed. So this file
// (linked into executables only, see the header) defines getrusage: a call
// whose return address lies in libipopt's code gets zero usage without a system
// call; every other call is forwarded to the next definition (libc's, or a
// sanitizer's interceptor). When libipopt is not a loaded shared object (a
// static Ipopt), everything is forwarded.
struct CodeRanges {
  std::array<std::uintptr_t, 8> begin{}, end{};
  int count = 0;
  bool Contains(std::uintptr_t pc) const {
    for (int i = 0; i < count; ++i)
      if (pc >= begin[i] && pc < end[i]) return true;
    return false;
  }
};

// The executable segments of the loaded libipopt.so*.
CodeRanges FindIpoptCode() {
  CodeRanges ranges;
  dl_iterate_phdr(
      [](dl_phdr_info* info, size_t, void* data) {
        const char* name = info->dlpi_name;
        const char* base = name ? std::strrchr(name, '/') : nullptr;
        base = base ? base + 1 : name;
        if (base == nullptr || std::strncmp(base, "libipopt.so", 11) != 0)
          return 0;
        auto* r = static_cast<CodeRanges*>(data);
        for (int i = 0; i < info->dlpi_phnum && r->count < 8; ++i) {
          const auto& ph = info->dlpi_phdr[i];
          if (ph.p_type != PT_LOAD || !(ph.p_flags & PF_X)) continue;
          r->begin[r->count] = info->dlpi_addr + ph.p_vaddr;
          r->end[r->count] = r->begin[r->count] + ph.p_memsz;
          ++r->count;
        }
        return 1;
      },
      &ranges);
  return ranges;
}

bool TimersEnabledAtStartup() {
  const char* env = std::getenv("QUASIROLL_IPOPT_TASK_TIMERS");
  return env != nullptr && std::strcmp(env, "1") == 0;
}

std::atomic<bool> g_ipopt_task_timers_enabled{TimersEnabledAtStartup()};
thread_local long t_ipopt_timer_calls_elided = 0;

using GetrusageFn = int (*)(int, rusage*);

GetrusageFn NextGetrusage() {
  static const GetrusageFn next =
      reinterpret_cast<GetrusageFn>(dlsym(RTLD_NEXT, "getrusage"));
  return next;
}

}  // namespace

void SetIpoptTaskTimersEnabled(bool enabled) {
  g_ipopt_task_timers_enabled.store(enabled, std::memory_order_relaxed);
}

bool IpoptTaskTimersEnabled() {
  return g_ipopt_task_timers_enabled.load(std::memory_order_relaxed);
}

long IpoptTaskTimerCallsElidedOnThisThread() {
  return t_ipopt_timer_calls_elided;
}

}  // namespace quasiroll

// See the comment above CodeRanges.
extern "C" int getrusage(int who, rusage* usage) noexcept {
  using namespace quasiroll;
  if (usage != nullptr &&
      !g_ipopt_task_timers_enabled.load(std::memory_order_relaxed)) {
    static const CodeRanges ipopt_code = FindIpoptCode();
    const auto caller =
        reinterpret_cast<std::uintptr_t>(__builtin_return_address(0));
    if (ipopt_code.Contains(caller)) {
      std::memset(usage, 0, sizeof(*usage));
      ++t_ipopt_timer_calls_elided;
      return 0;
    }
  }
  const GetrusageFn next = NextGetrusage();
  if (next == nullptr) {
    errno = ENOSYS;
    return -1;
  }
  return next(who, usage);
}
