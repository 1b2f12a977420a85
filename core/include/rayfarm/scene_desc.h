// A parsed scene exactly as written, before any defaults or checks beyond syntax:
// a list of entities with their attributes and source positions. Both the model-file and
// the JSON parser produce it; validation, conversion and scene building consume it.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rayfarm/diagnostic.h"
#include "rayfarm/options.h"

namespace rayfarm {

// A vector that keeps up to N elements inline (no allocation), and all of them on the heap
// only beyond that. Attribute values have at most 3 numbers, so a parsed scene of many
// spheres does not cost allocations per attribute.
template <class T, size_t N>
class SmallVec {
 public:
  using value_type = T;
  using size_type = size_t;
  using reference = T&;
  using const_reference = const T&;
  using iterator = T*;
  using const_iterator = const T*;

  SmallVec() = default;
  SmallVec(std::initializer_list<T> init) {
    for (const T& v : init) push_back(v);
  }
  SmallVec(const SmallVec& o) { *this = o; }
  SmallVec(SmallVec&& o) noexcept { *this = std::move(o); }
  SmallVec& operator=(const SmallVec& o) {
    if (this == &o) return *this;
    clear();
    for (const T& v : o) push_back(v);
    return *this;
  }
  SmallVec& operator=(SmallVec&& o) noexcept {
    if (this == &o) return *this;
    heap_ = std::move(o.heap_);
    if (!heap_)
      for (uint32_t i = 0; i < o.size_; ++i) inline_[i] = std::move(o.inline_[i]);
    size_ = o.size_;
    o.size_ = 0;
    return *this;
  }

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return heap_ ? heap_->data() : inline_; }
  const T* data() const { return heap_ ? heap_->data() : inline_; }
  T* begin() { return data(); }
  T* end() { return data() + size_; }
  const T* begin() const { return data(); }
  const T* end() const { return data() + size_; }
  T& operator[](size_t i) { return data()[i]; }
  const T& operator[](size_t i) const { return data()[i]; }
  T& front() { return data()[0]; }
  const T& front() const { return data()[0]; }
  T& back() { return data()[size_ - 1]; }
  const T& back() const { return data()[size_ - 1]; }

  void push_back(T v) {
    if (!heap_ && size_ < N) {
      inline_[size_++] = std::move(v);
      return;
    }
    if (!heap_) {
      heap_ = std::make_unique<std::vector<T>>();
      heap_->reserve(2 * N);
      for (T& x : inline_) heap_->push_back(std::move(x));
    }
    heap_->push_back(std::move(v));
    ++size_;
  }
  template <class... Args>
  T& emplace_back(Args&&... args) {
    push_back(T(std::forward<Args>(args)...));
    return back();
  }
  void clear() {
    size_ = 0;
    heap_.reset();
  }
  void assign(size_t n, const T& v) {
    T copy = v;  // v may be one of ours
    clear();
    for (size_t i = 0; i < n; ++i) push_back(copy);
  }

  friend bool operator==(const SmallVec& a, const SmallVec& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
  }
  friend bool operator==(const SmallVec& a, const std::vector<T>& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
  }

 private:
  T inline_[N] = {};
  uint32_t size_ = 0;
  std::unique_ptr<std::vector<T>> heap_;  // all elements, once there are more than N
};

// Where each value of an attribute was written, compactly: line and column inline, a JSON
// path only when there is one. Element i reads back as the Where that was added.
class ValuePositions {
 public:
  ValuePositions() = default;
  ValuePositions(const ValuePositions& o) { *this = o; }
  ValuePositions(ValuePositions&&) noexcept = default;
  ValuePositions& operator=(const ValuePositions& o) {
    if (this == &o) return *this;
    pos_ = o.pos_;
    paths_.reset(o.paths_ ? new std::vector<std::string>(*o.paths_) : nullptr);
    json_ = o.json_;
    return *this;
  }
  ValuePositions& operator=(ValuePositions&&) noexcept = default;

  size_t size() const { return pos_.size(); }
  bool empty() const { return pos_.empty(); }
  Where operator[](size_t i) const {
    return {pos_[i].line, pos_[i].column, paths_ ? (*paths_)[i] : std::string()};
  }
  Where front() const { return (*this)[0]; }
  Where back() const { return (*this)[size() - 1]; }
  void push_back(const Where& w) {
    if (!w.path.empty() && !paths_) paths_ = std::make_unique<std::vector<std::string>>(size());
    if (paths_) paths_->push_back(w.path);
    pos_.push_back({w.line, w.column});
  }
  void clear() {
    pos_.clear();
    paths_.reset();
    json_ = 0;
  }
  // A JSON value, whose path follows from its attribute's: that path itself (a lone number
  // or name), or that path and the index (an array's elements). No path is stored; read
  // such values back with AttrDesc::value_at.
  void push_json(bool element) {
    json_ = element ? 2 : 1;
    pos_.push_back({});
  }
  int json_mode() const { return json_; }  // 0 none, 1 the attribute's path, 2 path/index

 private:
  struct Pos {
    int line = 0;
    int column = 0;
  };
  SmallVec<Pos, 3> pos_;
  std::unique_ptr<std::vector<std::string>> paths_;  // one per value, when any has a path
  std::uint8_t json_ = 0;
};

// Every entity keyword of the format, in the order of the registry (core/src/scene/registry.cpp).
enum class EntityKind {
  camera, material, texture,                  // what objects and lights refer to
  light, spotlight, projector,                // lights
  sphere, plane, fplane, tiled_plane, texplane, triangle, tri, revsurf,  // objects
};
inline constexpr int kEntityKinds = 14;

struct AttrDesc {
  std::string key;
  SmallVec<double, 3> numbers;  // numeric values as written (a one-number colour stays one)
  std::string word;             // for name- and path-valued attributes (material, texname)
  Where where;                  // the attribute keyword
  ValuePositions value_where;   // read back with value_at

  // Where value i was written; the attribute's own place for one it has none for.
  Where value_at(size_t i) const;
};

struct EntityDesc {
  EntityKind kind = EntityKind::camera;
  std::string name;  // empty when the model file gave none
  Where where;       // the entity keyword
  Where name_where;
  std::vector<AttrDesc> attrs;
  // Attributes that were written but had errors: not "missing", and not reported again.
  std::vector<std::string> invalid_keys;

  const AttrDesc* find(std::string_view key) const;
};

struct SceneDesc {
  std::vector<EntityDesc> entities;
  // Render options carried by the scene itself (the JSON "render" object).
  OptionSet render;
};

}  // namespace rayfarm
