// The course conformance suite: every scene of tests/conformance/manifest.txt rendered in
// the cpsc102 profile and compared with the course's reference image channel by channel.
// The scenes' textures are read beside them, as the course's program read them.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "rayfarm/image_io.h"
#include "rayfarm/load.h"
#include "rayfarm/render.h"

namespace rayfarm {
namespace {

namespace fs = std::filesystem;

const fs::path kRoot = fs::path(RAYFARM_SOURCE_DIR) / "tests/conformance";

std::optional<std::string> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class BesideTheScene final : public ResourceResolver {
 public:
  explicit BesideTheScene(fs::path dir) : dir_(std::move(dir)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    auto bytes = read_file(dir_ / path);
    if (!bytes) error = "no such file";
    return bytes;
  }

 private:
  fs::path dir_;
};

struct Case {
  std::string scene;
  std::string options;
  double exact = -1;  // < 0: no reference image
};

std::vector<Case> manifest() {
  std::vector<Case> out;
  std::ifstream in(kRoot / "manifest.txt");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    Case c;
    std::string exact;
    fields >> c.scene >> c.options >> exact;
    c.exact = exact == "-" ? -1 : std::stod(exact);
    out.push_back(c);
  }
  return out;
}

std::string name_of(const testing::TestParamInfo<Case>& info) {
  std::string n = fs::path(info.param.scene).stem().string();
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
}

class Conformance : public testing::TestWithParam<Case> {};

TEST_P(Conformance, RendersTheCoursesReferenceImage) {
  const Case& c = GetParam();
  const fs::path path = kRoot / "course" / c.scene;
  const auto text = read_file(path);
  ASSERT_TRUE(text) << path;
  const BesideTheScene textures(path.parent_path());
  LoadedScene loaded = load_scene(*text, LoadDetail::full, &textures);
  ASSERT_TRUE(loaded.scene) << format_diagnostics(loaded.diags, path.string(), *text);
  RenderOptions o;
  Diagnostics diags;
  apply_options(o, loaded.scene->render, diags);
  ASSERT_FALSE(apply_option(o, "profile", "cpsc102"));
  if (c.options != "-") {
    const size_t eq = c.options.find('=');
    ASSERT_FALSE(apply_option(o, c.options.substr(0, eq), c.options.substr(eq + 1)));
  }
  std::string error;
  const Image image = render_image(*loaded.scene, o, 2, nullptr, {}, nullptr, &error);
  ASSERT_EQ(error, "");
  if (c.exact < 0) return;

  fs::path reference = path;
  reference.replace_extension(".png");
  const auto bytes = read_file(reference);
  ASSERT_TRUE(bytes) << reference;
  const auto expected = decode_image(*bytes, &error);
  ASSERT_TRUE(expected) << error;
  ASSERT_EQ(image.width, expected->width);
  ASSERT_EQ(image.height, expected->height);
  size_t same = 0;
  for (size_t i = 0; i < image.rgb.size(); ++i) same += image.rgb[i] == expected->rgb[i];
  const double fraction = static_cast<double>(same) / static_cast<double>(image.rgb.size());
  EXPECT_GE(fraction, c.exact) << c.scene << ": " << image.rgb.size() - same << " of "
                               << image.rgb.size() << " channels differ";
}

INSTANTIATE_TEST_SUITE_P(Course, Conformance, testing::ValuesIn(manifest()), name_of);

}  // namespace
}  // namespace rayfarm
