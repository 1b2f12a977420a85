// The sample scenes offered by GET /samples and /render?sample=NAME: each .txt or .json file
// of the samples directory that loads (with its textures), described by its first comment.
#include <cstdio>
#include <algorithm>
#include <fstream>
#include <sstream>

#include "rayfarm/load.h"
#include "service.h"

namespace rayfarm::server {
namespace fs = std::filesystem;
namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A sample's textures: files of the samples directory (beneath it, never outside), kept as the
// uploads of a request for it.
class BundleFiles final : public ResourceResolver {
 public:
  explicit BundleFiles(fs::path dir) : dir_(std::move(dir)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    const fs::path p(path);
    std::error_code ec;
    if (p.is_absolute() || std::find(p.begin(), p.end(), "..") != p.end() ||
        !fs::is_regular_file(dir_ / p, ec)) {
      error = "not a file of the samples directory";
      return std::nullopt;
    }
    return files[path] = read_text(dir_ / p);
  }
  mutable TextureFiles files;

 private:
  fs::path dir_;
};

}  // namespace

const Sample* Service::sample(const std::string& name) const {
  for (const Sample& s : samples_)
    if (s.name == name) return &s;
  return nullptr;
}

void Service::load_samples() {
  fs::path dir = settings_.samples_dir;
  std::error_code ec;
  if (dir.empty()) return;
  if (!fs::is_directory(dir, ec)) {
    std::fprintf(stderr, "rayfarmd: warning: --samples-dir %s is not a directory: no samples\n",
                 dir.string().c_str());
    return;
  }
  for (auto& e : fs::directory_iterator(dir, ec)) {
    auto ext = e.path().extension();
    if (ext != ".txt" && ext != ".json") continue;
    std::string name = e.path().stem().string();
    if (ext == ".json") name += ".json";
    std::string text = read_text(e.path());
    // The description is the file's opening comment, whole: its first line alone stops
    // mid-sentence in most scenes.
    std::string description;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
      size_t start = line.find_first_not_of(" \t\r");
      if (start == std::string::npos || line[start] != '#') break;
      std::string words = line.substr(start + 1);
      size_t first = words.find_first_not_of(" \t");
      size_t last = words.find_last_not_of(" \t\r");
      if (first == std::string::npos) break;
      if (!description.empty()) description += ' ';
      description += words.substr(first, last - first + 1);
    }
    const BundleFiles textures(dir);
    if (!load_scene(text, LoadDetail::scene, &textures).scene) continue;  // only what renders
    samples_.push_back({name, description, e.path(), std::move(textures.files)});
  }
  std::sort(samples_.begin(), samples_.end(), [](auto& a, auto& b) { return a.name < b.name; });
  // JSON has no comments: a twin is described by its model file.
  for (Sample& s : samples_) {
    if (!s.description.empty() || !s.name.ends_with(".json")) continue;
    std::string stem = s.name.substr(0, s.name.size() - 5);
    if (const Sample* twin = sample(stem); twin && !twin->description.empty())
      s.description = "The JSON form of '" + stem + "'. " + twin->description;
  }
}

}  // namespace rayfarm::server
