// Counts heap allocations in this thread, whichever way they are made: the global operator new and
// the C allocation functions (Eigen's dynamic matrices call std::malloc directly, not operator new).
//
//   Normal builds:   malloc/calloc/realloc/aligned_alloc/posix_memalign/memalign are replaced in the
//                    executable (the interposition glibc documents under "Replacing malloc") and
//                    forward to glibc's __libc_* functions after counting.
//   ASan builds:     the sanitizer owns malloc; a sanitizer malloc hook counts instead.
// The global operator new/delete forward to malloc/free, so each allocation is counted exactly once.
#include "tests/support/alloc_counter.h"
#include "tests/support/sanitizer.h"  // IDENT_TESTS_UNDER_ASAN

#include <cstddef>
#include <cstdlib>
#include <new>

namespace {
thread_local std::int64_t g_allocations = 0;
thread_local std::int64_t g_large_allocations = 0;  // of at least kLargeAllocationBytes
void Count(std::size_t size) {
  ++g_allocations;
  if (size >= ident::testing::kLargeAllocationBytes) ++g_large_allocations;
}
}  // namespace

namespace ident::testing {
std::int64_t AllocationsSoFar() { return g_allocations; }
std::int64_t LargeAllocationsSoFar() { return g_large_allocations; }
}  // namespace ident::testing

#if defined(IDENT_TESTS_UNDER_ASAN)

extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));
namespace {
void CountMalloc(const volatile void*, std::size_t size) { Count(size); }
void IgnoreFree(const volatile void*) {}
[[maybe_unused]] const int g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(CountMalloc, IgnoreFree);
}  // namespace

#else

extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void* __libc_memalign(std::size_t alignment, std::size_t size);
void __libc_free(void* p);

void* malloc(std::size_t size) {
  Count(size);
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  Count(count * size);
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) {
  Count(size);
  return __libc_realloc(p, size);
}
void* aligned_alloc(std::size_t alignment, std::size_t size) {
  Count(size);
  return __libc_memalign(alignment, size);
}
void* memalign(std::size_t alignment, std::size_t size) {
  Count(size);
  return __libc_memalign(alignment, size);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  if (alignment < sizeof(void*) || (alignment & (alignment - 1)) != 0) return 22;  // EINVAL
  Count(size);
  void* p = __libc_memalign(alignment, size);
  if (p == nullptr && size != 0) return 12;  // ENOMEM
  *out = p;
  return 0;
}
void free(void* p) { __libc_free(p); }
}  // extern "C"

#endif

namespace {
void* Allocate(std::size_t size) {
  if (size == 0) size = 1;
  if (void* p = std::malloc(size)) return p;
  throw std::bad_alloc();
}
void* AllocateAligned(std::size_t size, std::align_val_t align) {
  const std::size_t a = static_cast<std::size_t>(align);
  if (size == 0) size = a;
  size = (size + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, size)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return Allocate(size); }
void* operator new[](std::size_t size) { return Allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return AllocateAligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return AllocateAligned(size, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
