// One call from scene text to a checked scene: format detection, parsing, building.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "rayfarm/diagnostic.h"
#include "rayfarm/scene.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

enum class SceneFormat { model, json };

// The largest JSON scene read: a document tree takes some 30 times its text in memory (a
// model file of the same scene, a fraction of that), so 128 MiB of JSON is a few GiB.
inline constexpr size_t kMaxJsonSceneBytes = size_t{128} << 20;

// JSON when the first non-blank character is '{' (or '[' or '"', which begin no model
// file), a model file otherwise.
SceneFormat detect_format(std::string_view text);

// Where each diagnostic lies in `text`, as a byte offset: at its line and column, else at
// its JSON path's place (a member's key, an element's value); 0 for one about the scene as a
// whole. Sorted by it, they are in the order of the file. load_scene leaves its own so.
std::vector<size_t> places_in_text(std::string_view text, const std::vector<Diagnostic>& ds);
// Sorts `ds` by places_in_text, ties as they were.
void in_file_order(std::string_view text, std::vector<Diagnostic>& ds);

// What a caller needs back: `full` keeps the parsed description (for converters and content
// keys); `scene` lets a plainly valid model file skip it, which loads it several times faster.
enum class LoadDetail { full, scene };

struct LoadedScene {
  SceneDesc desc;  // empty when LoadDetail::scene took the fast path
  std::optional<Scene> scene;  // set when there were no errors
  Diagnostics diags;
};

// Reads through another resolver and keeps each file it read, by the path the scene writes:
// what a scene sent elsewhere (to a server, into a content key) must carry with it.
class RecordingResolver final : public ResourceResolver {
 public:
  explicit RecordingResolver(const ResourceResolver& inner) : inner_(inner) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override;
  long long max_pixels() const override { return inner_.max_pixels(); }
  const std::map<std::string, std::string>& files() const { return files_; }

 private:
  const ResourceResolver& inner_;
  mutable std::map<std::string, std::string> files_;
};

// With a resolver, the scene's textures are read and decoded too (their errors are scene
// errors); without, they are left unresolved (a render of a scene with textures then fails).
LoadedScene load_scene(std::string_view text, LoadDetail detail = LoadDetail::full,
                       const ResourceResolver* resolver = nullptr);

}  // namespace rayfarm
