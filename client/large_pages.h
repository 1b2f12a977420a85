// The client's allocator (large_pages.cpp): huge pages for the heap and for large blocks, and
// a thread that faults the heap's next pages in while the program works on one thread.
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
// blocks operator new has taken from it, for a stretch of work that one thread does alone
// (loading a scene). On the virtual machines measured, memory new to the
// process costs 1.7-2 ms per MB to fault in once the machine has been idle a few seconds;
// on the idle core that cost leaves the working thread's path.
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
