// The client's operator new (client/large_pages.cpp), linked into this test alone: blocks of
// 2 MB and more come from 2 MB-aligned mappings, those from 256 KB from freed ones whose
// pages are in memory, every size and alignment is usable and freed, from several threads at
// once, and the containers the renderer uses work on it.
#include <gtest/gtest.h>
#include <sys/mman.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <string>
#include <thread>
#include <vector>

namespace rayfarm::large_pages {
void drop_spares();
void start_warming();
void stop_warming();
bool warming();
std::uintptr_t heap_reach();
}  // namespace rayfarm::large_pages

namespace {

constexpr std::size_t kMiB = std::size_t{1} << 20;

std::uintptr_t address(const void* p) { return reinterpret_cast<std::uintptr_t>(p); }

// How many of three blocks of `size` bytes, allocated together, start on a 64 KB boundary
// (as every block cut from a spare does; a malloc block now and then).
int cut_of_three(std::size_t size) {
  void* blocks[3];
  int cut = 0;
  for (void*& b : blocks) {
    b = ::operator new(size);
    static_cast<char*>(b)[size - 1] = 1;
    cut += address(b) % (64 * 1024) == 0;
  }
  for (void* b : blocks) ::operator delete(b);
  return cut;
}

TEST(LargePages, LargeBlocksStartA2MiBAlignedMapping) {
  rayfarm::large_pages::drop_spares();  // with no spare to cut them from
  for (std::size_t size : {2 * kMiB, 2 * kMiB + 1, 7 * kMiB + 3, 64 * kMiB}) {
    char* p = static_cast<char*>(::operator new(size));
    EXPECT_EQ(address(p) % (2 * kMiB), 0u) << size;
    std::memset(p, 0x5a, size);  // every byte is writable
    EXPECT_EQ(p[size - 1], 0x5a);
    ::operator delete(p);
  }
}

// A freed large block's mapping is kept, its pages faulted in already, and the next large
// blocks are cut from it at 2 MB boundaries: from the smallest spare whose pages they would
// take are all in memory, else from the smallest that holds them. Freed pieces join the
// spares beside them.
TEST(LargePages, FreedMappingsAreCutForTheNextLargeBlocks) {
  rayfarm::large_pages::drop_spares();  // other tests' blocks
  char* big = static_cast<char*>(::operator new(101 * kMiB));  // a 102 MB mapping
  big[0] = big[101 * kMiB - 1] = 1;
  const std::uintptr_t base = address(big);
  ::operator delete(big);
  char* a = static_cast<char*>(::operator new(70 * kMiB - 1));  // its first 70 MB
  char* b = static_cast<char*>(::operator new(21 * kMiB));      // 22 of the 32 MB left
  EXPECT_EQ(address(a), base);
  EXPECT_EQ(address(b), base + 70 * kMiB);
  std::memset(a, 2, 70 * kMiB - 1);
  std::memset(b, 3, 21 * kMiB);
  EXPECT_EQ(a[70 * kMiB - 2], 2);
  EXPECT_EQ(b[0], 3);
  ::operator delete(a);
  // Spares of 70 MB, touched, and 10 MB of which only the last 2 MB were (b between them):
  // 8 MB comes from the larger, whose pages cost no faults.
  char* d = static_cast<char*>(::operator new(8 * kMiB));
  EXPECT_EQ(address(d), base);
  // b freed joins both: one spare from 8 to 102 MB, 92 to 100 untouched. No spare holds
  // 90 MB of touched pages, so the one that holds 90 MB at all.
  ::operator delete(b);
  char* e = static_cast<char*>(::operator new(90 * kMiB));
  EXPECT_EQ(address(e), base + 8 * kMiB);
  ::operator delete(e);
  ::operator delete(d);
  // Freed, the pieces join again: 100 MB fits at the start.
  char* c = static_cast<char*>(::operator new(100 * kMiB));
  EXPECT_EQ(address(c), base);
  ::operator delete(c);
  rayfarm::large_pages::drop_spares();
}

TEST(LargePages, BlocksBelow256KiBComeFromMalloc) {
  // A malloc block may land on a 64 KB boundary now and then, never three in a row; every
  // block here would, from a spare, and there is one to take.
  rayfarm::large_pages::drop_spares();
  char* spare = static_cast<char*>(::operator new(8 * kMiB));
  std::memset(spare, 1, 8 * kMiB);
  ::operator delete(spare);
  for (std::size_t size : {std::size_t{64}, std::size_t{12288}, kMiB / 4 - 1})
    EXPECT_LT(cut_of_three(size), 3) << size;
  rayfarm::large_pages::drop_spares();
}

// Blocks from 256 KB to 2 MB are cut from a spare whose pages are in memory: one that a
// freed block touched. With none, they come from malloc, never from a mapping of their own.
TEST(LargePages, MediumBlocksAreCutFromTouchedSparesElseFromMalloc) {
  rayfarm::large_pages::drop_spares();
  for (std::size_t size : {kMiB / 4, kMiB, 2 * kMiB - 1})
    EXPECT_LT(cut_of_three(size), 3) << size << ": no spare, so malloc's";
  // A spare of 8 MB whose first 2 MB were touched (a huge page, or 4 KB pages all touched).
  char* big = static_cast<char*>(::operator new(8 * kMiB));
  std::memset(big, 1, 2 * kMiB);
  const std::uintptr_t base = address(big);
  ::operator delete(big);
  // 1.5 MB fits in the touched part: cut there, in whole 64 KB units.
  char* a = static_cast<char*>(::operator new(3 * kMiB / 2));
  EXPECT_EQ(address(a), base);
  std::memset(a, 2, 3 * kMiB / 2);
  // The next 1 MB would reach past it (from 1.5 MB): malloc's.
  char* b = static_cast<char*>(::operator new(kMiB));
  EXPECT_FALSE(address(b) >= base && address(b) < base + 8 * kMiB);
  std::memset(b, 3, kMiB);
  // 256 KB still fits in the touched part, after a's piece.
  char* c = static_cast<char*>(::operator new(kMiB / 4));
  EXPECT_EQ(address(c), base + 3 * kMiB / 2);
  std::memset(c, 4, kMiB / 4);
  EXPECT_EQ(a[3 * kMiB / 2 - 1], 2);
  ::operator delete(a);
  ::operator delete(b);
  ::operator delete(c);
  // Freed, the pieces join the rest again: the whole 8 MB can be had in one block.
  char* whole = static_cast<char*>(::operator new(8 * kMiB));
  EXPECT_EQ(address(whole), base);
  ::operator delete(whole);
  rayfarm::large_pages::drop_spares();
}

// The VmFlags line of the mapping that holds `at` (smaps), "" when none does.
std::string vm_flags(std::uintptr_t at) {
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx ", &lo, &hi) == 2) {  // a mapping's first line
      inside = lo <= at && at < hi;
      continue;
    }
    if (inside && line.rfind("VmFlags:", 0) == 0) return line;
  }
  return "";
}

