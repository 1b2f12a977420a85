// The command line as its users run it: `rayfarm grade` and `compare` as a grading platform
// does (the worked example in scenes/assignments/lab1, the lock file, a student's program
// under --run, exit codes), and `render`'s refusals of outputs and server URLs it cannot use.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdio>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

const std::string kRayfarm = RAYFARM_BINARY_DIR "/client/rayfarm";
const std::string kLab = RAYFARM_SOURCE_DIR "/scenes/assignments/lab1";

struct Outcome {
  int code = -1;
  std::string out;
};

// Runs a shell command line; its standard output and exit code.
Outcome run(const std::string& command) {
  Outcome r;
  const bool merged = command.find("2>&1") != std::string::npos;
  FILE* p = popen((merged ? command : command + " 2>/dev/null").c_str(), "r");
  if (!p) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof buf, p)) > 0) r.out.append(buf, n);
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string q(const std::string& s) { return "'" + s + "'"; }

// The client is built with the tests, except in sanitizer builds (CI runs these there without).
#define REQUIRE_CLIENT()                                                          \
  if (!fs::exists(kRayfarm)) GTEST_SKIP() << "no " << kRayfarm << " in this build"

class GradeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    REQUIRE_CLIENT();
    dir_ = fs::temp_directory_path() /
           ("rayfarm-grade-cli-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cache_ = " --cache " + q((dir_ / "cache").string());
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  Json grade(const std::string& args, int expect_code = 0) {
    Outcome r = run(kRayfarm + " grade " + args + cache_ + " --format json");
    EXPECT_EQ(r.code, expect_code) << args << "\n" << r.out;
    Json j = Json::parse(r.out, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << r.out;
    return j;
  }

  fs::path dir_;
  std::string cache_;
};

TEST_F(GradeCli, TheWorkedExampleGradesEachStudent) {
  const std::string assignment = q(kLab + "/lab1.json");
  Json ada = grade(assignment + " --images " + q(kLab + "/students/ada"));
  EXPECT_EQ(ada["score"], 10);
  Json ben = grade(assignment + " --images " + q(kLab + "/students/ben"));
  EXPECT_EQ(ben["score"], 2);  // the glint test forgives one level
  for (const Json& t : ben["tests"]) EXPECT_EQ(t["hints"][0]["code"], "rounding");
  Json cam = grade(assignment + " --images " + q(kLab + "/students/cam"));
  EXPECT_EQ(cam["tests"][0]["hints"][0]["code"], "upside_down");
  EXPECT_EQ(cam["tests"][2]["hints"][0]["code"], "red_blue_swapped");
  EXPECT_EQ(cam["tests"][3]["hints"][0]["code"], "missing_image");
  Json dee = grade(assignment + " --images " + q(kLab + "/students/dee"));
  for (const Json& t : dee["tests"]) EXPECT_EQ(t["hints"][0]["code"], "lecture_profile");
  Json eli = grade(assignment + " --images " + q(kLab + "/students/eli"));
  EXPECT_EQ(eli["tests"][1]["hints"][0]["code"], "shadows");
  EXPECT_EQ(eli["tests"][2]["hints"][0]["code"], "path_cap");
  EXPECT_EQ(eli["tests"][2]["score"], 1.5);  // the step rule: under 2% of pixels differ
  Json fay = grade(assignment + " --images " + q(kLab + "/students/fay"));
  EXPECT_EQ(fay["tests"][2]["hints"][0]["code"], "no_reflections");
  EXPECT_EQ(fay["tests"][3]["hints"][0]["code"], "highlights");
}

TEST_F(GradeCli, PlatformFilesAreWrittenWhereAsked) {
  const fs::path out = dir_ / "results/results.json";  // PrairieLearn: the folder is not there
  Outcome r = run(kRayfarm + " grade " + q(kLab + "/lab1.json") + " --images " +
              q(kLab + "/students/ben") + cache_ + " --format prairielearn -o " + q(out.string()));
  ASSERT_EQ(r.code, 0);
  std::ifstream in(out);
  Json j = Json::parse(in);
  EXPECT_EQ(j["gradable"], true);
  EXPECT_NEAR(j["score"].get<double>(), 0.2, 1e-9);
  // --fail-under turns a low score into exit 1 for pass/fail use.
  EXPECT_EQ(run(kRayfarm + " grade " + q(kLab + "/lab1.json") + " --images " +
                q(kLab + "/students/ben") + cache_ + " --fail-under 50 -o /dev/null").code, 1);
}

TEST_F(GradeCli, ALockFileRefusesChangedReferences) {
  fs::copy(kLab + "/scenes", dir_ / "scenes");
  fs::copy(kLab + "/lab1.json", dir_ / "lab1.json");
  const std::string assignment = q((dir_ / "lab1.json").string());
  ASSERT_EQ(run(kRayfarm + " grade " + assignment + " --freeze" + cache_).code, 0);
  ASSERT_TRUE(fs::exists(dir_ / "lab1.lock.json"));
  Json ok = grade(assignment + " --images " + q(kLab + "/students/ada"));
  EXPECT_EQ(ok["score"], 10);
  // The instructor edits a scene after freezing: grading stops, with a result that says so.
  {
    std::ofstream edit(dir_ / "scenes/glint.txt", std::ios::app);
    edit << "\nlight extra\n{\n  location 1 1 1\n  emissivity 1 1 1\n}\n";
  }
  Json refused = grade(assignment + " --images " + q(kLab + "/students/ada"), 2);
  EXPECT_EQ(refused["score"], 0);
  EXPECT_NE(refused["error"].get<std::string>().find("test 'A glint'"), std::string::npos);
}

TEST_F(GradeCli, AStudentsProgramUnderRun) {
  const std::string assignment = q(kLab + "/lab1.json");
  const std::string ada = kLab + "/students/ada";
  // Writes {out}; complains on standard error and exits 3 for the glint.
  const std::string program =
      "f=$(basename {scene} .txt); cp " + ada + "/$f.png {out}; "
      "if [ $f = glint ]; then echo \"glint: oops\" >&2; exit 3; fi";
  Json j = grade(assignment + " --run " + q(program));
  EXPECT_EQ(j["score"], 10);
  EXPECT_EQ(j["tests"][3]["note"].get<std::string>().substr(0, 33), "your program exited with status 3");
  EXPECT_NE(j["tests"][3]["log_tail"].get<std::string>().find("glint: oops"), std::string::npos);
  // The image on standard output.
  Json stdout_image = grade(assignment + " --run " + q("cat " + ada + "/$(basename {scene} .txt).png"));
  EXPECT_EQ(stdout_image["score"], 10);
  // A program that ends but leaves a child holding its output is done when it ends.
  const auto quick = std::chrono::steady_clock::now();
  Json detached = grade(assignment + " --timeout 20 --run " +
                        q("sleep 30 & cp " + ada + "/$(basename {scene} .txt).png {out}"));
  EXPECT_LT(std::chrono::steady_clock::now() - quick, std::chrono::seconds(10));
  EXPECT_EQ(detached["score"], 10);
  // A program that never ends is stopped at the time limit, children and all.
  const auto start = std::chrono::steady_clock::now();
  Json slow = grade(assignment + " --timeout 0.5 --run " + q("sleep 30 & sleep 30"));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20));
  EXPECT_EQ(slow["score"], 0);
  EXPECT_EQ(slow["tests"][0]["message"], "your program ran past the time limit of 0.5 s and was stopped");
}

