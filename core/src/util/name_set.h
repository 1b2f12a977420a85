// Names seen so far, for duplicate checks over scenes of 100,000 objects: an open-addressing
// hash set of string views (the text they point into outlives the set), each with a small
// payload. Slots keep the hash, so a probe compares names only when the hashes match.
#pragma once

#include <algorithm>
#include <functional>
#include <string_view>
#include <vector>

namespace rayfarm {

template <class Payload>
class NameSet {
 public:
  void reserve(size_t n) {
    size_t want = 16;
    while (want < 2 * n) want *= 2;
    if (want > slots_.size()) rehash(want);
  }

  // The payload of the name, or nullptr when it is not in the set.
  const Payload* find(std::string_view name) const {
    if (slots_.empty()) return nullptr;
    const size_t h = std::hash<std::string_view>{}(name);
    const size_t mask = slots_.size() - 1;
    for (size_t i = h & mask;; i = (i + 1) & mask) {
      const Slot& s = slots_[i];
      if (!s.used) return nullptr;
      if (s.hash == h && s.name == name) return &s.payload;
    }
  }

  // Adds the name; returns the payload of the name's first insertion, or nullptr when the
  // name is new.
  const Payload* insert(std::string_view name, Payload payload) {
    if (2 * (count_ + 1) > slots_.size()) rehash(std::max<size_t>(16, 2 * slots_.size()));
    const size_t h = std::hash<std::string_view>{}(name);
    const size_t mask = slots_.size() - 1;
    for (size_t i = h & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (!s.used) {
        s = {h, name, payload, true};
        ++count_;
        return nullptr;
      }
      if (s.hash == h && s.name == name) return &s.payload;
    }
  }

 private:
  struct Slot {
    size_t hash = 0;
    std::string_view name;
    Payload payload{};
    bool used = false;
  };

  void rehash(size_t size) {
    std::vector<Slot> old(size);
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& s : old) {
      if (!s.used) continue;
      size_t i = s.hash & mask;
      while (slots_[i].used) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }

  std::vector<Slot> slots_;
  size_t count_ = 0;
};

}  // namespace rayfarm
