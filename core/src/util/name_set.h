// Names seen so far, for duplicate checks over scenes of 100,000 objects: an open-addressing
// hash set of string views (the text they point into outlives the set), each with a small
// payload. Slots keep 32 bits of the hash, so a probe reads a name's text only when those
// match; with no payload (NoPayload) a slot is 16 bytes: the fast loader's tables of a
// 100,000-sphere file take 4 MB of fresh memory instead of 8.
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <string_view>
#include <vector>

namespace rayfarm {

struct NoPayload {};

template <class Payload>
class NameSet {
 public:
  void reserve(size_t n) {
    size_t want = 16;
    while (want < 2 * n) want *= 2;
    if (want > slots_.size()) rehash(want);
  }

  static size_t hash(std::string_view name) { return std::hash<std::string_view>{}(name); }

  // Starts loading the slot where a name of hash h is first looked for, so that a caller
  // with other work before its find or insert does not wait for it there. Changes nothing.
  void prefetch(size_t h) const {
    if (!slots_.empty()) __builtin_prefetch(&slots_[h & (slots_.size() - 1)], 1);
  }

  // The payload of the name, or nullptr when it is not in the set.
  const Payload* find(std::string_view name) const { return find(name, hash(name)); }
  // The same, with h = hash(name) computed by the caller.
  const Payload* find(std::string_view name, size_t h) const {
    if (name.size() > kMaxSize) return find_long(name);
    if (slots_.empty()) return nullptr;
    const size_t mask = slots_.size() - 1;
    for (size_t i = h & mask;; i = (i + 1) & mask) {
      const Slot& s = slots_[i];
      if (!s.data) return nullptr;
      if (s.matches(static_cast<std::uint32_t>(h), name)) return &s.payload;
    }
  }

  // Adds the name; returns the payload of the name's first insertion, or nullptr when the
  // name is new.
  const Payload* insert(std::string_view name, Payload payload) {
    return insert(name, payload, hash(name));
  }
  // The same, with h = hash(name) computed by the caller.
  const Payload* insert(std::string_view name, Payload payload, size_t h) {
    if (name.size() > kMaxSize) {
      if (const Payload* p = find_long(name)) return p;
      long_.push_back({name, payload});
      return nullptr;
    }
    if (2 * (count_ + 1) > slots_.size()) rehash(std::max<size_t>(16, 2 * slots_.size()));
    const size_t mask = slots_.size() - 1;
    for (size_t i = h & mask;; i = (i + 1) & mask) {
      Slot& s = slots_[i];
      if (!s.data) {
        // A view with no text (an empty default) still needs a non-null mark of use.
        s = {static_cast<std::uint32_t>(h), static_cast<std::uint32_t>(name.size()),
             name.data() ? name.data() : "", payload};
        ++count_;
        return nullptr;
      }
      if (s.matches(static_cast<std::uint32_t>(h), name)) return &s.payload;
    }
  }

 private:
  // Longer names (none a real scene has) go to a list of their own.
  static constexpr size_t kMaxSize = std::numeric_limits<std::uint32_t>::max();

  struct Slot {
    std::uint32_t hash = 0;  // the low half of the name's
    std::uint32_t size = 0;
    const char* data = nullptr;  // null: an empty slot
    [[no_unique_address]] Payload payload{};

    bool matches(std::uint32_t h, std::string_view name) const {
      return hash == h && size == name.size() && std::string_view(data, size) == name;
    }
  };

  struct Long {
    std::string_view name;
    Payload payload;
  };

  const Payload* find_long(std::string_view name) const {
    for (const Long& l : long_)
      if (l.name == name) return &l.payload;
    return nullptr;
  }

  void rehash(size_t size) {
    std::vector<Slot> old(size);
    old.swap(slots_);
    const size_t mask = slots_.size() - 1;
    for (const Slot& s : old) {
      if (!s.data) continue;
      // The low half of the hash places it as the whole did: the mask is narrower.
      size_t i = s.hash & mask;
      while (slots_[i].data) i = (i + 1) & mask;
      slots_[i] = s;
    }
  }

  std::vector<Slot> slots_;
  size_t count_ = 0;
  std::vector<Long> long_;
};

}  // namespace rayfarm
