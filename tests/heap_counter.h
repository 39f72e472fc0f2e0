// Counts calls to the global operator new, for tests of "no heap allocation
// after warm-up". Replaces the global operator new and delete, so include it
// in exactly one translation unit of a test binary (and build that target
// with -Wno-mismatched-new-delete: GCC cannot see that new and delete here
// pair malloc with free).
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace quasiroll::testing_util {
inline std::atomic<long long> g_heap_allocations{0};
}  // namespace quasiroll::testing_util

void* operator new(std::size_t size) {
  ++quasiroll::testing_util::g_heap_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
