// The client's allocator (large_pages.cpp): huge pages for the small blocks' heap, large blocks
// in mappings of their own (4 KB pages) kept for reuse, and a thread that faults in the heap's
// page after next while the program loads a scene.
#pragma once

#include <cstdint>

namespace rayfarm::large_pages {

// Defined in large_pages.cpp, which sanitizer builds leave out (they bring their own
// operator new): weak, so that there they are null and Warming does nothing.
[[gnu::weak]] void start_warming();
[[gnu::weak]] void stop_warming();
// For tests: whether the warming thread is running, and the end of the highest block
// operator new has had from the heap.
[[gnu::weak]] bool warming();
[[gnu::weak]] std::uintptr_t heap_reach();

// From construction to stop(), a thread faults in the small blocks' heap just ahead of the
// blocks operator new has taken from it, for a stretch of work mostly on one thread (loading
// a scene). On the virtual machines measured, a huge page (2 MB) new to the process took
// 3.5-4 ms to fault in after a pause of a few seconds (docs/performance.md, eighteenth
// round); on the idle core that cost leaves the working thread's path.
class Warming {
 public:
  Warming() {
    if (start_warming) start_warming();
  }
  ~Warming() { stop(); }
  Warming(const Warming&) = delete;
  Warming& operator=(const Warming&) = delete;
  // The thread finishes the page it is on (a few ms at most) and ends; not waited for.
  void stop() {
    if (stop_warming) stop_warming();
  }
};

}  // namespace rayfarm::large_pages
