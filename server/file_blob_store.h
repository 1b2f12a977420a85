// BlobStore on the results directory, each file written atomically (temp file, fsync, rename):
//   DIR/jobs/ID.scene    the scene as submitted
//   DIR/textures/HASH    an uploaded texture file, named by the SHA-256 of its bytes
//   DIR/images/NAME.png  a result
// Without a directory it keeps nothing (memory mode).
#pragma once

#include <filesystem>

#include "blob_store.h"

namespace rayfarm::server {

class FileBlobStore final : public BlobStore {
 public:
  // Creates the folders and removes the temp files of writes a crash interrupted.
  explicit FileBlobStore(std::filesystem::path dir);

  bool durable() const override { return !dir_.empty(); }
  void put(BlobKind kind, const std::string& name, std::string_view bytes) override;
  std::optional<std::string> get(BlobKind kind, const std::string& name) const override;
  bool has(BlobKind kind, const std::string& name) const override;
  void remove(BlobKind kind, const std::string& name) override;
  std::vector<std::string> names(BlobKind kind) const override;
  std::vector<std::pair<std::string, std::uintmax_t>> oldest_first(BlobKind kind) const override;

 private:
  std::filesystem::path path_of(BlobKind kind, const std::string& name) const;

  std::filesystem::path dir_;
};

// Writes `bytes` to `path` so a crash leaves the old file or the new one, never a torn one.
// Throws std::runtime_error with the reason.
void write_atomically(const std::filesystem::path& path, std::string_view bytes);
std::string read_whole_file(const std::filesystem::path& path);

}  // namespace rayfarm::server
