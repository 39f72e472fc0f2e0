// The getrusage elision for Ipopt 3.11's task timers
// (bench/cli/ipopt_timer_elision.{h,cc}), linked into this test as into the
// quasiroll CLI: it must change no result and leave other callers alone.
// That no quasiroll library defines getrusage is checked by
// tests/cli/no_libc_symbols_test.sh.
#include "quasiroll/bench/cli/ipopt_timer_elision.h"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cerrno>
#include <string>
#include <vector>

#include "quasiroll/conformance/nlp_reference_problems.h"
#include "quasiroll/core/nlp.h"

namespace quasiroll {
namespace {

// Ipopt 3.11's task timers (getrusage around every phase) are answered
// without a system call in programs that link bench/cli/ipopt_timer_elision.cc
// (this test, like the quasiroll CLI, does). Eliding them must change
// no result: every reference problem gives bit-identical answers, statuses
// and iteration counts with the real timers and without, on fresh solvers.
TEST(IpoptBackendTest, ElidedTaskTimersChangeNoResult) {
  RegisterBuiltinNlpSolvers();
  struct Outcome {
    NlpStatus status;
    int iterations;
    Eigen::VectorXd x;
  };
  auto solve_all = [](bool timers_enabled) {
    SetIpoptTaskTimersEnabled(timers_enabled);
    std::vector<Outcome> out;
    for (const auto& p : MakeReferenceProblems()) {
      auto solver = NlpSolverRegistry::Create("ipopt");
      NlpResult r;
      const NlpStatus status =
          solver->Solve(*p, p->starting_point(), NlpOptions(), &r);
      out.push_back({status, r.iterations, r.x});
    }
    SetIpoptTaskTimersEnabled(false);
    return out;
  };
  const long before = IpoptTaskTimerCallsElidedOnThisThread();
  const std::vector<Outcome> real = solve_all(true);
  EXPECT_EQ(IpoptTaskTimerCallsElidedOnThisThread(), before)
      << "timers enabled, yet calls were elided";
  const std::vector<Outcome> elided = solve_all(false);
  // Each Ipopt iteration starts and ends several timed tasks.
  EXPECT_GT(IpoptTaskTimerCallsElidedOnThisThread(), before + 100)
      << "Ipopt's getrusage calls did not reach quasiroll's definition";
  ASSERT_EQ(real.size(), elided.size());
  const auto problems = MakeReferenceProblems();
  for (size_t i = 0; i < real.size(); ++i) {
    const std::string name = problems[i]->name();
    EXPECT_EQ(real[i].status, elided[i].status) << name;
    EXPECT_EQ(real[i].iterations, elided[i].iterations) << name;
    EXPECT_EQ(real[i].x, elided[i].x) << name;  // bitwise
  }
}

// Callers outside libipopt still get the kernel's answer.
TEST(IpoptBackendTest, OtherGetrusageCallersAreForwarded) {
  const long before = IpoptTaskTimerCallsElidedOnThisThread();
  rusage usage{};
  ASSERT_EQ(getrusage(RUSAGE_SELF, &usage), 0);
  EXPECT_GT(usage.ru_maxrss, 0) << "a zero answer, not the kernel's";
  EXPECT_EQ(IpoptTaskTimerCallsElidedOnThisThread(), before);
  errno = 0;
  EXPECT_EQ(getrusage(12345, &usage), -1);  // invalid `who`, as libc says
  EXPECT_EQ(errno, EINVAL);
}

}  // namespace
}  // namespace quasiroll