TEST_F(GradeCli, AssignmentErrorsArePlaced) {
  std::ofstream(dir_ / "bad.json") << R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "pionts": 2}]})";
  Outcome r = run(kRayfarm + " grade " + q((dir_ / "bad.json").string()) + " --images . 2>&1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("at /tests/0/pionts: unknown key 'pionts'; did you mean 'points'?"),
            std::string::npos)
      << r.out;
}

TEST(CompareCli, ExitsAsDiffDoes) {
  REQUIRE_CLIENT();
  const std::string ada = q(kLab + "/students/ada/mirror.png");
  const std::string ben = q(kLab + "/students/ben/mirror.png");
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ada).code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben).code, 1);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben + " --threshold 1").code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben + " --max-bad-fraction 0.9").code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + q(kLab + "/lab1.json")).code, 2);
  Json j = Json::parse(run(kRayfarm + " compare --json " + ada + " " + ada).out);
  EXPECT_TRUE(j["psnr"].is_null());
  EXPECT_EQ(j["identical"], true);
  EXPECT_EQ(j["match"], true);
}

TEST(ConvertCli, RenderFlagsGoIntoJsonAndAreRefusedForModelFiles) {
  REQUIRE_CLIENT();
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt");
  Outcome json = run(kRayfarm + " convert " + scene + " --to json --spp 8 --profile cpsc102");
  ASSERT_EQ(json.code, 0);
  Json j = Json::parse(json.out);
  EXPECT_EQ(j["render"]["spp"], 8);
  EXPECT_EQ(j["render"]["profile"], "cpsc102");
  EXPECT_EQ(run(kRayfarm + " convert " + scene + " --to model --spp 8").code, 2);
}

