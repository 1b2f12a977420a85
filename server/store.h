// The results directory: accepted jobs and finished images on disk, written atomically
// (temp file, fsync, rename), so a restart finds every accepted job and every result.
//   DIR/jobs/ID.json    the job record      DIR/jobs/ID.scene  the scene as submitted
//   DIR/images/NAME.png the result (NAME: the content key, or the job id)
//   DIR/textures/HASH   an uploaded texture file, named by the SHA-256 of its bytes (never by
//                       the path the scene gives it), while an unfinished job needs it
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "job.h"

namespace rayfarm::server {

class ResultStore {
 public:
  // An empty path disables persistence (everything stays in memory).
  explicit ResultStore(std::filesystem::path dir);

  bool enabled() const { return !dir_.empty(); }

  // Throws std::runtime_error when the disk refuses (full, read-only).
  void save_scene(const std::string& id, const std::string& text);
  void save_record(const Job& job);
  void save_image(const std::string& name, const std::string& png);
  std::optional<std::string> load_image(const std::string& name) const;
  bool has_image(const std::string& name) const;
  void remove_job(const std::string& id);
  void remove_image(const std::string& name);
  void save_texture(const std::string& hash, std::string_view bytes);
  std::optional<std::string> load_texture(const std::string& hash) const;
  void remove_texture(const std::string& hash);
  std::vector<std::string> texture_names() const;

  struct Stored {
    nlohmann::json record;
    std::string scene_text;
  };
  std::vector<Stored> load_jobs() const;

  // Images oldest first, with their sizes (for expiry by total size).
  std::vector<std::pair<std::string, std::uintmax_t>> images_oldest_first() const;

 private:
  void write_atomically(const std::filesystem::path& path, std::string_view bytes);

  std::filesystem::path dir_;
};

nlohmann::json job_record(const Job& job);

}  // namespace rayfarm::server
