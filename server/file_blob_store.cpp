// The results directory's files.
#include "file_blob_store.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace rayfarm::server {
namespace fs = std::filesystem;

bool valid_blob_name(std::string_view name) {
  if (name.empty() || name.size() > 128) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) return false;
  return true;
}

namespace {

void fsync_path(const fs::path& p, int flags) {
  int fd = ::open(p.c_str(), flags);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

const char* folder_of(BlobKind kind) {
  switch (kind) {
    case BlobKind::scene: return "jobs";
    case BlobKind::texture: return "textures";
    case BlobKind::image: return "images";
  }
  return "images";
}

const char* extension_of(BlobKind kind) {
  switch (kind) {
    case BlobKind::scene: return ".scene";
    case BlobKind::texture: return "";
    case BlobKind::image: return ".png";
  }
  return "";
}

}  // namespace

std::string read_whole_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_atomically(const fs::path& path, std::string_view bytes) {
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

FileBlobStore::FileBlobStore(fs::path dir) : dir_(std::move(dir)) {
  if (dir_.empty()) return;
  for (BlobKind kind : {BlobKind::scene, BlobKind::texture, BlobKind::image}) {
    fs::create_directories(dir_ / folder_of(kind));
    // Temp files of a write that a crash interrupted.
    for (auto& e : fs::directory_iterator(dir_ / folder_of(kind)))
      if (e.path().filename().string().find(".tmp") != std::string::npos) fs::remove(e.path());
  }
}

fs::path FileBlobStore::path_of(BlobKind kind, const std::string& name) const {
  return dir_ / folder_of(kind) / (name + extension_of(kind));
}

void FileBlobStore::put(BlobKind kind, const std::string& name, std::string_view bytes) {
  if (!durable() || !valid_blob_name(name)) return;
  std::error_code ec;
  // Content-addressed: a texture file already there holds these very bytes.
  if (kind == BlobKind::texture && fs::exists(path_of(kind, name), ec)) return;
  write_atomically(path_of(kind, name), bytes);
}

std::optional<std::string> FileBlobStore::get(BlobKind kind, const std::string& name) const {
  if (!has(kind, name)) return std::nullopt;
  return read_whole_file(path_of(kind, name));
}

bool FileBlobStore::has(BlobKind kind, const std::string& name) const {
  std::error_code ec;
  return durable() && valid_blob_name(name) && fs::exists(path_of(kind, name), ec);
}

void FileBlobStore::remove(BlobKind kind, const std::string& name) {
  if (!durable() || !valid_blob_name(name)) return;
  std::error_code ec;
  fs::remove(path_of(kind, name), ec);
}

std::vector<std::string> FileBlobStore::names(BlobKind kind) const {
  std::vector<std::string> out;
  for (auto& [name, size] : oldest_first(kind)) out.push_back(name);
  return out;
}

std::vector<std::pair<std::string, std::uintmax_t>> FileBlobStore::oldest_first(
    BlobKind kind) const {
  std::vector<std::tuple<fs::file_time_type, std::string, std::uintmax_t>> items;
  if (durable()) {
    const std::string ext = extension_of(kind);
    for (auto& e : fs::directory_iterator(dir_ / folder_of(kind))) {
      const std::string file = e.path().filename().string();
      if (file.size() <= ext.size() || file.compare(file.size() - ext.size(), ext.size(), ext))
        continue;
      const std::string name = file.substr(0, file.size() - ext.size());
      std::error_code ec;
      auto time = e.last_write_time(ec);
      auto size = e.file_size(ec);
      if (!ec && valid_blob_name(name)) items.emplace_back(time, name, size);
    }
  }
  std::sort(items.begin(), items.end());
  std::vector<std::pair<std::string, std::uintmax_t>> out;
  for (auto& [t, name, size] : items) out.emplace_back(name, size);
  return out;
}

}  // namespace rayfarm::server
