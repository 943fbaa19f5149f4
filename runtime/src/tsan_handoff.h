// ThreadSanitizer cannot see the synchronisation inside libtbb (it is not
// instrumented), so data handed to a TBB task, or read after waiting for one,
// looks racy to it. These mark such hand-offs explicitly; they compile to
// nothing without TSan.
#pragma once

#if defined(__SANITIZE_THREAD__)
#include <sanitizer/tsan_interface.h>
#endif

namespace sluice::runtime {

// Everything written before handoff_release(p) happens before everything
// after a later handoff_acquire(p).
inline void handoff_release([[maybe_unused]] void* p) {
#if defined(__SANITIZE_THREAD__)
  __tsan_release(p);
#endif
}
inline void handoff_acquire([[maybe_unused]] void* p) {
#if defined(__SANITIZE_THREAD__)
  __tsan_acquire(p);
#endif
}

}  // namespace sluice::runtime
