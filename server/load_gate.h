// How many large scenes the server reads at once. Reading takes many times the text's size
// (a 15 MB JSON scene some 300 MB while it is read and described), and every HTTP thread
// can be reading one: 64 requests at once would exhaust the machine. A large text waits
// for one of a few passes (the parse is CPU-bound, so more at once would not finish sooner);
// small texts, the lab's scenes, never wait.
#pragma once

#include <malloc.h>

#include <condition_variable>
#include <cstddef>
#include <mutex>

namespace rayfarm::server {

class LoadGate {
 public:
  // Texts up to this size pass without a pass: a lab scene is a few KB.
  static constexpr std::size_t kSmall = 1 << 20;

  explicit LoadGate(int passes) : free_(passes > 0 ? passes : 1) {}

  // Held while a scene is read and its description is alive.
  class Pass {
   public:
    Pass() = default;
    Pass(Pass&& o) noexcept : gate_(o.gate_) { o.gate_ = nullptr; }
    Pass& operator=(Pass&& o) noexcept {  // gives back the pass held, takes o's
      if (this != &o) {
        if (gate_) gate_->leave();
        gate_ = o.gate_;
        o.gate_ = nullptr;
      }
      return *this;
    }
    Pass(const Pass&) = delete;
    ~Pass() {
      if (gate_) gate_->leave();
    }
    bool held() const { return gate_ != nullptr; }

   private:
    friend class LoadGate;
    explicit Pass(LoadGate* gate) : gate_(gate) {}
    LoadGate* gate_ = nullptr;
  };

  // Waits for a pass when `bytes` is over kSmall; an empty pass otherwise.
  Pass enter(std::size_t bytes) {
    if (bytes <= kSmall) return Pass();
    std::unique_lock lock(mu_);
    ++waiting_;
    cv_.wait(lock, [&] { return free_ > 0; });
    --waiting_;
    --free_;
    return Pass(this);
  }

  // Large texts waiting for a pass now (for /metrics and the tests).
  int waiting() const {
    std::lock_guard lock(mu_);
    return waiting_;
  }

 private:
  void leave() {
    {
      std::lock_guard lock(mu_);
      ++free_;
    }
    cv_.notify_one();
    // The read's blocks are freed by now (a pass outlives the scene it was taken for), but
    // glibc keeps them in this thread's arena: the next large text, read on another thread,
    // would then take as much again from the system.
    malloc_trim(0);
  }

  mutable std::mutex mu_;
  std::condition_variable cv_;
  int free_;
  int waiting_ = 0;
};

}  // namespace rayfarm::server
