// The allocation guard's hooks (see alloc_guard.hpp for what each build sees).
#include "hapticlab/test/alloc_guard.hpp"

#include <Eigen/Core>
#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace {
// Initial-exec TLS: reading it never calls __tls_get_addr, which could itself allocate.
__attribute__((tls_model("initial-exec"))) thread_local int t_guard_depth = 0;
__attribute__((tls_model("initial-exec"))) thread_local std::uint64_t t_allocs = 0;
inline void Count() noexcept {
  if (t_guard_depth > 0) ++t_allocs;
}

#ifdef EIGEN_RUNTIME_NO_MALLOC
bool SetEigenMallocAllowed(bool allowed) {
  const bool was = Eigen::internal::is_malloc_allowed();
  Eigen::internal::set_is_malloc_allowed(allowed);
  return was;
}
#else
bool SetEigenMallocAllowed(bool) { return true; }
#endif
}  // namespace

#if defined(HL_GUARD_MALLOC) && !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
// glibc (2.36 has no malloc hooks) supports replacing malloc by defining these functions in
// the executable; its own implementation stays reachable under the __libc_* names, and its
// internal calls (strdup, fopen, libstdc++'s operator new) reach these definitions.
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void* __libc_valloc(std::size_t);
void* __libc_pvalloc(std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) noexcept {
  Count();
  return __libc_malloc(n);
}
void* calloc(std::size_t n, std::size_t size) noexcept {
  Count();
  return __libc_calloc(n, size);
}
void* realloc(void* p, std::size_t n) noexcept {
  Count();  // realloc may move the block: an allocation either way
  return __libc_realloc(p, n);
}
void* reallocarray(void* p, std::size_t n, std::size_t size) noexcept {
  std::size_t bytes;
  if (__builtin_mul_overflow(n, size, &bytes)) {
    errno = ENOMEM;
    return nullptr;
  }
  return realloc(p, bytes);
}
void free(void* p) noexcept { __libc_free(p); }
void* memalign(std::size_t alignment, std::size_t n) noexcept {
  Count();
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(std::size_t alignment, std::size_t n) noexcept {
  Count();
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, std::size_t alignment, std::size_t n) noexcept {
  if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
  Count();
  void* p = __libc_memalign(alignment, n);
  if (!p) return ENOMEM;
  *out = p;
  return 0;
}
void* valloc(std::size_t n) noexcept {
  Count();
  return __libc_valloc(n);
}
void* pvalloc(std::size_t n) noexcept {
  Count();
  return __libc_pvalloc(n);
}
}  // extern "C"

#else
// The sanitizer runtime owns malloc: count the global operator new family instead.
void* operator new(std::size_t n) {
  Count();
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) { return operator new(n); }
void* operator new(std::size_t n, std::align_val_t a) {
  Count();
  const auto al = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(al, (n + al - 1) / al * al)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
// The nothrow forms must be replaced too, or their memory would reach our delete (free)
// from the runtime's own allocator (AddressSanitizer reports the mismatch).
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  Count();
  return std::malloc(n ? n : 1);
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept { return operator new(n, t); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  Count();
  const auto al = static_cast<std::size_t>(a);
  return std::aligned_alloc(al, (n + al - 1) / al * al);
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t& t) noexcept {
  return operator new(n, a, t);
}
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#endif

namespace hapticlab::test {

NoAllocGuard::NoAllocGuard(EigenHeap eigen)
    : start_(t_allocs), restore_eigen_(eigen == EigenHeap::kForbid) {
  if (restore_eigen_) eigen_was_allowed_ = SetEigenMallocAllowed(false);
  ++t_guard_depth;
}
NoAllocGuard::~NoAllocGuard() {
  --t_guard_depth;
  if (restore_eigen_) SetEigenMallocAllowed(eigen_was_allowed_);
}
std::uint64_t NoAllocGuard::count() const { return t_allocs - start_; }

EigenNoMalloc::EigenNoMalloc() : was_allowed_(SetEigenMallocAllowed(false)) {}
EigenNoMalloc::~EigenNoMalloc() { SetEigenMallocAllowed(was_allowed_); }

}  // namespace hapticlab::test
