// Fast path of the model-file loader (see model_fast.h). It reads the same tokens as the
// full parser (the same lexer) and applies the same schema table: value counts, ranges,
// defaults, required attributes, names and material references. It gives up rather than
// deciding anything the full parser would decide differently.
#include "format/model_fast.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "format/model_lexer.h"
#include "util/count_byte.h"
#include "util/lines.h"
#include "util/name_set.h"
#include "rayfarm/model_parser.h"
#include "rayfarm/schema.h"

namespace rayfarm {
namespace {

constexpr size_t kMaxAttrs = 5;  // the most any entity it reads has (a material)

// One entity's attribute values, by their place in the entity's spec.
struct Values {
  double v[kMaxAttrs][3];
  bool seen[kMaxAttrs] = {};
  std::string_view material;  // a material_ref's name

  glm::dvec3 vec3(size_t k) const { return {v[k][0], v[k][1], v[k][2]}; }
};

class FastLoader {
 public:
  explicit FastLoader(std::string_view text) : text_(text), lex_(text) {}
  // A loader for the part of a file from a line start (see load_model_fast).
  FastLoader(std::string_view rest, int first_line) : text_(rest), lex_(rest, first_line) {}

  // Reads every entity; false at the first thing that is not plainly valid.
  bool parse() {
    reserve(0);
    return parse_reserved();
  }

  // Room for this part's entities and, with `more_bytes` > 0, for those of a part of that
  // length to be appended. An entity takes at least one '{': enough room for all spheres
  // without regrowth. The room for a part to be appended is a bound (an entity takes 16
  // bytes at least), never touched unless used: the append then moves those objects once,
  // into pages of this array, instead of moving both parts into a third one (fresh pages
  // cost more than the moves on the machines measured).
  void reserve(size_t more_bytes) {
    braces_ = count_byte(text_, '{');
    braces_ = std::min(braces_, text_.size() / 16 + 1);  // at most one entity per 16 bytes
    const size_t room = braces_ + (more_bytes > 0 ? more_bytes / 16 + 1 : 0);
    scene_.objects.reserve(room);
    object_materials_.reserve(room);
    names_[static_cast<int>(EntityKind::sphere)].reserve(braces_);
    room_ = {scene_.objects.data(), object_materials_.data(), room};
  }

  // The arrays a part appended to this one goes into, as reserve left them: they are not
  // moved while this part is read, so another thread may fault in their pages meanwhile.
  struct Room {
    Object* objects = nullptr;
    std::string_view* materials = nullptr;
    size_t capacity = 0;
  };
  Room room() const { return room_; }
  // No more entities than this in this part (set by reserve, then constant).
  size_t entity_bound() const { return braces_; }

  bool parse_reserved() {
    for (;;) {
      const Token t = lex_.next();
      if (t.kind == Token::end) return true;
      if (t.kind != Token::word) return false;
      const EntitySpec* spec = find_entity(t.text);
      if (!spec || !spec->fast_path || !entity(*spec, t)) return false;
    }
  }

  // Appends the entities of the part of the file that follows this one; false if a name
  // there repeats one here.
  bool append(FastLoader&& rest) {
    auto unique = [&](EntityKind kind, const std::string& name) {
      return name.empty() || !names_[static_cast<int>(kind)].find(name);
    };
    Scene& more = rest.scene_;
    for (const Camera& c : more.cameras)
      if (!unique(EntityKind::camera, c.name)) return false;
    for (const Material& m : more.materials)
      if (!unique(EntityKind::material, m.name)) return false;
    for (const Light& l : more.lights)
      if (!unique(EntityKind::light, l.name)) return false;
    // The objects' names, the many: each probe's slot is loaded a few objects ahead.
    constexpr size_t kAhead = 8;
    const std::vector<Object>& objects = more.objects;
    size_t ahead[kAhead];
    auto start = [&](size_t i) {
      const std::string& name = objects[i].name;
      const NameSet<NoPayload>& names = names_[static_cast<int>(objects[i].kind)];
      ahead[i % kAhead] = names.hash(name);
      names.prefetch(ahead[i % kAhead]);
    };
    for (size_t i = 0; i < std::min(kAhead, objects.size()); ++i) start(i);
    for (size_t i = 0; i < objects.size(); ++i) {
      const Object& o = objects[i];
      const size_t h = ahead[i % kAhead];
      if (i + kAhead < objects.size()) start(i + kAhead);
      if (!o.name.empty() && names_[static_cast<int>(o.kind)].find(o.name, h)) return false;
    }
    auto move_all = [](auto& to, auto& from) {
      to.insert(to.end(), std::make_move_iterator(from.begin()), std::make_move_iterator(from.end()));
    };
    move_all(scene_.cameras, more.cameras);
    move_all(scene_.materials, more.materials);
    move_all(scene_.lights, more.lights);
    move_all(scene_.objects, more.objects);
    move_all(object_materials_, rest.object_materials_);
    return true;
  }

  size_t object_count() const { return scene_.objects.size(); }

