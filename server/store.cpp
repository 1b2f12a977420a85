// Results directory persistence.
#include "store.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

namespace rayfarm::server {
namespace fs = std::filesystem;

namespace {

bool safe_name(const std::string& name) {
  if (name.empty() || name.size() > 128) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) return false;
  return true;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void fsync_path(const fs::path& p, int flags) {
  int fd = ::open(p.c_str(), flags);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

ResultStore::ResultStore(fs::path dir) : dir_(std::move(dir)) {
  if (dir_.empty()) return;
  fs::create_directories(dir_ / "jobs");
  fs::create_directories(dir_ / "images");
  fs::create_directories(dir_ / "textures");
  // Temp files of a write that a crash interrupted.
  for (auto& sub : {dir_ / "jobs", dir_ / "images", dir_ / "textures"})
    for (auto& e : fs::directory_iterator(sub))
      if (e.path().filename().string().find(".tmp") != std::string::npos) fs::remove(e.path());
}

void ResultStore::write_atomically(const fs::path& path, std::string_view bytes) {
  fs::path tmp = path;
  tmp += ".tmp" + std::to_string(std::random_device{}());
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + tmp.string() + ": " + std::strerror(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = errno;
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(err));
    }
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(err));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    int err = errno;
    ::unlink(tmp.c_str());
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(err));
  }
  fsync_path(path.parent_path(), O_RDONLY | O_DIRECTORY);
}

void ResultStore::save_scene(const std::string& id, const std::string& text) {
  if (enabled() && safe_name(id)) write_atomically(dir_ / "jobs" / (id + ".scene"), text);
}

void ResultStore::save_record(const Job& job) {
  if (enabled() && safe_name(job.id))
    write_atomically(dir_ / "jobs" / (job.id + ".json"), json_text(job_record(job)));
}

void ResultStore::save_image(const std::string& name, const std::string& png) {
  if (enabled() && safe_name(name)) write_atomically(dir_ / "images" / (name + ".png"), png);
}

std::optional<std::string> ResultStore::load_image(const std::string& name) const {
  if (!enabled() || !safe_name(name)) return std::nullopt;
  fs::path p = dir_ / "images" / (name + ".png");
  std::error_code ec;
  if (!fs::exists(p, ec)) return std::nullopt;
  return read_file(p);
}

bool ResultStore::has_image(const std::string& name) const {
  std::error_code ec;
  return enabled() && safe_name(name) && fs::exists(dir_ / "images" / (name + ".png"), ec);
}

void ResultStore::remove_job(const std::string& id) {
  if (!enabled() || !safe_name(id)) return;
  std::error_code ec;
  fs::remove(dir_ / "jobs" / (id + ".json"), ec);
  fs::remove(dir_ / "jobs" / (id + ".scene"), ec);
}

void ResultStore::remove_image(const std::string& name) {
  if (!enabled() || !safe_name(name)) return;
  std::error_code ec;
  fs::remove(dir_ / "images" / (name + ".png"), ec);
}

void ResultStore::save_texture(const std::string& hash, std::string_view bytes) {
  if (!enabled() || !safe_name(hash)) return;
  std::error_code ec;
  // Content-addressed: a file already there holds these very bytes.
  if (!fs::exists(dir_ / "textures" / hash, ec)) write_atomically(dir_ / "textures" / hash, bytes);
}

std::optional<std::string> ResultStore::load_texture(const std::string& hash) const {
  if (!enabled() || !safe_name(hash)) return std::nullopt;
  std::error_code ec;
  if (!fs::exists(dir_ / "textures" / hash, ec)) return std::nullopt;
  return read_file(dir_ / "textures" / hash);
}

void ResultStore::remove_texture(const std::string& hash) {
  if (!enabled() || !safe_name(hash)) return;
  std::error_code ec;
  fs::remove(dir_ / "textures" / hash, ec);
}

std::vector<std::string> ResultStore::texture_names() const {
  std::vector<std::string> out;
  if (enabled())
    for (auto& e : fs::directory_iterator(dir_ / "textures"))
      if (safe_name(e.path().filename().string())) out.push_back(e.path().filename().string());
  return out;
}

std::vector<ResultStore::Stored> ResultStore::load_jobs() const {
  std::vector<Stored> out;
  if (!enabled()) return out;
  for (auto& e : fs::directory_iterator(dir_ / "jobs")) {
    if (e.path().extension() != ".json") continue;
    auto record = nlohmann::json::parse(read_file(e.path()), nullptr, false);
    if (record.is_discarded() || !record.is_object()) continue;  // torn or foreign: skip
    fs::path scene = e.path();
    scene.replace_extension(".scene");
    std::error_code ec;
    out.push_back({record, fs::exists(scene, ec) ? read_file(scene) : std::string()});
  }
  return out;
}

std::vector<std::pair<std::string, std::uintmax_t>> ResultStore::images_oldest_first() const {
  std::vector<std::tuple<fs::file_time_type, std::string, std::uintmax_t>> items;
  if (enabled())
    for (auto& e : fs::directory_iterator(dir_ / "images"))
      if (e.path().extension() == ".png")
        items.emplace_back(e.last_write_time(), e.path().stem().string(), e.file_size());
  std::sort(items.begin(), items.end());
  std::vector<std::pair<std::string, std::uintmax_t>> out;
  for (auto& [t, name, size] : items) out.emplace_back(name, size);
  return out;
}

nlohmann::json job_record(const Job& job) {
  std::lock_guard lock(job.mu);
  nlohmann::json options = nlohmann::json::object();
  for (auto& [k, v] : option_pairs(job.options)) options[k] = v;
  nlohmann::json record = {{"id", job.id},
                           {"client", job.client},
                           {"state", to_string(job.state)},
                           {"options", options},
                           {"cache_key", job.cache_key},
                           {"image_name", job.image_name},
                           {"created_ms", job.created_ms},
                           {"started_ms", job.started_ms},
                           {"finished_ms", job.finished_ms},
                           {"attempts", job.attempts},
                           {"error", job.error},
                           {"error_code", job.error_code},
                           {"width", job.width},
                           {"height", job.height},
                           {"stats",
                            {{"primary", job.stats.primary_rays},
                             {"shadow", job.stats.shadow_rays},
                             {"reflection", job.stats.reflection_rays},
                             {"render_ms", job.stats.render_ms},
                             {"spp_done", job.stats.spp_done},
                             {"error_estimate", job.stats.error_estimate},
                             {"parts", job.stats.parts}}}};
  // Only a job that may still render needs its textures; the files go when it ends.
  if (!is_final(job.state) && !job.textures.empty()) record["textures"] = job.textures;
  return record;
}

}  // namespace rayfarm::server
