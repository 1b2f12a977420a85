// Large allocations on transparent huge pages, for this program only (it replaces the global
// operator new and delete). A scene of 100,000 spheres fills some 100 MB of arrays of a few
// megabytes each (the text, the objects, the hierarchy and its build arrays, the bins and
// buffers), each touched once: in 4 KB pages that is some 25,000 page faults, which on the
// virtual machines measured cost more than parsing the file (random-100k 0.63 -> 0.46 s).
// A block of 2 MB or more gets a mapping of its own, a multiple of 2 MB aligned to 2 MB and
// marked MADV_HUGEPAGE (transparent huge pages in `madvise` mode, Debian's default), so it
// faults once per 2 MB. Smaller ones go to malloc, whose heap is on huge pages too (below):
// the preparation's arrays of a few hundred KB cost grid-8000 and random-100k 8-15% of
// their runs in 4 KB faults, and in the heap they share huge pages instead of holding a
// 2 MB mapping each (as from 256 KB before): 8 MB less memory for kinds-mix (20.3 -> 12.3
// MB) and grid-8000 (14.3 -> 6.3). That is what counts once the machine has been idle a few
// seconds, when memory new to the process costs 0.9-1.7 ms per MB (0.07 when it was freed
// just before). Freed, a mapping is kept for the next large blocks, and for blocks from
// 256 KB where its pages are in memory already (below): 4-8 MB less for shallow-60k,
// mirror-room-20k, lights-inside-50k and camera-inside-50k.
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>

