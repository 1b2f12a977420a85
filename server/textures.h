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
  UploadedTextures(const TextureFiles& files, long long max_pixels)
      : files_(files), max_pixels_(max_pixels) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override;
  long long max_pixels() const override { return max_pixels_; }

 private:
  const TextureFiles& files_;
  long long max_pixels_;
};

// What is wrong with the first uploaded part that `scene` names as no texture: "part 'x' is
// not a texture the scene names; did you mean 'y'?"; empty when the scene names them all.
std::string unnamed_part(const Scene& scene, const TextureFiles& files);

}  // namespace rayfarm::server
