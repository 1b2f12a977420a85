// Texture files into a scene's textures, through the caller's resolver (core never opens a
// file itself: the CLI reads beside the model file, the server only what was uploaded).
#include "rayfarm/image_io.h"
#include "rayfarm/scene.h"

namespace rayfarm {

bool resolve_textures(Scene& scene, const ResourceResolver& resolver, Diagnostics& diags) {
  bool ok = true;
  for (Texture& t : scene.textures) {
    if (t.image) continue;
    const std::string what = t.name.empty() ? "texture '" + t.path + "'"
                                            : "texture '" + t.name + "' ('" + t.path + "')";
    std::string error;
    std::optional<std::string> bytes = resolver.read(t.path, error);
    if (!bytes) {
      diags.error("texture-missing", "cannot read " + what + ": " + error, t.path_where);
      ok = false;
      continue;
    }
    std::optional<Image> image = decode_image(*bytes, &error, resolver.max_pixels());
    if (!image) {
      diags.error("texture-invalid", what + " is not a readable image: " + error, t.path_where);
      ok = false;
      continue;
    }
    t.image = std::make_shared<const Image>(std::move(*image));
  }
  return ok;
}

}  // namespace rayfarm
