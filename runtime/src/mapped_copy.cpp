#include "mapped_copy.h"

#include <csetjmp>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <mutex>

#include "sluice/io/reader.h"

#if defined(__x86_64__) || defined(_M_X64)
#include <emmintrin.h>
#define SLUICE_STREAM_STORES 1
#endif

namespace sluice::runtime::detail {
namespace {

// The copy's landing place while one runs on this thread, else null. Set
// and cleared by its own thread only; the handler runs on the faulting
// thread (SIGBUS from a memory access is synchronous).
thread_local sigjmp_buf* t_landing = nullptr;
struct sigaction g_previous {};

void on_sigbus(int signal, siginfo_t* info, void* context) {
  if (sigjmp_buf* landing = t_landing) siglongjmp(*landing, 1);
  // Not raised by a copy: what was there before handles it.
  if (g_previous.sa_flags & SA_SIGINFO) {
    if (g_previous.sa_sigaction) g_previous.sa_sigaction(signal, info, context);
    return;
  }
  if (g_previous.sa_handler == SIG_DFL || g_previous.sa_handler == SIG_IGN) {
    // Returning re-runs the faulting access, which now meets the default
    // action (a SIGBUS from memory cannot be ignored).
    ::signal(SIGBUS, SIG_DFL);
    return;
  }
  g_previous.sa_handler(signal);
}

void install_handler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_sigaction = on_sigbus;
    action.sa_flags = SA_SIGINFO | SA_ONSTACK;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGBUS, &action, &g_previous);
  });
}

}  // namespace

void stream_copy(std::byte* dst, const std::byte* src, size_t n) noexcept {
#ifdef SLUICE_STREAM_STORES
  // Plain copy up to a 16-byte destination boundary, streaming stores for
  // the 64-byte blocks, plain copy of the tail.
  const size_t head = std::min(n, (16 - reinterpret_cast<uintptr_t>(dst) % 16) % 16);
  std::memcpy(dst, src, head);
  size_t at = head;
  for (; at + 64 <= n; at += 64) {
    const auto* s = reinterpret_cast<const __m128i*>(src + at);
    auto* d = reinterpret_cast<__m128i*>(dst + at);
    const __m128i a = _mm_loadu_si128(s), b = _mm_loadu_si128(s + 1), c = _mm_loadu_si128(s + 2), e = _mm_loadu_si128(s + 3);
    _mm_stream_si128(d, a);
    _mm_stream_si128(d + 1, b);
    _mm_stream_si128(d + 2, c);
    _mm_stream_si128(d + 3, e);
  }
  std::memcpy(dst + at, src + at, n - at);
  _mm_sfence();  // streaming stores are weakly ordered: visible before whoever is told the copy is done reads them
#else
  std::memcpy(dst, src, n);
#endif
}

namespace {

// Runs `touch` (which reads the mapping) with this thread's landing set:
// false if a SIGBUS jumped out of it. `touch` holds nothing that needs
// unwinding.
template <class Touch>
bool with_landing(Touch touch) noexcept {
  install_handler();
  sigjmp_buf landing;
  // savemask: the handler runs with SIGBUS blocked; the jump back restores
  // the mask, so the next copy can catch one again.
  if (sigsetjmp(landing, 1) != 0) {
    t_landing = nullptr;
    return false;
  }
  t_landing = &landing;
  touch();
  t_landing = nullptr;
  return true;
}

}  // namespace

bool copy_from_mapping(std::byte* dst, const std::byte* src, size_t n) noexcept {
  return with_landing([&] { stream_copy(dst, src, n); });
}

bool copy_from_mapping_checked(std::byte* dst, const std::byte* src, size_t n, uint64_t& checksum, bool streaming) noexcept {
  return with_landing([&] {  // the hash reads the mapping too
    const auto stream = [](std::byte* d, const std::byte* s, size_t k, void*) { stream_copy(d, s, k); };
    const auto plain = [](std::byte* d, const std::byte* s, size_t k, void*) { std::memcpy(d, s, k); };
    checksum = io::copy_and_checksum(dst, src, n, streaming ? io::BlockCopy(stream) : io::BlockCopy(plain), nullptr);
  });
}

}  // namespace sluice::runtime::detail
