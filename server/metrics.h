// Prometheus metrics (text exposition format 0.0.4), names prefixed rayfarm_.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace rayfarm::server {

class Metrics {
 public:
  void request(const std::string& route, int status);
  void render_finished(const std::string& state, double seconds, std::uint64_t primary,
                       std::uint64_t shadow, std::uint64_t reflection);
  void cache(bool hit) { (hit ? cache_hits_ : cache_misses_).fetch_add(1); }
  void merged() { merged_.fetch_add(1); }
  void rejected(const std::string& reason);

  struct Gauges {
    std::map<std::string, long> jobs_by_state;
    long queue_depth = 0;
    long running = 0;
    long workers = 0;
    long event_streams = 0;
    long waiting_requests = 0;
    long waiting_loads = 0;
    long cache_bytes = 0;
  };
  std::string render_text(const Gauges& gauges) const;

 private:
  static constexpr std::array<double, 10> kBuckets = {0.01, 0.05, 0.1, 0.25, 0.5,
                                                      1,    2.5,  5,   10,  60};
  mutable std::mutex mu_;
  std::map<std::pair<std::string, int>, std::uint64_t> requests_;
  std::map<std::string, std::uint64_t> finished_;
  std::map<std::string, std::uint64_t> rejected_;
  std::array<std::uint64_t, kBuckets.size() + 1> render_buckets_{};
  double render_sum_ = 0;
  std::uint64_t render_count_ = 0;
  std::uint64_t rays_[3] = {0, 0, 0};
  std::atomic<std::uint64_t> cache_hits_{0}, cache_misses_{0}, merged_{0};
};

}  // namespace rayfarm::server
