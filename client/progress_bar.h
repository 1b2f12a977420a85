// A one-line progress bar on a terminal, redrawn at most a few times a second; plain lines
// when not a terminal (and only when asked).
#pragma once

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

#include "rayfarm/render.h"

namespace rayfarm::cli {

class ProgressBar {
 public:
  explicit ProgressBar(bool enabled) : enabled_(enabled) {}

  void update(double fraction, const RenderStats& st) {
    if (!enabled_) return;
    std::lock_guard lock(mu_);
    auto now = std::chrono::steady_clock::now();
    // Quick renders finish before the bar would tell anything.
    if (now - start_ < std::chrono::milliseconds(300) || now - last_ < std::chrono::milliseconds(100))
      return;
    last_ = now;
    draw(fraction, st.spp_done, st.spp_target, st.error_estimate);
  }

  void draw(double fraction, int spp_done, int spp_target, double error) {
    constexpr int kWidth = 30;
    int filled = static_cast<int>(fraction * kWidth + 0.5);
    std::string bar(filled, '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r[%s] %5.1f%%  spp %d/%d", bar.c_str(), fraction * 100, spp_done,
                 spp_target);
    if (error >= 0) std::fprintf(stderr, "  error %.2f", error);
    std::fprintf(stderr, "   ");
    std::fflush(stderr);
    drawn_ = true;
  }

  void finish() {
    std::lock_guard lock(mu_);
    if (drawn_) std::fprintf(stderr, "\r%*s\r", 70, "");
    drawn_ = false;
  }

 private:
  bool enabled_;
  bool drawn_ = false;
  std::mutex mu_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace rayfarm::cli
