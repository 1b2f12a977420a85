// Uploaded textures (docs/http-api.md#textures): multipart parts named by the path the scene
// writes. The server reads textures only from these, never from its own disk: a path such as
// `../images/brick8.ppm` or `/etc/passwd` is a key, not a file.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rayfarm/scene.h"

namespace rayfarm::server {

// Path as the scene writes it -> the file's bytes.
using TextureFiles = std::map<std::string, std::string>;

class UploadedTextures final : public ResourceResolver {
 public:
  explicit UploadedTextures(const TextureFiles& files) : files_(files) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override;

 private:
  const TextureFiles& files_;
};

}  // namespace rayfarm::server