// The small blocks' heap is marked for huge pages from the start (VmFlags "hg" in smaps); a
// large block's own mapping is marked for none ("nh": a fresh huge page is the host's coldest
// memory on the virtual machines measured, large_pages.cpp).
TEST(LargePages, SmallBlocksComeFromAHeapMarkedForHugePagesAndLargeOnesDoNot) {
  if (!std::ifstream("/sys/kernel/mm/transparent_hugepage/enabled"))
    GTEST_SKIP() << "this kernel has no transparent huge pages";
  // 8 MB of them: past the heap's first 2 MB boundary, where the marked range starts.
  std::vector<std::unique_ptr<char[]>> blocks;
  for (int i = 0; i < 40000; ++i) blocks.push_back(std::make_unique<char[]>(200));
  const std::string small = vm_flags(address(blocks.back().get()));
  ASSERT_FALSE(small.empty()) << "the block's mapping is not in smaps";
  EXPECT_NE(small.find(" hg"), std::string::npos) << small;

  rayfarm::large_pages::drop_spares();
  auto large = std::make_unique<char[]>(8 * kMiB);
  const std::string flags = vm_flags(address(large.get()));
  ASSERT_FALSE(flags.empty()) << "the large block's mapping is not in smaps";
  EXPECT_EQ(flags.find(" hg"), std::string::npos) << flags;
  EXPECT_NE(flags.find(" nh"), std::string::npos) << flags;  // nor left to the kernel's mode
}

