// Textures uploaded with a scene: the resolver that serves only them, the limits on them, the
// parts a scene must name, and their files in the results directory while a job may render.
#include "textures.h"

#include <set>
#include <string_view>

#include "rayfarm/load.h"
#include "rayfarm/sha256.h"
#include "service.h"

namespace rayfarm::server {
namespace {

// Part names are the client's text: quoted in messages, but not at any length.
std::string clipped(const std::string& s) { return s.size() <= 200 ? s : s.substr(0, 200) + "..."; }

}  // namespace

std::optional<std::string> UploadedTextures::read(const std::string& path,
                                                  std::string& error) const {
  if (auto it = files_.find(path); it != files_.end()) return it->second;
  error = "it was not uploaded (send the file as a multipart part named '" + path + "')";
  return std::nullopt;
}

ApiError Service::check_uploads(const TextureFiles& files) const {
  const Settings& s = settings_;
  if (files.size() > static_cast<size_t>(s.max_textures))
    return limit_error("max_textures", "the request uploads " + std::to_string(files.size()) +
                                           " texture files; the limit is " +
                                           std::to_string(s.max_textures));
  for (const auto& [path, bytes] : files)
    if (bytes.size() > s.max_texture_bytes)
      return limit_error("max_texture_bytes",
                         "texture '" + clipped(path) + "' has " + std::to_string(bytes.size()) +
                             " bytes; the limit is " + std::to_string(s.max_texture_bytes));
  return {};
}

// A part the scene does not name is refused: a misspelt part name would otherwise leave the
// texture missing with no word about why. Missing and undecodable textures are scene errors
// at the place that names them.
std::string unnamed_part(const Scene& scene, const TextureFiles& files) {
  std::set<std::string_view> named;
  for (const Texture& t : scene.textures) named.insert(t.path);
  for (const auto& [path, bytes] : files) {
    if (named.count(path)) continue;
    const std::vector<std::string_view> paths(named.begin(), named.end());
    const std::string near = nearest_word(path, paths);
    return "part '" + clipped(path) + "' is not a texture the scene names" +
           (!near.empty()   ? "; did you mean '" + near + "'?"
            : named.empty() ? " (it names none)"
                            : "");
  }
  return {};
}

ApiError Service::resolve_uploads(Scene& scene, const TextureFiles& files) const {
  std::set<std::string_view> named;
  for (const Texture& t : scene.textures) named.insert(t.path);
  if (named.size() > static_cast<size_t>(settings_.max_textures))
    return limit_error("max_textures", "the scene names " + std::to_string(named.size()) +
                                           " texture files; the limit is " +
                                           std::to_string(settings_.max_textures));
  if (std::string unnamed = unnamed_part(scene, files); !unnamed.empty())
    return api_error(400, "unknown_part", unnamed);
  Diagnostics diags;
  if (!resolve_textures(scene, UploadedTextures(files, settings_.max_pixels), diags)) return scene_error(diags);
  return {};
}

void Service::keep_textures(const std::vector<std::string>& hashes, const Scene& scene,
                            const TextureFiles& files) {
  {
    // Counted before the files are written: a finishing job that shares one cannot delete it
    // in between (it deletes under the same lock, and only at zero).
    std::lock_guard lock(mu_);
    for (const std::string& h : hashes) ++texture_refs_[h];
  }
  for (size_t i = 0; i < hashes.size(); ++i)
    blobs_.put(BlobKind::texture, hashes[i], files.at(scene.textures[i].path));
}

void Service::release_textures(const std::vector<std::string>& hashes) {
  std::lock_guard lock(mu_);
  for (const std::string& h : hashes) {
    auto it = texture_refs_.find(h);
    if (it == texture_refs_.end() || --it->second > 0) continue;
    texture_refs_.erase(it);
    blobs_.remove(BlobKind::texture, h);
  }
}

std::shared_ptr<const Scene> Service::reload_scene(const std::string& text,
                                                   const std::vector<std::string>& hashes) {
  const LoadGate::Pass pass = enter_load(text.size() + (hashes.empty() ? 0 : LoadGate::kSmall + 1));
  LoadedScene loaded = load_scene(text, LoadDetail::scene);
  if (!loaded.scene || loaded.scene->textures.size() != hashes.size()) return nullptr;
  TextureFiles files;
  for (size_t i = 0; i < hashes.size(); ++i) {
    auto bytes = blobs_.get(BlobKind::texture, hashes[i]);
    if (!bytes || sha256_hex(*bytes) != hashes[i]) return nullptr;  // lost or damaged
    files[loaded.scene->textures[i].path] = std::move(*bytes);
  }
  Diagnostics diags;
  if (!resolve_textures(*loaded.scene, UploadedTextures(files, settings_.max_pixels), diags)) return nullptr;
  return std::make_shared<const Scene>(std::move(*loaded.scene));
}

void Service::sweep_textures() {
  std::lock_guard lock(mu_);
  for (const std::string& name : blobs_.names(BlobKind::texture))
    if (!texture_refs_.count(name)) blobs_.remove(BlobKind::texture, name);
}

}  // namespace rayfarm::server
