#pragma once
// The process's heap allocations, counted over every thread: `rhot-eval scale` reports those its
// tracking makes per frame (docs/tracking.md "Threads": after its first frames the tracking
// allocates nothing). Every allocation is counted, whoever makes it: operator new, the standard
// containers', Eigen's and C libraries' malloc. Under AddressSanitizer its allocation hook counts
// them; otherwise this program's own malloc, calloc, realloc and aligned allocations count each
// block and hand it to the C library's allocator.

#include <cstdint>

namespace rhot::eval {

// Allocations made so far by the whole process (under AddressSanitizer, those since
// counting_heap_allocations was first called; only differences mean anything).
std::uint64_t heap_allocations();

// Starts counting (under AddressSanitizer: installs the hook; idempotent). False where this build
// cannot count (then heap_allocations stays 0).
bool counting_heap_allocations();

}  // namespace rhot::eval