// Nor do small blocks fill 4 KB pages first (a fault each, some 12 us on the virtual machines
// measured): below the first marked 2 MB boundary the heap is one block that is never
// touched, and nothing touched the marked range before it was marked. 8 MB of small blocks
// leave under 256 KB of the heap in 4 KB pages (what was touched before the program
// started; 20 KB here), where filling the heap up to its first 2 MB boundary in 4 KB pages
// would leave as much as lies below it (0 to 2 MB, with the heap's random start), and 2 MB
// more if the marked range's first 2 MB had a 4 KB page before it was marked.
TEST(LargePages, SmallBlocksDoNotFill4KiBPagesFirst) {
  std::ifstream thp("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string mode;
  if (!std::getline(thp, mode) || mode.find("[never]") != std::string::npos)
    GTEST_SKIP() << "no transparent huge pages here";
  std::vector<std::unique_ptr<char[]>> blocks;
  for (int i = 0; i < 40000; ++i) {
    blocks.push_back(std::make_unique<char[]>(200));
    std::memset(blocks.back().get(), 1, 200);
  }
  std::ifstream smaps("/proc/self/smaps");
  ASSERT_TRUE(smaps) << "no /proc/self/smaps";
  std::string line;
  bool heap = false;
  long rss_kb = 0, huge_kb = 0;
  while (std::getline(smaps, line)) {
    std::uintptr_t lo = 0, hi = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx ", &lo, &hi) == 2) {
      heap = line.find("[heap]") != std::string::npos;
      continue;
    }
    long kb = 0;
    if (heap && std::sscanf(line.c_str(), "Rss: %ld kB", &kb) == 1) rss_kb += kb;
    if (heap && std::sscanf(line.c_str(), "AnonHugePages: %ld kB", &kb) == 1) huge_kb += kb;
  }
  EXPECT_GE(huge_kb, 6 * 1024) << "the blocks are in huge pages";
  EXPECT_LT(rss_kb - huge_kb, 256) << "kB of " << rss_kb << " kB of heap in 4 KB pages";
}

TEST(LargePages, EverySizeAndAlignmentIsUsable) {
  for (std::size_t size : {std::size_t{0}, std::size_t{1}, std::size_t{100}, kMiB, 3 * kMiB}) {
    for (std::size_t align : {std::size_t{8}, std::size_t{16}, std::size_t{64}, std::size_t{4096}}) {
      void* p = ::operator new(size, std::align_val_t{align});
      EXPECT_EQ(address(p) % align, 0u) << size << " " << align;
      if (size) std::memset(p, 1, size);
      ::operator delete(p, std::align_val_t{align});
    }
  }
  void* q = ::operator new(5 * kMiB, std::nothrow);
  ASSERT_NE(q, nullptr);
  ::operator delete(q, std::nothrow);
}

TEST(LargePages, ThreadsAllocateAndFreeLargeAndSmallBlocksTogether) {
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([t] {
      for (int i = 0; i < 50; ++i) {
        std::vector<std::uint64_t> big((i % 5 + 1) * kMiB / 2, static_cast<std::uint64_t>(t));
        auto small = std::make_unique<int[]>(static_cast<std::size_t>(i) + 1);
        small[0] = i;
        EXPECT_EQ(big.back(), static_cast<std::uint64_t>(t));
        EXPECT_EQ(small[0], i);
      }
    });
  for (auto& th : threads) th.join();
}