TEST(RenderCli, RefusesOutputsAndServersItCannotUse) {
  REQUIRE_CLIENT();
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt");
  const std::string out = q((fs::temp_directory_path() / "rayfarm-cli-out").string());
  auto render = [&](const std::string& args) {
    return run(kRayfarm + " render " + scene + " -q " + args + " 2>&1");
  };
  Outcome jpg = render("-o " + out + ".jpg");
  EXPECT_EQ(jpg.code, 2);
  EXPECT_NE(jpg.out.find("rayfarm writes PNG or PPM images"), std::string::npos) << jpg.out;
  EXPECT_EQ(render("-o " + out + ".png --format ppm").code, 2);
  // A flag's bad value is a usage error, said with the flag's name.
  Outcome spp = render("-o " + out + ".png --spp 0");
  EXPECT_EQ(spp.code, 2);
  EXPECT_EQ(spp.out.rfind("--spp: must be an integer in 1..", 0), 0u) << spp.out;
  // What check would warn about, render says too (and still renders).
  const fs::path behind = fs::temp_directory_path() / "rayfarm-cli-behind.txt";
  std::ofstream(behind) << "camera c\n{ pixeldim 8 6\n  worlddim 8 6\n  viewpoint 4 3 5 }\n"
                           "material m\n{ diffuse 1 1 1 }\nlight l\n{ location 4 3 2 }\n"
                           "sphere s\n{ material m\n  center 4 3 10\n  radius 1 }\n";
  Outcome warned = run(kRayfarm + " render " + q(behind.string()) + " -o " + out + ".png 2>&1");
  EXPECT_EQ(warned.code, 0);
  EXPECT_NE(warned.out.find("warning: sphere 's' is behind the eye"), std::string::npos) << warned.out;
  fs::remove(behind);
  // A server URL it cannot use is a usage error, never a crash.
  for (const char* url : {"ftp://x", "http://localhost:8080/api", "http://:80", "http://h:99999"}) {
    Outcome r = render(std::string("--server ") + url + " -o " + out + ".png");
    EXPECT_EQ(r.code, 2) << url << ": " << r.out;
    EXPECT_EQ(r.out.rfind("rayfarm: ", 0), 0u) << r.out;
  }
  // Nobody listens on port 1: the message says what to check.
  Outcome refused = render("--server http://127.0.0.1:1 -o " + out + ".png");
  EXPECT_EQ(refused.code, 3);
  EXPECT_NE(refused.out.find("is rayfarmd running there?"), std::string::npos) << refused.out;
  // `none` renders here, whatever RAYFARM_SERVER says.
  EXPECT_EQ(run("RAYFARM_SERVER=ftp://x " + kRayfarm + " render " + scene + " -q --server none -o " +
                out + ".png").code,
            0);
  fs::remove(fs::temp_directory_path() / "rayfarm-cli-out.png");
}

}  // namespace
