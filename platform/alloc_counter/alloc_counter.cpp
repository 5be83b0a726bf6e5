// The replacement allocation functions. Built as an OBJECT library so that linking it
// always brings these definitions in (a static archive member would only be pulled in
// if something referenced it first).
#include "skyloc/platform/alloc_counter.h"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {

std::atomic<std::uint64_t> g_allocations{0};
std::atomic<std::uint64_t> g_bytes{0};

inline void Count(std::size_t bytes) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  g_bytes.fetch_add(bytes, std::memory_order_relaxed);
}

#if !defined(SKYLOC_SANITIZED)
// glibc's own entry points, which our malloc forwards to.
extern "C" void* __libc_malloc(std::size_t);
extern "C" void* __libc_calloc(std::size_t, std::size_t);
extern "C" void* __libc_realloc(void*, std::size_t);
extern "C" void __libc_free(void*);
#endif

void* CountedMalloc(std::size_t size) {
  Count(size);
#if defined(SKYLOC_SANITIZED)
  return std::malloc(size);
#else
  return __libc_malloc(size);
#endif
}

void CountedFree(void* p) {
#if defined(SKYLOC_SANITIZED)
  std::free(p);
#else
  __libc_free(p);
#endif
}

void* NewOrThrow(std::size_t size) {
  void* p = CountedMalloc(size == 0 ? 1 : size);
  if (p == nullptr)
    throw std::bad_alloc();
  return p;
}

void* AlignedNew(std::size_t size, std::align_val_t align, bool nothrow) {
  Count(size);
  void* p = nullptr;
  const std::size_t alignment = static_cast<std::size_t>(align);
  if (posix_memalign(&p, alignment < sizeof(void*) ? sizeof(void*) : alignment,
                     size == 0 ? 1 : size) != 0) {
    if (nothrow)
      return nullptr;
    throw std::bad_alloc();
  }
  return p;
}

}  // namespace

namespace skyloc {
AllocationTotals AllocationTotalsNow() {
  return {g_allocations.load(std::memory_order_relaxed), g_bytes.load(std::memory_order_relaxed)};
}
bool AllocationCounterActive() {
  return true;
}
}  // namespace skyloc

// NOLINTBEGIN: these signatures are fixed by the standard.
void* operator new(std::size_t size) {
  return NewOrThrow(size);
}
void* operator new[](std::size_t size) {
  return NewOrThrow(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return CountedMalloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return CountedMalloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t a) {
  return AlignedNew(size, a, false);
}
void* operator new[](std::size_t size, std::align_val_t a) {
  return AlignedNew(size, a, false);
}
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return AlignedNew(size, a, true);
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept {
  return AlignedNew(size, a, true);
}
void operator delete(void* p) noexcept {
  CountedFree(p);
}
void operator delete[](void* p) noexcept {
  CountedFree(p);
}
void operator delete(void* p, std::size_t) noexcept {
  CountedFree(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  CountedFree(p);
}
void operator delete(void* p, const std::nothrow_t&) noexcept {
  CountedFree(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  CountedFree(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}

#if !defined(SKYLOC_SANITIZED)
// C allocations (libraries written in C, strdup, fopen's buffer) are counted too.
// Sanitizer builds leave malloc to the sanitizer runtime, which must own it.
extern "C" {
void* malloc(std::size_t size) {
  return CountedMalloc(size);
}
void free(void* p) {
  __libc_free(p);
}
void* calloc(std::size_t n, std::size_t size) {
  Count(n * size);
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t size) {
  Count(size);
  return __libc_realloc(p, size);
}
}
#endif
// NOLINTEND
