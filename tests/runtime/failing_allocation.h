// Allocation failures on purpose: the runtime tests' operator new fails the
// next `count` allocations of the calling thread with std::bad_alloc.
#pragma once

namespace sluice::test {

void fail_next_allocations(int count);
// Allocations (operator new) made so far by every thread.
unsigned long long allocations_so_far();

}  // namespace sluice::test
