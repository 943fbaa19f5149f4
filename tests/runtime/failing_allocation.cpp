// The runtime tests' global operator new: malloc, unless the calling thread
// asked for its next allocations to fail; every allocation is counted
// (failing_allocation.h).
#include "failing_allocation.h"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {

thread_local int g_failures_left = 0;
std::atomic<unsigned long long> g_allocations{0};

void* allocate(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (g_failures_left > 0) {
    --g_failures_left;
    throw std::bad_alloc();
  }
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}

}  // namespace

void sluice::test::fail_next_allocations(int count) { g_failures_left = count; }
unsigned long long sluice::test::allocations_so_far() { return g_allocations.load(std::memory_order_relaxed); }

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
// The nothrow forms too (std::stable_partition's buffer uses one): every
// plain operator new of the binary is ours, so every operator delete matches.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
