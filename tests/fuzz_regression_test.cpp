// Every input a fuzzer (or a user) ever found to break something, replayed on every run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "fuzz/targets.h"

namespace rayfarm {
namespace {

void replay(const std::string& target, int (*run)(const std::uint8_t*, std::size_t)) {
  const std::filesystem::path dir = RAYFARM_SOURCE_DIR "/tests/fuzz/regressions/" + target;
  int replayed = 0;
  for (auto& entry : std::filesystem::directory_iterator(dir)) {
    std::ifstream in(entry.path(), std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    std::string bytes = s.str();
    SCOPED_TRACE(entry.path().string());
    EXPECT_EQ(run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0);
    ++replayed;
  }
  EXPECT_GT(replayed, 0) << "no regression inputs in " << dir;
}

TEST(FuzzRegressions, ModelParserInputsReplayCleanly) {
  replay("model_parser", fuzz::model_parser);
}

TEST(FuzzRegressions, JsonSceneInputsReplayCleanly) { replay("json_scene", fuzz::json_scene); }

TEST(FuzzRegressions, ImageDecodeInputsReplayCleanly) {
  replay("image_decode", fuzz::image_decode);
}

TEST(FuzzRegressions, HttpRequestInputsReplayCleanly) {
  replay("http_request", fuzz::http_request);
}

}  // namespace
}  // namespace rayfarm
