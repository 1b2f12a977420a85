// Scene text to a checked scene.
#include "rayfarm/load.h"

#include "format/model_fast.h"
#include "rayfarm/json_scene.h"
#include "rayfarm/model_parser.h"

namespace rayfarm {

SceneFormat detect_format(std::string_view text) {
  if (text.starts_with("\xEF\xBB\xBF")) text.remove_prefix(3);  // UTF-8 byte-order mark
  for (char c : text) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') continue;
    return c == '{' ? SceneFormat::json : SceneFormat::model;
  }
  return SceneFormat::model;
}

LoadedScene load_scene(std::string_view text, LoadDetail detail,
                       const ResourceResolver* resolver) {
  LoadedScene out;
  const SceneFormat format = detect_format(text);
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
  return out;
}

}  // namespace rayfarm