  // The whole file's checks, once every entity is read.
  std::optional<Scene> finish() {
    if (scene_.cameras.empty()) return std::nullopt;
    // Materials may be defined after the objects that use them: resolve at the end.
    NameSet<int> materials;
    materials.reserve(scene_.materials.size());
    for (size_t i = 0; i < scene_.materials.size(); ++i)
      materials.insert(scene_.materials[i].name, static_cast<int>(i));
    for (size_t i = 0; i < scene_.objects.size(); ++i) {
      const int* index = materials.find(object_materials_[i]);
      if (!index) return std::nullopt;
      scene_.objects[i].material = *index;
    }
    return std::move(scene_);
  }

 private:
  static Where at(const Token& t) { return {t.line, t.column, {}}; }

  // KEYWORD [NAME] { ATTRIBUTE VALUES ... }, already past the keyword.
  bool entity(const EntitySpec& spec, const Token& keyword) {
    if (spec.attrs.size() > kMaxAttrs) return false;  // a schema grown past Values
    Token t = lex_.next();
    std::string_view name;
    if (t.kind == Token::word) {
      if (!is_valid_name(t.text)) return false;
      name = t.text;
      t = lex_.next();
    }
    if (t.kind != Token::open || (name.empty() && spec.name_required)) return false;
    // A repeated name is checked after the body: its slot loads meanwhile (a miss per
    // entity in a table of 100,000 names).
    NameSet<NoPayload>& names = names_[static_cast<int>(spec.kind)];
    const size_t name_hash = name.empty() ? 0 : names.hash(name);
    if (!name.empty()) names.prefetch(name_hash);

    Values values;
    for (;;) {
      const Token key = lex_.next();
      if (key.kind == Token::close) break;
      if (key.kind != Token::word) return false;
      const AttrSpec* attr = find_attr(spec, key.text);
      if (!attr) return false;
      const size_t k = static_cast<size_t>(attr - spec.attrs.data());
      if (values.seen[k]) return false;
      values.seen[k] = true;
      if (attr->kind == ValueKind::material_ref) {
        const Token v = lex_.next();
        if (v.kind != Token::word || starts_like_number(v.text) || find_attr(spec, v.text) ||
            find_entity(v.text) || !is_valid_name(v.text))
          return false;
        values.material = v.text;
        continue;
      }
      const int hi = value_count(attr->kind)[1];
      int n = 0;
      for (;;) {
        const Token& value = lex_.peek();
        if (value.kind != Token::word || !starts_like_number(value.text)) break;
        if (n == hi) return false;
        const std::optional<double> x = parse_number(value.text);
        lex_.drop();
        if (!x || !value_in_range(*attr, *x)) return false;
        values.v[k][n++] = *x;
      }
      if (!valid_value_count(attr->kind, n)) return false;
      if (n == 1 && attr->kind == ValueKind::colour) values.v[k][1] = values.v[k][2] = values.v[k][0];
      if (attr->kind == ValueKind::direction && is_zero_vector(values.v[k])) return false;
    }
    for (size_t k = 0; k < spec.attrs.size(); ++k) {
      if (values.seen[k]) continue;
      if (spec.attrs[k].required) return false;
      for (int i = 0; i < 3; ++i) values.v[k][i] = spec.attrs[k].fallback[i];
    }
    if (!name.empty() && names.insert(name, {}, name_hash)) return false;
    add(spec.kind, std::string(name), at(keyword), values);
    return true;
  }

  // Attribute places follow the schema table (scene/entities/*.cpp).
  void add(EntityKind kind, std::string name, Where where, const Values& v) {
    switch (kind) {
      case EntityKind::camera:
        scene_.cameras.push_back({std::move(name), std::move(where), static_cast<int>(v.v[0][0]),
                                  static_cast<int>(v.v[0][1]), v.v[1][0], v.v[1][1], v.vec3(2)});
        break;
      case EntityKind::material:
        scene_.materials.push_back({std::move(name), std::move(where), v.vec3(0), v.vec3(1),
                                    v.vec3(2),
                                    v.seen[3] ? std::optional<double>(v.v[3][0]) : std::nullopt,
                                    v.v[4][0]});
        break;
      case EntityKind::light: {
        Light& l = scene_.lights.emplace_back();
        l.name = std::move(name);
        l.where = std::move(where);
        l.location = v.vec3(0);
        l.emissivity = v.vec3(1);
        break;
      }
      case EntityKind::sphere:
        scene_.objects.push_back({std::move(name), std::move(where), kind, -1,
                                  Sphere{v.vec3(1), v.v[2][0]}});
        object_materials_.push_back(v.material);
        break;
      case EntityKind::plane:
        scene_.objects.push_back({std::move(name), std::move(where), kind, -1,
                                  Plane{v.vec3(1), v.vec3(2)}});
        object_materials_.push_back(v.material);
        break;
      default:  // only kinds with fast_path in the schema get here
        break;
    }
  }

