// Scene text to a checked scene.
#include "rayfarm/load.h"

#include <algorithm>
#include <vector>

#include "format/json_tree.h"
#include "format/model_fast.h"
#include "rayfarm/json_scene.h"
#include "rayfarm/model_parser.h"

namespace rayfarm {

SceneFormat detect_format(std::string_view text) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // UTF-8 byte-order mark
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') continue;
    // '[' and '"' begin no model file: JSON of the wrong shape, to be told so as JSON.
    return c == '{' || c == '[' || c == '"' ? SceneFormat::json : SceneFormat::model;
  }
  return SceneFormat::model;
}

namespace {

// What a file that is not a scene at all is, so that it is named rather than parsed into a
// page of errors (and its bytes never echoed to a terminal). Only signatures that no scene
// can begin with: the loader must refuse exactly what the parser refuses.
std::string not_a_scene(std::string_view text) {
  if (text.starts_with("\x89PNG")) return "this is a PNG image, not a scene";
  if (text.starts_with("\xFF\xD8\xFF")) return "this is a JPEG image, not a scene";
  if (text.starts_with("GIF8")) return "this is a GIF image, not a scene";
  if (text.size() > 2 && text[0] == 'P' && (text[1] == '3' || text[1] == '6') &&
      (text[2] == '\n' || text[2] == ' ' || text[2] == '\r' || text[2] == '\t'))
    return "this is a PPM image, not a scene";
  if (text.starts_with("PK\x03\x04")) return "this is a zip archive, not a scene";
  if (text.starts_with("\x1F\x8B")) return "this is gzip-compressed, not a scene";
  // UTF-16, as some editors save text: with its byte-order mark, or an ASCII character and a
  // NUL byte (no scene holds a NUL).
  if (text.starts_with("\xFF\xFE") || text.starts_with("\xFE\xFF") ||
      (text.size() >= 2 && (text[0] == '\0') != (text[1] == '\0')))
    return "this is UTF-16 text (save the scene as UTF-8)";
  return "";
}

}  // namespace

std::optional<std::string> RecordingResolver::read(const std::string& path,
                                                   std::string& error) const {
  auto bytes = inner_.read(path, error);
  if (bytes) files_[path] = *bytes;
  return bytes;
}

std::vector<size_t> places_in_text(std::string_view text, const std::vector<Diagnostic>& ds) {
  std::vector<size_t> place(ds.size(), 0);
  std::vector<std::string> pointers;
  std::vector<size_t> by_pointer;
  std::vector<size_t> line_start;  // filled on the first diagnostic with a line
  for (size_t i = 0; i < ds.size(); ++i) {
    const Where& w = ds[i].where;
    if (w.line > 0) {
      if (line_start.empty()) {
        line_start.push_back(0);
        for (size_t k = 0; k < text.size(); ++k)
          if (text[k] == '\n') line_start.push_back(k + 1);
      }
      const size_t line = std::min(static_cast<size_t>(w.line), line_start.size()) - 1;
      place[i] = line_start[line] + static_cast<size_t>(std::max(w.column, 1) - 1);
    } else if (!w.path.empty()) {
      pointers.push_back(w.path);
      by_pointer.push_back(i);
    }
  }
  if (!pointers.empty()) {
    const std::vector<size_t> offsets = json_pointer_offsets(text, pointers);
    for (size_t k = 0; k < by_pointer.size(); ++k) place[by_pointer[k]] = offsets[k];
  }
  return place;
}

void in_file_order(std::string_view text, std::vector<Diagnostic>& ds) {
  sort_by_place(ds, places_in_text(text, ds));
}

LoadedScene load_scene(std::string_view text, LoadDetail detail,
                       const ResourceResolver* resolver) {
  LoadedScene out;
  if (std::string what = not_a_scene(text); !what.empty()) {
    out.diags.error("not-a-scene", what + ": a scene is a model file or JSON text", Where{});
    return out;
  }
  const SceneFormat format = detect_format(text);
  if (format == SceneFormat::json && text.size() > kMaxJsonSceneBytes) {
    out.diags.error("json-size",
                    "a JSON scene of " + std::to_string(text.size() >> 20) +
                        " MiB is over the limit of 128 MiB (reading JSON takes some 30 times its "
                        "size in memory): write the scene as a model file",
                    Where{});
    return out;
  }
  if (detail == LoadDetail::scene && format == SceneFormat::model) {
    out.scene = load_model_fast(text);
    if (out.scene) return out;  // the fast path reads no kind that has textures
  }
  out.desc = format == SceneFormat::json ? parse_json_scene(text, out.diags)
                                         : parse_model(text, out.diags);
  // Build even after parse errors, so missing attributes and bad references are reported in
  // the same pass; only input that did not parse at all (JSON syntax) stops here.
  if (!out.diags.has_errors() || !out.desc.entities.empty())
    out.scene = build_scene(out.desc, out.diags);
  if (out.scene && resolver && !resolve_textures(*out.scene, *resolver, out.diags))
    out.scene.reset();
  // A JSON scene's errors come from passes by kind (structure, then materials, objects,
  // ...); a model file's are read in order already.
  if (format == SceneFormat::json && out.diags.items().size() > 1)
    out.diags.reorder(places_in_text(text, out.diags.items()));
  return out;
}

}  // namespace rayfarm
