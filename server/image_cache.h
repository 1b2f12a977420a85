// Finished images in memory, least recently used first out, within a byte budget.
#pragma once

#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>

namespace rayfarm::server {

class ImageCache {
 public:
  explicit ImageCache(std::uint64_t budget) : budget_(budget) {}

  std::shared_ptr<const std::string> get(const std::string& key) {
    std::lock_guard lock(mu_);
    auto it = index_.find(key);
    if (it == index_.end()) return nullptr;
    order_.splice(order_.begin(), order_, it->second);
    return it->second->second;
  }

  void put(const std::string& key, std::shared_ptr<const std::string> bytes) {
    std::lock_guard lock(mu_);
    if (auto it = index_.find(key); it != index_.end()) {
      bytes_ -= it->second->second->size();
      order_.erase(it->second);
      index_.erase(it);
    }
    if (bytes->size() > budget_) return;
    bytes_ += bytes->size();
    order_.emplace_front(key, std::move(bytes));
    index_[key] = order_.begin();
    while (bytes_ > budget_ && !order_.empty()) {
      bytes_ -= order_.back().second->size();
      index_.erase(order_.back().first);
      order_.pop_back();
    }
  }

  void erase(const std::string& key) {
    std::lock_guard lock(mu_);
    if (auto it = index_.find(key); it != index_.end()) {
      bytes_ -= it->second->second->size();
      order_.erase(it->second);
      index_.erase(it);
    }
  }

  std::uint64_t bytes() const {
    std::lock_guard lock(mu_);
    return bytes_;
  }

 private:
  using Item = std::pair<std::string, std::shared_ptr<const std::string>>;
  const std::uint64_t budget_;
  mutable std::mutex mu_;
  std::list<Item> order_;
  std::unordered_map<std::string, std::list<Item>::iterator> index_;
  std::uint64_t bytes_ = 0;
};

}  // namespace rayfarm::server
