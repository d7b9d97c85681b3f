#include "tools/eval/AllocationCount.h"

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdlib>

#include <malloc.h>

// RHOT_COUNT_WITH_ASAN_HOOK: AddressSanitizer owns malloc (GCC says so with __SANITIZE_ADDRESS__,
// Clang with __has_feature), so its hook counts.
#if defined(__SANITIZE_ADDRESS__)
#define RHOT_COUNT_WITH_ASAN_HOOK 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define RHOT_COUNT_WITH_ASAN_HOOK 1
#endif
#endif
#ifndef RHOT_COUNT_WITH_ASAN_HOOK
#define RHOT_COUNT_WITH_ASAN_HOOK 0
#endif

namespace {

std::atomic<std::uint64_t> g_allocations{0};

void count_one() { g_allocations.fetch_add(1, std::memory_order_relaxed); }

}  // namespace

#if RHOT_COUNT_WITH_ASAN_HOOK

// The sanitizers' allocator interface (LLVM's sanitizer/allocator_interface.h, which GCC does not
// ship; both runtimes define it).
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));

namespace {

void on_malloc(const volatile void* /*block*/, std::size_t /*bytes*/) { count_one(); }
void on_free(const volatile void* /*block*/) {}

}  // namespace

namespace rhot::eval {

// The runtime installs hooks only in pairs (it refuses a null free hook, returning 0).
bool counting_heap_allocations() {
  static const bool installed = __sanitizer_install_malloc_and_free_hooks(on_malloc, on_free) != 0;
  return installed;
}

}  // namespace rhot::eval

#else

// glibc's allocator under its own names (its headers declare the C functions noexcept): a program may replace malloc, calloc, realloc and
// free and hand the blocks on (the glibc manual, "Replacing malloc"); the aligned allocations too, so that a block from any of them is
// counted once and freed by the same allocator.
extern "C" {
void* __libc_malloc(std::size_t bytes);
void* __libc_calloc(std::size_t count, std::size_t bytes);
void* __libc_realloc(void* block, std::size_t bytes);
void* __libc_memalign(std::size_t alignment, std::size_t bytes);
void __libc_free(void* block);

void* malloc(std::size_t bytes) noexcept {
  count_one();
  return __libc_malloc(bytes);
}
void* calloc(std::size_t count, std::size_t bytes) noexcept {
  count_one();
  return __libc_calloc(count, bytes);
}
void* realloc(void* block, std::size_t bytes) noexcept {
  count_one();
  return __libc_realloc(block, bytes);
}
void free(void* block) noexcept { __libc_free(block); }
void* memalign(std::size_t alignment, std::size_t bytes) noexcept {
  count_one();
  return __libc_memalign(alignment, bytes);
}
void* aligned_alloc(std::size_t alignment, std::size_t bytes) noexcept {
  count_one();
  return __libc_memalign(alignment, bytes);
}
int posix_memalign(void** block, std::size_t alignment, std::size_t bytes) noexcept {
  if (alignment == 0 || alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  count_one();
  void* p = __libc_memalign(alignment, bytes);
  if (p == nullptr && bytes != 0) return ENOMEM;
  *block = p;
  return 0;
}
}

namespace rhot::eval {

bool counting_heap_allocations() { return true; }

}  // namespace rhot::eval

#endif

namespace rhot::eval {

std::uint64_t heap_allocations() { return g_allocations.load(std::memory_order_relaxed); }

}  // namespace rhot::eval
