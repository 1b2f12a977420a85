// The content key of a render: what decides its every byte, hashed. Equal keys, equal images;
// the server's cache, the grader's reference cache and its lock files all use it.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "rayfarm/options.h"
#include "rayfarm/scene.h"
#include "rayfarm/scene_desc.h"

namespace rayfarm {

// The scene as parsed (so layout and comments do not matter, and a model file and its JSON
// twin share results), the hash of each texture file it names, every option that changes
// pixels (not the format: caches hold PNGs and convert), and the render version.
std::string content_key(const SceneDesc& desc, const RenderOptions& options,
                        const std::vector<std::string>& texture_hashes);

// The SHA-256 of each of the scene's textures, in its order, from the files by the path the
// scene writes (each must be there).
std::vector<std::string> texture_hashes(const Scene& scene,
                                        const std::map<std::string, std::string>& files);

}  // namespace rayfarm
