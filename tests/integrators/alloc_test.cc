// The RK backends must not touch the heap inside a warmed-up Integrate() call
// (the zoh client calls Integrate thousands of times per simulation).
//
// This executable replaces malloc (glibc: symbol interposition, forwarding to
// __libc_malloc) and counts calls made between two points. Eigen allocates
// through std::malloc and operator new ends in malloc, so every heap
// allocation is seen. Not meaningful under AddressSanitizer, which owns
// malloc: the test is skipped there.
#include <gtest/gtest.h>

#include <atomic>
#include <cstddef>
#include <cstdlib>

#include "quasiroll/core/dae.h"
#include "tests/integrators/test_problems.h"

#if defined(__SANITIZE_ADDRESS__)
#define QUASIROLL_COUNT_MALLOC 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define QUASIROLL_COUNT_MALLOC 0
#endif
#endif
#if !defined(QUASIROLL_COUNT_MALLOC) && defined(__GLIBC__)
#define QUASIROLL_COUNT_MALLOC 1
#endif
#ifndef QUASIROLL_COUNT_MALLOC
#define QUASIROLL_COUNT_MALLOC 0
#endif

namespace {
std::atomic<long> g_mallocs{0};
std::atomic<bool> g_counting{false};
}  // namespace

#if QUASIROLL_COUNT_MALLOC
extern "C" void* __libc_malloc(std::size_t size);
extern "C" void* malloc(std::size_t size) noexcept {
  if (g_counting.load(std::memory_order_relaxed))
    g_mallocs.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
#endif

namespace quasiroll {
namespace {

struct Case {
  const char* backend;
  const char* method;  // rk_method option
  double step;
};

TEST(IntegratorAllocationTest, WarmRkCallsDoNotAllocate) {
  if (!QUASIROLL_COUNT_MALLOC) GTEST_SKIP() << "malloc cannot be counted here";
  {  // The counter must see Eigen's allocations, or the test proves nothing.
    g_mallocs = 0;
    g_counting = true;
    Eigen::VectorXd probe(100);
    g_counting = false;
    probe.setZero();
    ASSERT_GT(g_mallocs.load(), 0);
  }
  RegisterBuiltinIntegrators();
  const Case cases[] = {{"rk-baumgarte", "rk4", 0.0},
                        {"rk-projection", "rk4", 0.0},
                        {"rk-baumgarte", "dp54", 0.0},
                        {"rk-projection", "bs32", 0.01}};
  for (const Case& c : cases) {
    auto integrator = IntegratorRegistry::Create(c.backend);
    integrator->SetBackendOptions({{"rk_method", c.method}});
    testing::PendulumOde pendulum;
    testing::FallingBodyOde falling;  // exercises the event path
    IntegratorOptions o;
    o.step = c.step;
    IntegratorResult r;
    Eigen::VectorXd y = pendulum.AtAngle(0.4);
    Eigen::VectorXd z = Eigen::Vector2d(1.0, 0.0);
    // Warm-up call sizes the workspaces.
    ASSERT_EQ(integrator->Integrate(pendulum, 0.0, 0.05, y, o, &r),
              IntegratorStatus::kSuccess);
    g_mallocs = 0;
    g_counting = true;
    double t = 0.05;
    for (int k = 0; k < 20; ++k, t += 0.05)
      integrator->Integrate(pendulum, t, t + 0.05, y, o, &r);
    g_counting = false;
    EXPECT_EQ(r.status, IntegratorStatus::kSuccess) << r.message;
    EXPECT_EQ(g_mallocs.load(), 0) << c.backend << " " << c.method;

    // Event path: warm up on the falling body (different sizes), then count.
    IntegratorResult re;
    ASSERT_EQ(integrator->Integrate(falling, 0.0, 1.0, z, o, &re),
              IntegratorStatus::kEvent);
    z = Eigen::Vector2d(1.0, 0.0);
    g_mallocs = 0;
    g_counting = true;
    integrator->Integrate(falling, 0.0, 1.0, z, o, &re);
    g_counting = false;
    EXPECT_EQ(re.status, IntegratorStatus::kEvent);
    EXPECT_EQ(g_mallocs.load(), 0) << c.backend << " events";
  }
}

}  // namespace
}  // namespace quasiroll
