// Where the bytes of jobs live: scene texts (by job id), uploaded texture files (by the SHA-256
// of their bytes) and result PNGs (by image name: the content key, or the job id). Names are
// [A-Za-z0-9]{1,128}; anything else is neither stored nor found.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace rayfarm::server {

enum class BlobKind { scene, texture, image };

class BlobStore {
 public:
  virtual ~BlobStore() = default;

  // False in memory mode: nothing is kept (the job table and the image cache are all there is).
  virtual bool durable() const = 0;
  // Durable when it returns; throws std::runtime_error when the storage refuses (disk full).
  // Writing a name that exists replaces it (a texture's name is its content: the same bytes).
  virtual void put(BlobKind kind, const std::string& name, std::string_view bytes) = 0;
  virtual std::optional<std::string> get(BlobKind kind, const std::string& name) const = 0;
  virtual bool has(BlobKind kind, const std::string& name) const = 0;
  virtual void remove(BlobKind kind, const std::string& name) = 0;
  virtual std::vector<std::string> names(BlobKind kind) const = 0;
  // Blobs of a kind, the least recently written first, with their sizes (the size budget).
  virtual std::vector<std::pair<std::string, std::uintmax_t>> oldest_first(BlobKind kind) const = 0;
};

// A blob name as every store accepts it.
bool valid_blob_name(std::string_view name);

}  // namespace rayfarm::server
