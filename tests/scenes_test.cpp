// Every bundled scene parses, passes its own check and renders; turning the scene-specific
// pipeline off never changes a byte.
#include <filesystem>
#include <fstream>
#include <sstream>

#include "rayfarm/lint.h"
#include "test_util.h"

namespace rayfarm {
namespace {

std::vector<std::filesystem::path> scene_files() {
  std::vector<std::filesystem::path> out;
  for (auto& entry : std::filesystem::recursive_directory_iterator(RAYFARM_SOURCE_DIR "/scenes")) {
    auto ext = entry.path().extension();
    // scenes/assignments/ also holds assignment files (JSON, not scenes).
    const bool assignment = ext == ".json" && entry.path().string().find("/assignments/") != std::string::npos;
    if ((ext == ".txt" || ext == ".json") && !assignment) out.push_back(entry.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(Scenes, EverySceneLoadsAndRendersTheSameWithAndWithoutSpecialization) {
  for (const auto& path : scene_files()) {
    SCOPED_TRACE(path.string());
    std::string text;
    LoadedScene loaded = test::load_file(path.string(), &text);
    ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.diags, path.string(), text);
    RenderOptions o;
    Diagnostics diags;
    apply_options(o, loaded.scene->render, diags);
    ASSERT_FALSE(diags.has_errors());
    // A reduced size keeps the suite quick; the window is the same.
    o.width = 96;
    o.height = 72;
    Image fast = test::render(*loaded.scene, o, 2);
    ASSERT_EQ(fast.width, 96);
    o.specialize = false;
    EXPECT_EQ(test::render(*loaded.scene, o, 2), fast);
    bool any_lit = false;
    for (auto b : fast.rgb) any_lit = any_lit || b > 0;
    EXPECT_TRUE(any_lit) << "an all-black image";
  }
}

TEST(Scenes, BundledScenesHaveNoLintWarnings) {
  for (const auto& path : scene_files()) {
    if (path.string().find("/extreme/") != std::string::npos) continue;  // stiff on purpose
    std::string text;
    LoadedScene loaded = test::load_file(path.string(), &text);
    ASSERT_TRUE(loaded.scene);
    RenderOptions o;
    Diagnostics diags;
    lint_scene(*loaded.scene, o, diags);
    EXPECT_TRUE(diags.items().empty())
        << path << ":\n" << format_diagnostics(diags, path.string(), text);
  }
}

}  // namespace
}  // namespace rayfarm