  std::string_view text_;
  ModelLexer lex_;
  Scene scene_;
  NameSet<NoPayload> names_[kEntityKinds];  // names per entity kind: a repeated one is an error
  std::vector<std::string_view> object_materials_;  // per object: its material's name
  size_t braces_ = 0;  // a bound on this part's entities (reserve)
  Room room_;
};

// Has the kernel supply the pages of [at, at + bytes) now, on this thread (Linux 5.14+;
// elsewhere nothing happens). Memory new to a process costs about 1 ms per MB on the
// virtual machines measured, mostly the host's: a thread that would wait anyway pays it
// instead of the one on the critical path. Whole pages inside the range only.
void prefault(void* at, size_t bytes) {
#ifdef MADV_POPULATE_WRITE
  const auto page = static_cast<std::uintptr_t>(sysconf(_SC_PAGESIZE));
  const auto from = (reinterpret_cast<std::uintptr_t>(at) + page - 1) & ~(page - 1);
  const auto to = (reinterpret_cast<std::uintptr_t>(at) + bytes) & ~(page - 1);
  if (to > from) madvise(reinterpret_cast<void*>(from), to - from, MADV_POPULATE_WRITE);
#else
  (void)at;
  (void)bytes;
#endif
}

// Where a large file can be cut in two: the start of a line that begins with an entity
// keyword, just after a line that ends with '}'; npos if none is near the middle. A cut at
// a line start never falls inside a token or a comment, and if it fell inside an entity,
// one of the parts would not parse and the whole file is read in one piece after all.
size_t split_point(std::string_view text) {
  constexpr size_t kSearch = 1 << 16;
  const size_t end = std::min(text.size(), text.size() / 2 + kSearch);
  for (size_t i = text.find('\n', text.size() / 2); i != std::string_view::npos && i < end;
       i = text.find('\n', i + 1)) {
    size_t k = i;
    while (k > 0 && (text[k - 1] == ' ' || text[k - 1] == '\t' || text[k - 1] == '\r')) --k;
    if (k == 0 || text[k - 1] != '}') continue;
    size_t w = i + 1;
    while (w < text.size() && ((text[w] >= 'a' && text[w] <= 'z') || (text[w] >= 'A' && text[w] <= 'Z')))
      ++w;
    if (w > i + 1 && find_entity(text.substr(i + 1, w - i - 1))) return i + 1;
  }
  return std::string_view::npos;
}

}  // namespace

std::optional<Scene> load_model_fast(std::string_view text, std::size_t parallel_min) {
  if (text.size() >= parallel_min && std::thread::hardware_concurrency() > 1) {
    if (const size_t cut = split_point(text); cut != std::string_view::npos) {
      const int line = 1 + static_cast<int>(count_lines(text.substr(0, cut)));
      FastLoader head(text.substr(0, cut)), tail(text.substr(cut), line);
      bool tail_ok = false;
      // The tail's objects will be moved into room the head reserved and has not touched:
      // whichever part is read first faults those pages in while the other is still being
      // read (shallow-60k: 4 MB), instead of the head after both. Only as many objects'
      // pages as the part read first has really read: an entity bound counts every '{',
      // comments' too, and a file of commented braces must not make its reader fault in
      // memory for objects it does not have.
      std::atomic<bool> head_reserved{false}, tail_reserved{false}, claimed{false};
      auto prefault_room = [&head](size_t from, size_t count) {
        const FastLoader::Room room = head.room();
        const size_t end = std::min(from + count, room.capacity);
        if (end <= from) return;
        prefault(room.objects + from, (end - from) * sizeof(Object));
        prefault(room.materials + from, (end - from) * sizeof(std::string_view));
      };
      std::thread reader([&] {
        tail.reserve(0);
        tail_reserved.store(true, std::memory_order_release);
        tail_ok = tail.parse_reserved();
        // The tail's objects land where the head's end, a few entities (its cameras,
        // materials and lights) short of its bound. The head's count is not known until it
        // is read, so this faults in from the bound: those few are left to the move.
        if (tail_ok && head_reserved.load(std::memory_order_acquire) && !claimed.exchange(true))
          prefault_room(head.entity_bound(), tail.object_count());
      });
      head.reserve(text.size() - cut);
      head_reserved.store(true, std::memory_order_release);
      const bool head_ok = head.parse_reserved();
      // The tail's count is not known yet: as many as the head's (the cut halves the bytes),
      // and no more than the tail's bound.
      if (head_ok && tail_reserved.load(std::memory_order_acquire) && !claimed.exchange(true))
        prefault_room(head.object_count(),
                      std::min(tail.entity_bound(), head.object_count() + 1024));
      reader.join();
      // Both parts read: the cut was at an entity boundary, so the answer is final (a name
      // repeated across the cut fails in one piece too). Otherwise read it in one piece.
      if (head_ok && tail_ok)
        return head.append(std::move(tail)) ? head.finish() : std::nullopt;
    }
  }
  FastLoader whole(text);
  if (!whole.parse()) return std::nullopt;
  return whole.finish();
}

}  // namespace rayfarm