namespace {

constexpr std::size_t kHuge = std::size_t{1} << 21;
constexpr std::size_t kMinBlock = std::size_t{1} << 21;
// Blocks from kMedium up to kMinBlock are cut from a spare when there is one (below), in
// whole kUnits; otherwise they come from malloc. A block of either kind starts its piece,
// so a block of exactly 2 MB (a hash table's slots) holds one huge page, not two.
constexpr std::size_t kMedium = std::size_t{1} << 18;
constexpr std::size_t kUnit = std::size_t{1} << 16;

// The live blocks and their pieces' lengths, so that delete can tell them from malloc's
// without reading memory that is not its own. A pointer on a 64 KB boundary is looked up
// here; malloc's blocks land there once in 4,096.
struct Live {
  std::atomic<void*> block{nullptr};
  std::atomic<std::size_t> length{0};
};
Live live[1024];

// Freed mappings kept for the next large and medium blocks. Their pages are faulted in
// already: on the virtual machines measured, a fresh page costs about 1 ms per MB to fault in
// and clear, more than building the hierarchy over what it holds. Loading a large scene frees
// arrays (the text, the two halves of the file's objects and their name tables) that the
// next steps can fill instead: the hierarchy's arrays, and the bins' and light buffers'
// arrays of a few hundred KB, which from malloc would grow its heap by fresh pages while
// these lie unused (shallow-60k: 9 MB more). A spare larger than asked for is cut and the
// rest kept; a freed piece joins the spares beside it. Kept while the program runs: a
// command's whole life.
struct Spare {
  std::uintptr_t base;
  std::size_t length;
};
constexpr int kMaxSpares = 64;
constexpr std::size_t kMaxSpareBytes = std::size_t{1} << 30;
std::mutex spare_mutex;
Spare spares[kMaxSpares];
int spare_count = 0;
std::size_t spare_bytes = 0;

// Whether every page of [base, base + length) has been touched (and is still there).
bool resident(std::uintptr_t base, std::size_t length) {
  constexpr std::size_t kPage = 4096;
  unsigned char pages[kMinBlock / kPage];
  for (std::size_t done = 0; done < length; done += kMinBlock) {
    const std::size_t n = std::min(kMinBlock, length - done);
    if (mincore(reinterpret_cast<void*>(base + done), n, pages) != 0) return false;
    for (std::size_t i = 0; i < (n + kPage - 1) / kPage; ++i)
      if (!(pages[i] & 1)) return false;
  }
  return true;
}

// The start of `length` bytes cut from the smallest spare that holds them (`warm`: whose
// first `length` bytes are in memory already); 0 if none does.
std::uintptr_t take_spare(std::size_t length, bool warm = false) {
  std::lock_guard lock(spare_mutex);
  int best = -1;
  for (int i = 0; i < spare_count; ++i)
    if (spares[i].length >= length && (best < 0 || spares[i].length < spares[best].length) &&
        (!warm || resident(spares[i].base, length)))
      best = i;
  if (best < 0) return 0;
  const std::uintptr_t base = spares[best].base;
  spare_bytes -= length;
  if (spares[best].length > length) {
    spares[best].base += length;
    spares[best].length -= length;
  } else {
    spares[best] = spares[--spare_count];
  }
  return base;
}

// Keeps a freed piece for reuse, joined to the spares it touches; false when there is no
// room (the caller unmaps it).
bool keep_spare(std::uintptr_t base, std::size_t length) {
  std::lock_guard lock(spare_mutex);
  if (spare_bytes + length > kMaxSpareBytes) return false;
  std::uintptr_t end = base + length;
  for (int i = 0; i < spare_count;) {
    if (spares[i].base + spares[i].length == base || spares[i].base == end) {
      base = std::min(base, spares[i].base);
      end = std::max(end, spares[i].base + spares[i].length);
      spare_bytes -= spares[i].length;
      spares[i] = spares[--spare_count];
    } else {
      ++i;
    }
  }
  if (spare_count == kMaxSpares) return false;
  spares[spare_count++] = {base, end - base};
  spare_bytes += end - base;
  return true;
}

// A fresh 2 MB-aligned mapping of `length` bytes marked for huge pages; 0 on failure.
std::uintptr_t map_fresh(std::size_t length) {
  // Map 2 MB more than needed and cut an aligned range out of it.
  void* raw = mmap(nullptr, length + kHuge, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                   -1, 0);
  if (raw == MAP_FAILED) return 0;
  const std::uintptr_t start = reinterpret_cast<std::uintptr_t>(raw);
  const std::uintptr_t base = (start + kHuge - 1) & ~(kHuge - 1);
  if (base > start) munmap(raw, base - start);
  if (const std::uintptr_t end = start + length + kHuge; end > base + length)
    munmap(reinterpret_cast<void*>(base + length), end - (base + length));
  madvise(reinterpret_cast<void*>(base), length, MADV_HUGEPAGE);
  return base;
}

void release_mapping(std::uintptr_t base, std::size_t length) {
  if (!keep_spare(base, length)) munmap(reinterpret_cast<void*>(base), length);
}

// A block of `size` bytes in a piece of its own: cut from a spare, or for a large block (not
// `medium`) from a fresh mapping when none holds it. Null when neither can be had.
void* map_large(std::size_t size, bool medium) {
  if (size > (std::size_t{1} << 46)) return nullptr;
  const std::size_t grain = medium ? kUnit : kHuge;
  const std::size_t length = (size + grain - 1) & ~(grain - 1);
  // Pages in memory first, whatever the block: a large one cut from the untouched part of a
  // spare faults as a fresh mapping does.
  std::uintptr_t base = take_spare(length, true);
  if (!base && !medium) base = take_spare(length);
  if (!base && !medium) base = map_fresh(length);
  if (!base) return nullptr;
  void* p = reinterpret_cast<void*>(base);
  for (auto& slot : live) {
    void* empty = nullptr;
    if (slot.block.compare_exchange_strong(empty, p, std::memory_order_acq_rel)) {
      slot.length.store(length, std::memory_order_relaxed);  // read only by p's delete
      return p;
    }
  }
  release_mapping(base, length);  // too many at once: malloc's turn
  return nullptr;
}

bool unmap_large(void* p) {
  if ((reinterpret_cast<std::uintptr_t>(p) & (kUnit - 1)) != 0) return false;
  for (auto& slot : live) {
    void* mine = p;
    if (slot.block.load(std::memory_order_relaxed) != p) continue;
    // The length first: once the slot is free, another block may take it.
    const std::size_t length = slot.length.load(std::memory_order_relaxed);
    if (slot.block.compare_exchange_strong(mine, nullptr, std::memory_order_acq_rel)) {
      release_mapping(reinterpret_cast<std::uintptr_t>(p), length);
      return true;
    }
  }
  return false;
}

void* allocate(std::size_t size, std::size_t align) {
  if (size >= kMedium && align <= kUnit)
    if (void* p = map_large(size, size < kMinBlock)) return p;
  void* p = align <= alignof(std::max_align_t)
                ? std::malloc(size ? size : 1)
                : std::aligned_alloc(align, (size + align - 1) / align * align);
  if (!p) throw std::bad_alloc();
  return p;
}

void release(void* p) noexcept {
  if (p && !unmap_large(p)) std::free(p);
}

// The small blocks' heap (glibc's, grown with brk) on huge pages too: its first growth
// reserves 128 MB (address space; pages are touched as used), that range is marked
// MADV_HUGEPAGE and never trimmed, and one arena serves every thread (the others' arenas
// would be 4 KB pages again). A scene that the general parser reads (any kind beyond
// spheres and planes) makes thousands of small blocks, and the preparation blocks of up to
// 2 MB. Past 128 MB the heap grows 64 MB at a time, unmarked.
//
// A 4 KB page costs a fault of its own (12 us each on the virtual machines measured, some
// 3 ms per MB, against 0.07 ms per MB in recycled huge pages), and a 2 MB range with one 4 KB
// page in it stays in 4 KB pages. So no page at or past the first 2 MB boundary above the
// heap's top is touched before it is marked, and the heap below that boundary, up to 2 MB,
// is one block that is never used (its pages never touched): small blocks start at it.
void* volatile heap_filler = nullptr;

[[gnu::constructor]] void heap_on_huge_pages() {
  mallopt(M_TOP_PAD, 128 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_ARENA_MAX, 1);
  // Blocks up to 4 MB from the heap, not mmap: the filler below, and C libraries' buffers
  // (the operator new above maps its own from 2 MB).
  mallopt(M_MMAP_THRESHOLD, 4 << 20);
  // The top chunk (where new blocks are cut) runs from `start` to the break; pages below
  // the break may have been touched, none above.
  const std::uintptr_t brk = reinterpret_cast<std::uintptr_t>(sbrk(0));
  const std::uintptr_t start = brk - mallinfo2().keepcost;
  std::uintptr_t from = (brk + kHuge - 1) & ~(kHuge - 1);
  if (from - brk < 2 * 4096) from += kHuge;  // room for the growth's header below it
  // Grow the heap by the reserve: one block just larger than the top chunk, whose end (where
  // malloc writes the next chunk's header) stays below `from`.
  void* grow = std::malloc(brk - start + 64);
  const std::uintptr_t top = reinterpret_cast<std::uintptr_t>(sbrk(0));
  std::free(grow);
  mallopt(M_TOP_PAD, 64 << 20);
  if (!grow || top < from + kHuge) return;
  madvise(reinterpret_cast<void*>(from), (top & ~(kHuge - 1)) - from, MADV_HUGEPAGE);
  // The filler: a block from `start` to `from` (glibc's chunk of a request n is n + 8
  // rounded up to 16, headers included), so the next chunk begins at `from`. Kept for the
  // program's life, in a volatile so that the compiler cannot drop it as unused.
  heap_filler = std::malloc(from - start - 8);
}
}  // namespace

namespace rayfarm::large_pages {
// For tests: unmaps every spare, so that what follows sees only its own.
void drop_spares() {
  std::lock_guard lock(spare_mutex);
  for (int i = 0; i < spare_count; ++i)
    munmap(reinterpret_cast<void*>(spares[i].base), spares[i].length);
  spare_count = 0;
  spare_bytes = 0;
}
}  // namespace rayfarm::large_pages

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
