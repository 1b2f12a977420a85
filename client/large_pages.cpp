// Large allocations on transparent huge pages, for this program only (it replaces the global
// operator new and delete). A scene of 100,000 spheres fills some 100 MB of arrays of a few
// megabytes each (the text, the objects, the hierarchy and its build arrays, the bins and
// buffers), each touched once: in 4 KB pages that is some 25,000 page faults, which on the
// virtual machines measured cost more than parsing the file (random-100k 0.63 -> 0.46 s).
// A block of 1 MB or more gets a mapping of its own, a multiple of 2 MB aligned to 2 MB and
// marked MADV_HUGEPAGE (transparent huge pages in `madvise` mode, Debian's default), so it
// faults once per 2 MB; smaller ones go to malloc as before. From 1 MB, not 2: an 800x600
// image (1.44 MB, written once by the render and once by the PNG encoder) took 4.2 ms to
// touch in 4 KB pages there and 0.2 ms in one huge page, a tenth of the lecture scene's run.
#include <sys/mman.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

namespace {

constexpr std::size_t kHuge = std::size_t{1} << 21;
constexpr std::size_t kMinBlock = std::size_t{1} << 20;
// The block starts this far into its mapping, where the mapping's length is kept; it also
// keeps every alignment up to 64 (the hierarchy's nodes ask for 64).
constexpr std::size_t kHeader = 64;

// The live blocks, so that delete can tell them from malloc's without reading memory that
// is not its own. A pointer 64 bytes past a 2 MB boundary is looked up here; malloc's blocks
// land there once in 100,000.
std::atomic<void*> live[1024];

void* map_large(std::size_t size) {
  if (size > (std::size_t{1} << 46)) return nullptr;
  const std::size_t length = (size + kHeader + kHuge - 1) & ~(kHuge - 1);
  // Map 2 MB more than needed and cut an aligned range out of it.
  void* raw = mmap(nullptr, length + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                   -1, 0);
  if (raw == MAP_FAILED) return nullptr;
  const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(raw);
  const std::uintptr_t base = (start + kHuge - 1) & ~(kHuge - 1);
  if (base > start) munmap(raw, base - start);
  if (const std::uintptr_t end = start + length + kHuge; end > base + length)
    munmap(reinterpret_cast<void*>(base + length), end - (base + length));
  madvise(reinterpret_cast<void*>(base), length, MADV_HUGEPAGE);
  *reinterpret_cast<std::size_t*>(base) = length;
  void* p = reinterpret_cast<void*>(base + kHeader);
  for (auto& slot : live) {
    void* empty = nullptr;
    if (slot.compare_exchange_strong(empty, p, std::memory_order_acq_rel)) return p;
  }
  munmap(reinterpret_cast<void*>(base), length);  // too many at once: malloc's turn
  return nullptr;
}

bool unmap_large(void* p) {
  if ((reinterpret_cast<std::uintptr_t>(p) & (kHuge - 1)) != kHeader) return false;
  for (auto& slot : live) {
    void* mine = p;
    if (slot.load(std::memory_order_relaxed) == p &&
        slot.compare_exchange_strong(mine, nullptr, std::memory_order_acq_rel)) {
      char* base = static_cast<char*>(p) - kHeader;
      munmap(base, *reinterpret_cast<std::size_t*>(base));
      return true;
    }
  }
  return false;
}

void* allocate(std::size_t size, std::size_t align) {
  if (size >= kMinBlock && align <= kHeader)
    if (void* p = map_large(size)) return p;
  void* p = align <= alignof(std::max_align_t)
                ? std::malloc(size ? size : 1)
                : std::aligned_alloc(align, (size + align - 1) / align * align);
  if (!p) throw std::bad_alloc();
  return p;
}

void release(void* p) noexcept {
  if (p && !unmap_large(p)) std::free(p);
}

}  // namespace

void* operator new(std::size_t n) { return allocate(n, alignof(std::max_align_t)); }
void* operator new[](std::size_t n) { return allocate(n, alignof(std::max_align_t)); }
void* operator new(std::size_t n, std::align_val_t a) {
  return allocate(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a) {
  return allocate(n, static_cast<std::size_t>(a));
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  try {
    return allocate(n, alignof(std::max_align_t));
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, const std::nothrow_t& t) noexcept {
  return operator new(n, t);
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  try {
    return allocate(n, static_cast<std::size_t>(a));
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t& t) noexcept {
  return operator new(n, a, t);
}

void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
