// Golden images: the SHA-256 of every bundled scene's pixels in both precisions, at one and
// four samples per pixel, pinned in tests/golden/hashes.txt. Any change to a byte of any of
// them fails here; a change made on purpose bumps kRenderVersion (rayfarm/render.h) and
// rewrites the file with RAYFARM_UPDATE_GOLDEN=1.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "rayfarm/sha256.h"
#include "test_util.h"

namespace rayfarm {
namespace {

namespace fs = std::filesystem;

const fs::path kHashes = fs::path(RAYFARM_SOURCE_DIR) / "tests/golden/hashes.txt";

std::vector<fs::path> bundled_scenes() {
  std::vector<fs::path> out;
  for (auto& entry : fs::recursive_directory_iterator(fs::path(RAYFARM_SOURCE_DIR) / "scenes")) {
    auto ext = entry.path().extension();
    // scenes/assignments/ also holds assignment files (JSON, not scenes).
    const bool assignment = ext == ".json" && entry.path().string().find("/assignments/") != std::string::npos;
    if ((ext == ".txt" || ext == ".json") && !assignment) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// "scene|variant" -> hash, for every case this build renders.
std::map<std::string, std::string> current_hashes() {
  std::map<std::string, std::string> out;
  const std::string root = RAYFARM_SOURCE_DIR "/";
  for (const fs::path& path : bundled_scenes()) {
    LoadedScene loaded = test::load_file(path.string());
    EXPECT_TRUE(loaded.scene) << path;
    if (!loaded.scene) continue;
    const std::string name = path.string().substr(root.size());
    // The lecture profile in both precisions (its cases keep their names: "double",
    // "float"), and the cpsc102 profile.
    for (const char* variant : {"double", "float", "cpsc102"})
      for (int spp : {1, 4}) {
        RenderOptions o;
        Diagnostics diags;
        apply_options(o, loaded.scene->render, diags);
        EXPECT_FALSE(diags.has_errors()) << path;
        o.width = 96;
        o.height = 72;
        o.spp = spp;
        if (std::string(variant) == "cpsc102")
          EXPECT_FALSE(apply_option(o, "profile", "cpsc102"));
        else
          EXPECT_FALSE(apply_option(o, "precision", variant));
        const Image image = test::render(*loaded.scene, o, 2);
        const std::string bytes(image.rgb.begin(), image.rgb.end());
        out[name + "|" + variant + ",spp=" + std::to_string(spp)] = sha256_hex(bytes);
      }
  }
  return out;
}

TEST(Golden, BundledScenesRenderTheirPinnedBytes) {
  const std::map<std::string, std::string> now = current_hashes();
  if (std::getenv("RAYFARM_UPDATE_GOLDEN")) {
    std::ofstream out(kHashes, std::ios::binary | std::ios::trunc);
    out << "# render version " << kRenderVersion
        << ": SHA-256 of the RGB bytes at 96x72 (tests/golden_test.cpp)\n";
    for (const auto& [key, hash] : now) out << key << ' ' << hash << '\n';
    GTEST_SKIP() << "rewrote " << kHashes;
  }
  std::ifstream in(kHashes);
  ASSERT_TRUE(in) << "missing " << kHashes;
  std::map<std::string, std::string> pinned;
  std::string line;
  int version = -1;
  while (std::getline(in, line)) {
    if (line.rfind("# render version ", 0) == 0) version = std::atoi(line.c_str() + 17);
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.rfind(' ');
    pinned[line.substr(0, space)] = line.substr(space + 1);
  }
  EXPECT_EQ(version, kRenderVersion)
      << "the pinned hashes are of another render version: regenerate them";
  for (const auto& [key, hash] : pinned) {
    auto it = now.find(key);
    if (it == now.end()) {
      ADD_FAILURE() << key << " is pinned but no longer rendered";
      continue;
    }
    EXPECT_EQ(it->second, hash)
        << key << " changed: if on purpose, bump kRenderVersion in rayfarm/render.h and run "
                  "RAYFARM_UPDATE_GOLDEN=1 ./build/tests/rayfarm_tests --gtest_filter=Golden.*";
  }
  for (const auto& [key, hash] : now)
    EXPECT_TRUE(pinned.count(key)) << key << " is rendered but not pinned: regenerate the file";
}

}  // namespace
}  // namespace rayfarm
