#include "rayfarm/content_key.h"

#include <string_view>

#include "rayfarm/render.h"
#include "rayfarm/sha256.h"
#include "rayfarm/writers.h"

namespace rayfarm {

std::string content_key(const SceneDesc& desc, const RenderOptions& options,
                        const std::vector<std::string>& texture_hashes) {
  // The scene's render block is left out: `options` are the ones in effect, so a JSON scene
  // that asks for spp 4 and its model twin sent with spp=4 share one result.
  std::string text = "render-version " + std::to_string(kRenderVersion) + "\n" +
                     write_json(desc, false) + "\n" + canonical_string(options);
  for (const std::string& t : texture_hashes) text += "\ntexture " + t;
  return sha256_hex(text).substr(0, 40);
}

std::vector<std::string> texture_hashes(const Scene& scene,
                                        const std::map<std::string, std::string>& files) {
  std::map<std::string_view, std::string> by_path;
  std::vector<std::string> out;
  for (const Texture& t : scene.textures) {
    auto [it, added] = by_path.try_emplace(t.path);
    if (added) it->second = sha256_hex(files.at(t.path));
    out.push_back(it->second);
  }
  return out;
}

}  // namespace rayfarm
