// Large allocations for this program only (it replaces the global operator new and delete).
// A scene of 100,000 spheres fills some 100 MB of arrays of a few megabytes each (the text,
// the objects, the hierarchy and its build arrays, the bins and buffers), each touched once,
// and memory new to the process is what a run after a pause pays for most.
// A block of 2 MB or more gets a mapping of its own, a multiple of 2 MB aligned to 2 MB, in
// 4 KB pages. It was marked MADV_HUGEPAGE (one fault per 2 MB), which paid on the virtual
// machines first measured, where a 4 KB fault cost 12 us (random-100k 0.63 -> 0.46 s). On
// the later ones a free 2 MB block is handed back to the host (virtio-balloon free page
// reporting, order 9) and a huge page faulted into it after a pause costs 2.9 ms per MB,
// against 1.0 in 4 KB pages (32 MB: 92 against 30 ms, medians of 6; right after a run 0.13
// against 0.45): without the mark, runs that follow a POV-Ray run take 0.84-0.95 times as long
// (tiny-big-150k 0.276 -> 0.231 s, random-100k 0.268 -> 0.237, shallow-60k 0.212 -> 0.200,
// kinds-mix 0.151 -> 0.142, medians of 7; docs/performance.md, thirtieth round).
// Smaller ones go to malloc, whose heap is on huge pages (below): the preparation's arrays of
// a few hundred KB cost grid-8000 and random-100k 8-15% of their runs in 4 KB faults, and in
// the heap they share huge pages instead of holding a mapping each: 8 MB less memory for
// kinds-mix (20.3 -> 12.3 MB) and grid-8000 (14.3 -> 6.3). (Leaving the heap in 4 KB pages
// too measured no better here: shallow-60k 0.205 s, cho 27 against 26 ms.) Freed, a mapping
// is kept for the next large blocks, and for blocks from 256 KB where its pages are in
// memory already (below): 4-8 MB less for shallow-60k, mirror-room-20k, lights-inside-50k
// and camera-inside-50k.
// While a scene loads, a thread faults in the heap's page after next on the idle core
// (Warming in large_pages.h; below).
#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>
#include <system_error>
#include <thread>

#include "large_pages.h"

namespace {

constexpr std::size_t kHuge = std::size_t{1} << 21;
constexpr std::size_t kMinBlock = std::size_t{1} << 21;
// Blocks from kMedium up to kMinBlock are cut from a spare when there is one (below), in
// whole kUnits; otherwise they come from malloc. A block of either kind starts its piece,
// so a block of exactly 2 MB (a hash table's slots) takes one 2 MB piece, not two.
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

// A fresh 2 MB-aligned mapping of `length` bytes (4 KB pages: see the top); 0 on failure.
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
  // Said, not left to the kernel: with transparent huge pages "always" it would use them.
  madvise(reinterpret_cast<void*>(base), length, MADV_NOHUGEPAGE);
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

// The heap's range on huge pages (set up below), and the end of the highest block operator
// new has had from it: where the heap's next pages will be needed.
std::uintptr_t heap_low = 0;
std::uintptr_t heap_high = 0;
std::atomic<std::uintptr_t> reach_end{0};

void* allocate(std::size_t size, std::size_t align) {
  if (size >= kMedium && align <= kUnit)
    if (void* p = map_large(size, size < kMinBlock)) return p;
  void* p = align <= alignof(std::max_align_t)
                ? std::malloc(size ? size : 1)
                : std::aligned_alloc(align, (size + align - 1) / align * align);
  if (!p) throw std::bad_alloc();
  // A racing thread's larger end may be lost: the warmer only falls behind for a moment.
  if (const std::uintptr_t end = reinterpret_cast<std::uintptr_t>(p) + size;
      end > reach_end.load(std::memory_order_relaxed) && end <= heap_high)
    reach_end.store(end, std::memory_order_relaxed);
  return p;
}

// The warmer keeps one huge page in memory past the one after reach_end's: that next one the
// working thread is about to fault in itself (two threads faulting one huge page both clear
// one, and one is thrown away), the one after it is cleared on the idle core meanwhile. More
// ahead only costs memory and, once the working thread stops allocating, the other threads'
// time. kinds-mix after two seconds idle: loading 15.7 -> 11.4 ms (medians of 11); whole
// runs take 0.969 times as long as without it, and 0.977 right after a POV-Ray run (paired
// medians of 15 and 21 rounds).
constexpr std::size_t kWarmGap = 2 * kHuge;
constexpr std::size_t kWarmLead = kHuge;

// The warming thread's state; made on first use and never destroyed, so that a thread still
// finishing its page when the program exits finds it there.
struct Warmer {
  std::mutex mutex;
  std::condition_variable wake;
  bool running = false;
  bool stop = false;
};
Warmer& warmer() {
  static Warmer* const w = new Warmer;
  return *w;
}

// Faults in the heap's huge pages ahead of reach_end until stopped, with MADV_POPULATE_WRITE
// (Linux 5.14): the pages a write would fault in, reading zero as untouched pages do. It
// ends at the first failure (an older kernel, no memory): the pages then fault in where
// they are used, as without it.
void warm() {
  Warmer& w = warmer();
  std::uintptr_t next = heap_low;
  std::unique_lock lock(w.mutex);
  while (!w.stop) {
    const std::uintptr_t reach = std::max(reach_end.load(std::memory_order_relaxed), heap_low);
    const std::uintptr_t page = reach & ~(kHuge - 1);
    next = std::max(next, page + kWarmGap);
    if (next < std::min(heap_high, page + kWarmGap + kWarmLead)) {
      lock.unlock();
      if (madvise(reinterpret_cast<void*>(next), kHuge, MADV_POPULATE_WRITE) != 0) {
        lock.lock();
        break;
      }
      next += kHuge;
      lock.lock();
    } else {
      w.wake.wait_for(lock, std::chrono::microseconds(500));
    }
  }
  w.running = false;
}

void release(void* p) noexcept {
  if (p && !unmap_large(p)) std::free(p);
}

// The small blocks' heap (glibc's, grown with brk) on huge pages: its first growth
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
  heap_low = from;
  heap_high = top & ~(kHuge - 1);
  // The filler: a block from `start` to `from` (glibc's chunk of a request n is n + 8
  // rounded up to 16, headers included), so the next chunk begins at `from`. Kept for the
  // program's life, in a volatile so that the compiler cannot drop it as unused.
  heap_filler = std::malloc(from - start - 8);
}
}  // namespace

namespace rayfarm::large_pages {
void start_warming() {
  if (heap_high == 0) return;  // the heap is not on huge pages
  Warmer& w = warmer();
  std::lock_guard lock(w.mutex);
  w.stop = false;
  if (w.running) return;  // stopped but still finishing its page: it carries on
  w.running = true;
  try {
    std::thread(warm).detach();
  } catch (const std::system_error&) {
    w.running = false;  // no thread to spare: the pages fault in where they are used
  }
}

void stop_warming() {
  if (heap_high == 0) return;
  Warmer& w = warmer();
  std::lock_guard lock(w.mutex);
  w.stop = true;
  w.wake.notify_one();
}

std::uintptr_t heap_reach() { return reach_end.load(std::memory_order_relaxed); }

bool warming() {
  if (heap_high == 0) return false;
  Warmer& w = warmer();
  std::lock_guard lock(w.mutex);
  return w.running;
}

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