TEST(LargePages, VectorsGrowAcrossTheThreshold) {
  std::vector<double> v;
  for (int i = 0; i < 3'000'000; ++i) v.push_back(i);  // 24 MB, through 2, 4, 8 and 16 MB
  double sum = 0;
  for (double x : v) sum += x;
  EXPECT_EQ(sum, 3'000'000.0 * 2'999'999 / 2);
}

// Whether the 4 KB page holding `at` is in memory.
bool in_memory(std::uintptr_t at) {
  unsigned char v = 0;
  return mincore(reinterpret_cast<void*>(at & ~std::uintptr_t{4095}), 4096, &v) == 0 && (v & 1);
}

// Waits up to 20 s for `done`.
template <class F>
bool within_seconds(F done) {
  for (int i = 0; i < 20000 && !done(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return done();
}

// Whether this kernel has MADV_POPULATE_WRITE (Linux 5.14), which the warmer uses.
bool kernel_populates() {
  void* p = mmap(nullptr, 4096, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) return false;
  const bool ok = madvise(p, 4096, MADV_POPULATE_WRITE) == 0;
  munmap(p, 4096);
  return ok;
}

// Warming faults in the heap's huge page after the next one past the blocks operator new has
// taken (the next is the allocating thread's own), not beyond, and stops when told; started
// again, it follows the blocks taken since. Once per process: the pages it warmed stay.
TEST(LargePages, WarmingFaultsInTheHeapJustAheadOfItsBlocks) {
  namespace lp = rayfarm::large_pages;
  if (!kernel_populates()) GTEST_SKIP() << "this kernel has no MADV_POPULATE_WRITE";
  constexpr std::uintptr_t kHuge = 2 * kMiB;
  ASSERT_FALSE(lp::warming());
  std::vector<std::unique_ptr<char[]>> blocks;
  blocks.emplace_back(new char[100 * 1024]);  // from malloc's heap: under 256 KB
  std::uintptr_t page = lp::heap_reach() & ~(kHuge - 1);
  ASSERT_NE(page, 0u) << "the heap is not on huge pages";
  ASSERT_FALSE(in_memory(page + 2 * kHuge)) << "touched before any warming";
  ASSERT_FALSE(in_memory(page + 3 * kHuge));
  // Untouched unless the last block ends within a few bytes of its page's end (malloc writes
  // the next chunk's header there).
  const bool next_untouched = !in_memory(page + kHuge);

  lp::start_warming();
  // Its first and last 4 KB: where no huge page can be had, they come one by one.
  EXPECT_TRUE(within_seconds([&] {
    return in_memory(page + 2 * kHuge) && in_memory(page + 3 * kHuge - 4096);
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(in_memory(page + 3 * kHuge)) << "warmed further ahead than one page";
  if (next_untouched) {
    EXPECT_FALSE(in_memory(page + kHuge)) << "warmed the next page, the allocating thread's own";
  }
  lp::stop_warming();
  EXPECT_TRUE(within_seconds([&] { return !lp::warming(); }));

  // Blocks taken past the warmed page, with no thread warming: nothing ahead of them moves.
  while ((lp::heap_reach() & ~(kHuge - 1)) < page + 3 * kHuge)
    blocks.emplace_back(new char[200 * 1024]);
  page = lp::heap_reach() & ~(kHuge - 1);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(in_memory(page + 2 * kHuge)) << "warmed while stopped";

  lp::start_warming();
  EXPECT_TRUE(within_seconds([&] {
    return in_memory(page + 2 * kHuge) && in_memory(page + 3 * kHuge - 4096);
  }));
  lp::stop_warming();
  EXPECT_TRUE(within_seconds([&] { return !lp::warming(); }));
}

}  // namespace
