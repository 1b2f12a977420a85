// The command line as its users run it: `rayfarm grade` and `compare` as a grading platform
// does (the worked example in scenes/assignments/lab1, the lock file, a student's program
// under --run, exit codes), `render`'s refusals of outputs and server URLs it cannot use,
// usage errors and help, and the remote workflow against a real rayfarmd.
#include <dlfcn.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "http.h"
#include "hostile_server.h"
#include "temp_dir.h"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

const std::string kRayfarm = RAYFARM_BINARY_DIR "/client/rayfarm";
const std::string kRayfarmd = RAYFARM_BINARY_DIR "/server/rayfarmd";
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

bool is_png(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[8] = {};
  in.read(magic, 8);
  return std::string(magic + 1, 3) == "PNG";
}

// The client is built with the tests, except in sanitizer builds (CI runs these there without).
#define REQUIRE_CLIENT()                                                          \
  if (!fs::exists(kRayfarm)) GTEST_SKIP() << "no " << kRayfarm << " in this build"

using rayfarm::test::TempDir;

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

// A misnamed image is missing, and the report names the file that is probably it.
TEST_F(GradeCli, AMissingImageNamesAFileCloseToItsName) {
  const fs::path images = dir_ / "ada";
  fs::copy(kLab + "/students/ada", images);
  fs::rename(images / "glint.png", images / "Glnt.png");
  Json j = grade(q(kLab + "/lab1.json") + " --images " + q(images.string()));
  EXPECT_EQ(j["tests"][3]["score"], 0);
  EXPECT_EQ(j["tests"][3]["message"],
            "your image glint.png was not found; a file named 'Glnt.png' is there");
  EXPECT_EQ(j["tests"][0]["score"], 2);
  // A folder by the image's name is said to be one (not "not found; it is there").
  fs::create_directory(images / "glint.png");
  Json folder = grade(q(kLab + "/lab1.json") + " --images " + q(images.string()));
  EXPECT_EQ(folder["tests"][3]["message"], "your image glint.png is a folder, not an image file");
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
  // Nothing graded: no test shows feedback measured against the changed reference.
  EXPECT_TRUE(refused["tests"].empty()) << refused.dump();
  // Nor is the student's program run: the lock is checked once the references are had.
  const fs::path ran = dir_ / "ran";
  const std::string program = " --run " + q("touch " + ran.string());
  Json not_run = grade(assignment + program, 2);
  EXPECT_TRUE(not_run["tests"].empty()) << not_run.dump();
  EXPECT_FALSE(fs::exists(ran));
  fs::remove(dir_ / "lab1.lock.json");  // without the lock, the same grade runs it
  grade(assignment + program);
  EXPECT_TRUE(fs::exists(ran));
}

// The result and a frozen lock never go over what the grade reads: the assignment, a test's
// scene, a student's image.
TEST_F(GradeCli, OutputsNeverOverwriteTheGradesInputs) {
  fs::copy(kLab + "/scenes", dir_ / "scenes");
  fs::copy(kLab + "/lab1.json", dir_ / "lab1.json");
  fs::copy(kLab + "/students/ada", dir_ / "ada");
  const std::string assignment = q((dir_ / "lab1.json").string());
  const std::string images = " --images " + q((dir_ / "ada").string());
  auto bytes = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string before_json = bytes(dir_ / "lab1.json");
  const std::string before_png = bytes(dir_ / "ada/glint.png");
  const std::string before_scene = bytes(dir_ / "scenes/glint.txt");
  for (const fs::path& target :
       {dir_ / "lab1.json", dir_ / "ada/glint.png", dir_ / "scenes/glint.txt"}) {
    Outcome r = run(kRayfarm + " grade " + assignment + images + " -o " + q(target.string()) +
                    cache_ + " 2>&1");
    EXPECT_EQ(r.code, 2) << target;
    EXPECT_NE(r.out.find("itself: writing it would lose that file"), std::string::npos) << r.out;
  }
  // Also when the assignment does not parse: the "grader error" result is not written over it.
  {
    std::ofstream(dir_ / "broken.json") << "{ not json";
    const std::string broken = q((dir_ / "broken.json").string());
    Outcome r = run(kRayfarm + " grade " + broken + images + " -o " + broken + cache_ + " 2>&1");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(bytes(dir_ / "broken.json"), "{ not json");
  }
  Outcome lock = run(kRayfarm + " grade " + assignment + " --freeze --lock " + assignment +
                     cache_ + " 2>&1");
  EXPECT_EQ(lock.code, 2);
  EXPECT_NE(lock.out.find("--lock"), std::string::npos) << lock.out;
  EXPECT_EQ(bytes(dir_ / "lab1.json"), before_json);
  EXPECT_EQ(bytes(dir_ / "ada/glint.png"), before_png);
  EXPECT_EQ(bytes(dir_ / "scenes/glint.txt"), before_scene);
  // The lock a grade checks against is an input too.
  ASSERT_EQ(run(kRayfarm + " grade " + assignment + " --freeze" + cache_).code, 0);
  const std::string before_lock = bytes(dir_ / "lab1.lock.json");
  EXPECT_EQ(run(kRayfarm + " grade " + assignment + images + " -o " +
                q((dir_ / "lab1.lock.json").string()) + cache_ + " 2>&1")
                .code,
            2);
  EXPECT_EQ(bytes(dir_ / "lab1.lock.json"), before_lock);
  // Beside them is fine.
  EXPECT_EQ(run(kRayfarm + " grade " + assignment + images + " -o " +
                q((dir_ / "ada/result.json").string()) + cache_)
                .code,
            0);
  // A texture a test's scene reads is an input as well.
  fs::copy(RAYFARM_SOURCE_DIR "/scenes/textures.txt", dir_ / "scenes/textures.txt");
  fs::copy(RAYFARM_SOURCE_DIR "/scenes/textures", dir_ / "scenes/textures");
  std::ofstream(dir_ / "textured.json")
      << R"({"name": "t", "tests": [{"name": "bricks", "scene": "scenes/textures.txt",
                                     "image": "textures.png"}]})";
  const fs::path texture = dir_ / "scenes/textures/bricks.ppm";
  const std::string before_texture = bytes(texture);
  Outcome textured = run(kRayfarm + " grade " + q((dir_ / "textured.json").string()) + images +
                         " -o " + q(texture.string()) + cache_ + " 2>&1");
  EXPECT_EQ(textured.code, 2) << textured.out;
  EXPECT_NE(textured.out.find("itself: writing it would lose that file"), std::string::npos)
      << textured.out;
  EXPECT_EQ(bytes(texture), before_texture);
  // Said before the student's program runs, and also for a texture that cannot be decoded.
  std::ofstream(texture, std::ios::trunc) << "P6 not an image";
  const fs::path ran = dir_ / "ran";
  Outcome program = run(kRayfarm + " grade " + q((dir_ / "textured.json").string()) +
                        " --run " + q("touch " + ran.string()) + " -o " + q(texture.string()) +
                        cache_ + " 2>&1");
  EXPECT_EQ(program.code, 2) << program.out;
  EXPECT_NE(program.out.find("itself: writing it would lose that file"), std::string::npos)
      << program.out;
  EXPECT_FALSE(fs::exists(ran));
  EXPECT_EQ(bytes(texture), "P6 not an image");
}

// A test whose scene has errors is the instructor's to fix: nothing is graded (exit 2, a
// result that says grader error), and no platform lists points for the tests that passed.
TEST_F(GradeCli, AnAssignmentWhoseSceneHasErrorsGradesNothing) {
  fs::copy(kLab + "/scenes", dir_ / "scenes");
  fs::copy(kLab + "/lab1.json", dir_ / "lab1.json");
  {
    std::ofstream edit(dir_ / "scenes/glint.txt", std::ios::app);
    edit << "\nsphere broken\n{\n  material nowhere\n  center 0 0 0\n  radius 1\n}\n";
  }
  const std::string args =
      q((dir_ / "lab1.json").string()) + " --images " + q(kLab + "/students/ada");
  Json j = grade(args, 2);
  EXPECT_EQ(j["score"], 0);
  EXPECT_EQ(j["error"].get<std::string>().rfind("test 'A glint': ", 0), 0u) << j["error"];
  for (const Json& t : j["tests"]) EXPECT_EQ(t["score"], 0) << t["name"];
  EXPECT_EQ(j["tests"][0]["status"], "passed");  // what was found stays said
  EXPECT_EQ(j["tests"][3]["status"], "error");
  Outcome gs = run(kRayfarm + " grade " + args + cache_ + " --format gradescope");
  EXPECT_EQ(gs.code, 2);
  Json g = Json::parse(gs.out, nullptr, false);
  ASSERT_FALSE(g.is_discarded()) << gs.out;
  EXPECT_EQ(g["score"], 0);
  for (const Json& t : g["tests"]) EXPECT_EQ(t["score"], 0) << t["name"];
  EXPECT_NE(g["output"].get<std::string>().find("grader error: test 'A glint'"), std::string::npos);
}

// What a student hands in must be theirs: a link out of their folder, or a program's link,
// is no image; and a program that overwrites the grader's cached references changes no
// grade (every reference is read before any student's program runs).
TEST_F(GradeCli, AStudentCannotHandInAnotherFile) {
  const std::string assignment = q(kLab + "/lab1.json");
  const std::string ada = kLab + "/students/ada", ben = kLab + "/students/ben";
  EXPECT_EQ(grade(assignment + " --images " + q(ada))["score"], 10);  // fills the cache
  const fs::path sneaky = dir_ / "sneaky";
  fs::create_directories(sneaky / "real");
  for (const char* name : {"shadows.png", "mirror.png", "glint.png"})
    fs::create_symlink(fs::path(ada) / name, sneaky / name);
  fs::copy_file(fs::path(ada) / "spheres.png", sneaky / "real" / "spheres.png");
  fs::create_symlink("real/spheres.png", sneaky / "spheres.png");  // inside: fine
  Json linked = grade(assignment + " --images " + q(sneaky.string()));
  EXPECT_EQ(linked["score"], 2);
  EXPECT_EQ(linked["tests"][1]["message"], "your image shadows.png is a link to a file outside your folder");

  Json link_run = grade(assignment + " --run " + q("ln -s " + ada + "/$(basename {scene} .txt).png {out}"));
  EXPECT_EQ(link_run["score"], 0);
  EXPECT_EQ(link_run["tests"][0]["message"].get<std::string>().rfind("your program wrote a link", 0), 0u)
      << link_run["tests"][0]["message"];

  const std::string poison = "for c in " + q((dir_ / "cache").string()) + "/*.png; do cp " + ben +
                             "/spheres.png \"$c\"; done; cp " + ada +
                             "/$(basename {scene} .txt).png {out}";
  EXPECT_EQ(grade(assignment + " --run " + q(poison))["score"], 10);
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
  // {out} lies in a folder of the grade's own, private and new (not one another user could
  // have made or linked beforehand), which is gone when the grade ends, leftovers and all.
  const fs::path record = dir_ / "where";
  Json placed = grade(assignment + " --run " +
                      q("d=$(dirname {out}); echo $(stat -c %a \"$d\") \"$d\" >> " +
                        record.string() + "; cp " +
                        ada + "/$(basename {scene} .txt).png {out}; touch \"$(dirname {out})/left\""));
  EXPECT_EQ(placed["score"], 10);
  std::ifstream lines(record);
  std::string mode, folder;
  int runs = 0;
  while (lines >> mode >> folder) {
    ++runs;
    EXPECT_EQ(mode, "700") << folder;
    EXPECT_FALSE(fs::exists(folder)) << folder;
  }
  EXPECT_EQ(runs, 4);
}

// --fail-under compares exactly: 57 of 100 points is not below 57%.
TEST_F(GradeCli, FailUnderIsExactAtItsPercentage) {
  fs::copy(kLab + "/scenes", dir_ / "scenes");
  std::ofstream(dir_ / "a.json") << R"({"name": "x", "profile": "cpsc102", "tests": [
      {"name": "s", "scene": "scenes/spheres.txt", "image": "spheres.png", "points": 57},
      {"name": "m", "scene": "scenes/mirror.txt", "image": "mirror.png", "points": 43}]})";
  fs::create_directories(dir_ / "st");
  fs::copy_file(kLab + "/students/ada/spheres.png", dir_ / "st/spheres.png");
  fs::copy_file(kLab + "/students/ben/mirror.png", dir_ / "st/mirror.png");
  const std::string args = q((dir_ / "a.json").string()) + " --images " + q((dir_ / "st").string());
  EXPECT_EQ(grade(args)["score"], 57);
  EXPECT_EQ(run(kRayfarm + " grade " + args + cache_ + " --fail-under 57 -o /dev/null").code, 0);
  EXPECT_EQ(run(kRayfarm + " grade " + args + cache_ + " --fail-under 57.01 -o /dev/null").code, 1);
}

// A command line the grader refuses still leaves the platform a result that says so.
TEST_F(GradeCli, ABadCommandLineStillWritesAResult) {
  const std::string assignment = q(kLab + "/lab1.json");
  const fs::path none = dir_ / "none.json", threads = dir_ / "out/threads.json";
  EXPECT_EQ(run(kRayfarm + " grade " + assignment + cache_ + " --format json -o " + q(none.string())).code, 2);
  std::ifstream in(none);
  Json j = Json::parse(in, nullptr, false);
  ASSERT_FALSE(j.is_discarded());
  EXPECT_NE(j["error"].get<std::string>().find("--images"), std::string::npos) << j;
  EXPECT_EQ(run(kRayfarm + " grade " + assignment + " --images " + q(kLab + "/students/ada") +
                " --threads 2000 --format=gradescope -o" + threads.string()).code, 2);
  std::ifstream in2(threads);
  Json g = Json::parse(in2, nullptr, false);
  ASSERT_FALSE(g.is_discarded());
  EXPECT_EQ(g["score"], 0);
  EXPECT_NE(g["output"].get<std::string>().find("--threads"), std::string::npos) << g;
  // A file named where the folder of images belongs is told apart from a missing folder.
  const fs::path file = dir_ / "file.json";
  EXPECT_EQ(run(kRayfarm + " grade " + assignment + " --images " + assignment + cache_ +
                " --format json -o " + q(file.string())).code, 2);
  std::ifstream in3(file);
  Json f = Json::parse(in3, nullptr, false);
  ASSERT_FALSE(f.is_discarded());
  EXPECT_NE(f["error"].get<std::string>().find("is not a folder"), std::string::npos) << f;
}

// --run's placeholders are replaced in one pass: a scene path holding "{name}" does not get
// the test's name spliced into its quotes (where a name's $(...) would run).
TEST_F(GradeCli, RunPlaceholdersAreQuotedWhateverTheyHold) {
  fs::copy(kLab + "/scenes", dir_ / "s{name}");
  const fs::path marker = dir_ / "INJECTED";
  Json a = {{"name", "x"},
            {"profile", "cpsc102"},
            {"tests", {{{"name", "t $(touch " + marker.string() + ")"},
                        {"scene", "s{name}/spheres.txt"},
                        {"image", "spheres.png"}}}}};
  std::ofstream(dir_ / "a.json") << a.dump();
  const std::string program = "test -f {scene} && cp " + kLab + "/students/ada/spheres.png {out}";
  Json j = grade(q((dir_ / "a.json").string()) + " --run " + q(program));
  EXPECT_EQ(j["score"], 1) << j;
  EXPECT_FALSE(fs::exists(marker));
}

// A hard link is a link too: a program under --run cannot hand in a file that was there
// before it ran; and a link to nothing is said to be one.
TEST_F(GradeCli, LinksOfEveryKindAreNoImage) {
  fs::copy(kLab + "/students/ada", dir_ / "ada");
  const std::string assignment = q(kLab + "/lab1.json");
  Json hard = grade(assignment + " --run " +
                    q("ln " + (dir_ / "ada").string() + "/$(basename {scene} .txt).png {out}"));
  EXPECT_EQ(hard["score"], 0);
  EXPECT_EQ(hard["tests"][0]["message"].get<std::string>().rfind("your program wrote a link", 0), 0u)
      << hard["tests"][0]["message"];
  fs::remove(dir_ / "ada/glint.png");
  fs::create_symlink(dir_ / "ada/nowhere.png", dir_ / "ada/glint.png");
  Json dangling = grade(assignment + " --images " + q((dir_ / "ada").string()));
  EXPECT_EQ(dangling["tests"][3]["message"], "your image glint.png is a link to a file that does not exist");
}

// An image in a folder of the student's is named with that folder, as the assignment names it.
TEST_F(GradeCli, AnImageInASubfolderIsNamedWithIt) {
  fs::copy(kLab + "/scenes", dir_ / "scenes");
  std::ofstream(dir_ / "sub.json")
      << R"({"name": "s", "tests": [{"name": "glint", "scene": "scenes/glint.txt",
                                     "image": "part2/glint.png"}]})";
  fs::create_directories(dir_ / "ada/part2");
  std::ofstream(dir_ / "ada/part2/glint.png") << "not an image";
  Json j = grade(q((dir_ / "sub.json").string()) + " --images " + q((dir_ / "ada").string()));
  EXPECT_EQ(j["tests"][0]["message"].get<std::string>().rfind(
                "your image part2/glint.png cannot be read: ", 0),
            0u)
      << j["tests"][0]["message"];
  fs::remove(dir_ / "ada/part2/glint.png");
  std::ofstream(dir_ / "ada/part2/glint.ppm") << "P3 1 1 255 0 0 0";
  Json other = grade(q((dir_ / "sub.json").string()) + " --images " + q((dir_ / "ada").string()));
  EXPECT_NE(other.dump().find("graded part2/glint.ppm: no part2/glint.png was found"),
            std::string::npos)
      << other.dump();
}

TEST_F(GradeCli, AssignmentErrorsArePlaced) {
  std::ofstream(dir_ / "bad.json") << R"({"name": "x", "tests": [{"name": "a", "scene": "a.txt", "pionts": 2}]})";
  Outcome r = run(kRayfarm + " grade " + q((dir_ / "bad.json").string()) + " --images . 2>&1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("at /tests/0/pionts: unknown key 'pionts'; did you mean 'points'?"),
            std::string::npos)
      << r.out;
  // The result file, all a platform shows, holds the place too.
  const fs::path out = dir_ / "result.json";
  run(kRayfarm + " grade " + q((dir_ / "bad.json").string()) + " --images . --format json -o " +
      q(out.string()) + " 2>&1");
  std::ifstream in(out);
  const Json result = Json::parse(in, nullptr, false);
  ASSERT_FALSE(result.is_discarded());
  EXPECT_NE(result["error"].get<std::string>().find("at /tests/0/pionts: unknown key"),
            std::string::npos)
      << result.dump();
}

TEST(CompareCli, ExitsAsDiffDoes) {
  REQUIRE_CLIENT();
  const std::string ada = q(kLab + "/students/ada/mirror.png");
  const std::string ben = q(kLab + "/students/ben/mirror.png");
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ada).code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben).code, 1);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben + " --threshold 1").code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben + " --max-bad-fraction 0.9").code, 0);
  // A subnormal fraction is a number (it allows no differing pixel here).
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ada + " --max-bad-fraction 2e-308").code, 0);
  EXPECT_EQ(run(kRayfarm + " compare " + ada + " " + ben + " --max-bad-fraction 2e-308").code, 1);
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
  // Options that make an image no render takes are not written into the scene.
  Outcome big = run(kRayfarm + " convert " + scene + " --to json --width 65535 --height 65535 2>&1");
  EXPECT_EQ(big.code, 2);
  EXPECT_NE(big.out.find("with the options given, the image has 4294836225 pixels"),
            std::string::npos) << big.out;
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
  EXPECT_EQ(spp.out.rfind("rayfarm: --spp: must be an integer in 1..", 0), 0u) << spp.out;
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
  // `none` renders here, whatever RAYFARM_SERVER says; so does an empty --server.
  EXPECT_EQ(run("RAYFARM_SERVER=ftp://x " + kRayfarm + " render " + scene + " -q --server none -o " +
                out + ".png").code,
            0);
  EXPECT_EQ(run("RAYFARM_SERVER=ftp://x " + kRayfarm + " render " + scene + " -q --server '' -o " +
                out + ".png").code,
            0);
  fs::remove(fs::temp_directory_path() / "rayfarm-cli-out.png");
}

// Where the output goes: a device or a pipe is written in place (a render `-o /dev/null` once
// replaced the machine's /dev/null with a file), a full device or a directory is refused with
// its reason, and a file is replaced whole, through a symbolic link to what it names, keeping
// its permissions.
TEST(RenderCli, OutputsGoWhereTheyPoint) {
  REQUIRE_CLIENT();
  const fs::path dir = fs::temp_directory_path() / ("rayfarm-out-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "real");
  const std::string render = kRayfarm + " render " + q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") +
                             " -q --width 40 --height 30 -o ";
  auto status = [](const fs::path& p) { return fs::symlink_status(p).type(); };

  EXPECT_EQ(run(render + "/dev/null 2>&1").code, 0);
  EXPECT_EQ(status("/dev/null"), fs::file_type::character);
  Outcome full = run(render + "/dev/full 2>&1");
  EXPECT_EQ(full.code, 2);
  EXPECT_NE(full.out.find("cannot write /dev/full: No space left on device"), std::string::npos)
      << full.out;
  EXPECT_EQ(status("/dev/full"), fs::file_type::character);
  Outcome to_full = run(render + "- 2>&1 > /dev/full");
  EXPECT_EQ(to_full.code, 2);
  EXPECT_NE(to_full.out.find("cannot write to standard output"), std::string::npos) << to_full.out;

  // A pipe: its reader gets the image (smaller than the pipe's buffer, so read once the
  // render is done), and the pipe stays.
  const fs::path fifo = dir / "fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
  ASSERT_GE(reader, 0);
  EXPECT_EQ(run(render + q(fifo.string()) + " 2>&1").code, 0);
  std::string got;
  char buf[4096];
  for (ssize_t n; (n = ::read(reader, buf, sizeof buf)) > 0;) got.append(buf, static_cast<size_t>(n));
  ::close(reader);
  EXPECT_EQ(got.substr(0, 4), "\x89PNG");
  EXPECT_EQ(status(fifo), fs::file_type::fifo);

  // A new file, then the same again over it.
  EXPECT_EQ(run(render + q((dir / "new.png").string()) + " 2>&1").code, 0);
  EXPECT_EQ(run(render + q((dir / "new.png").string()) + " 2>&1").code, 0);
  EXPECT_TRUE(is_png(dir / "new.png"));
  // A link to nothing yet, then to that file: the link stays and the file gets the image.
  const fs::path link = dir / "link.png", target = dir / "real" / "t.png";
  fs::create_symlink("real/t.png", link);
  EXPECT_EQ(run(render + q(link.string()) + " 2>&1").code, 0);
  EXPECT_TRUE(is_png(target));
  fs::permissions(target, fs::perms::owner_read | fs::perms::owner_write);
  fs::resize_file(target, 3);
  EXPECT_EQ(run(render + q(link.string()) + " 2>&1").code, 0);
  EXPECT_EQ(status(link), fs::file_type::symlink);
  EXPECT_TRUE(is_png(target));
  EXPECT_EQ(fs::status(target).permissions(), fs::perms::owner_read | fs::perms::owner_write);

  fs::create_directories(dir / "d.png");
  Outcome directory = run(render + q((dir / "d.png").string()) + " 2>&1");
  EXPECT_EQ(directory.code, 2);
  EXPECT_NE(directory.out.find("d.png: it is a directory"), std::string::npos) << directory.out;
  // Nothing left beside the outputs.
  for (const auto& e : fs::recursive_directory_iterator(dir))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
  fs::remove_all(dir);
}

// An input larger than the client reads (1 GiB: client/read_file.h) is refused with its name
// and exit 2, the scene file's and standard input's alike, and a texture that large is an
// error of the scene at its place: `render /dev/zero` once filled memory until the program
// aborted. (tests/read_file_test.cpp holds the limit's edge.) Memory is capped for the runs, so
// that a regression fails here rather than filling the machine.
// A texture that is a pipe would be opened for ever (no writer comes), a device read to the
// limit: each is refused at its place, at once.
TEST(RenderCli, APipeOrADeviceIsNoTexture) {
  REQUIRE_CLIENT();
  const fs::path dir = fs::temp_directory_path() / ("rayfarm-fifo-" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  ASSERT_EQ(mkfifo((dir / "pipe.ppm").c_str(), 0600), 0);
  std::ofstream(dir / "scene.txt")
      << "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
         "material m { diffuse 1 1 1 }\n"
         "texture t { filename pipe.ppm }\n"
         "texplane w { material m normal 0 0 1 point 0 0 -5 xdir 1 0 0 dimensions 8 6 "
         "texname t mode 0 }\n";
  const auto start = std::chrono::steady_clock::now();
  Outcome r = run("timeout 20 " + kRayfarm + " check " + q((dir / "scene.txt").string()) + " 2>&1");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("pipe.ppm is a pipe, not a file"), std::string::npos) << r.out;
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
  // A device is refused before it is read (/dev/zero took 5 s and 1.6 GB to be "too large").
  std::ofstream(dir / "device.txt")
      << "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 4 3 5 }\n"
         "material m { diffuse 1 1 1 }\n"
         "texture t { filename /dev/zero }\n"
         "texplane w { material m normal 0 0 1 point 0 0 -5 xdir 1 0 0 dimensions 8 6 "
         "texname t mode 0 }\n";
  Outcome device = run(kRayfarm + " check " + q((dir / "device.txt").string()) + " 2>&1");
  EXPECT_EQ(device.code, 1) << device.out;
  EXPECT_NE(device.out.find("/dev/zero is a device, not a file"), std::string::npos) << device.out;
  fs::remove_all(dir);
}

TEST(RenderCli, InputsPastTheLimitAreRefused) {
  REQUIRE_CLIENT();
  const std::string pid = std::to_string(::getpid());
  const fs::path sparse = fs::temp_directory_path() / ("rayfarm-cli-sparse-" + pid);
  const fs::path out = fs::temp_directory_path() / ("rayfarm-cli-never-" + pid + ".png");
  const std::string capped = "ulimit -v 4194304; ";  // KiB: 4 GiB of address space
  std::ofstream(sparse).put('c');
  std::error_code ec;
  fs::resize_file(sparse, (std::uintmax_t{1} << 30) + 1, ec);  // sparse: nothing is written
  ASSERT_FALSE(ec) << ec.message();
  const std::string limit = ": larger than 1 GiB, the most rayfarm reads from one input";
  Outcome scene = run(capped + kRayfarm + " render " + q(sparse.string()) + " -q -o " +
                      q(out.string()) + " 2>&1");
  EXPECT_EQ(scene.code, 2) << scene.out;
  EXPECT_EQ(scene.out, "rayfarm: " + sparse.string() + limit + "\n");

  const fs::path textured = fs::temp_directory_path() / ("rayfarm-cli-texture-" + pid + ".txt");
  std::ofstream(textured) << "camera c { pixeldim 8 6 worlddim 8 6 viewpoint 0 0 5 }\n"
                             "material m { diffuse 1 1 1 }\n"
                             "texplane t { material m normal 0 1 0 point 0 0 0 xdir 1 0 0\n"
                             "             dimensions 1 1 texname " << sparse.string() << " mode 0 }\n";
  Outcome texture = run(capped + kRayfarm + " render " + q(textured.string()) + " -q -o " +
                        q(out.string()) + " 2>&1");
  EXPECT_EQ(texture.code, 2) << texture.out;
  EXPECT_NE(texture.out.find(":4:37: error: cannot read texture '" + sparse.string() + "': " +
                             sparse.string() + limit),
            std::string::npos)
      << texture.out;
  fs::remove(textured);
  fs::remove(sparse);

  // A pipe that never ends: read to the limit, then refused.
  Outcome piped = run(capped + "cat /dev/zero | " + kRayfarm + " check - 2>&1");
  EXPECT_EQ(piped.code, 2) << piped.out;
  EXPECT_EQ(piped.out, "rayfarm: <stdin>" + limit + "\n");
  EXPECT_FALSE(fs::exists(out));
  fs::remove(out);
}

// Every command's words for a command line it cannot use: what is wrong in plain words, the
// option named with the values it takes, and exit 2.
TEST(UsageCli, ErrorsNameTheOptionAndWhatItTakes) {
  REQUIRE_CLIENT();
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt");
  auto usage = [&](const std::string& args, const std::string& expected) {
    Outcome r = run(kRayfarm + " " + args + " 2>&1");
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_EQ(r.out.rfind("rayfarm: " + expected + "\n", 0), 0u) << args << "\n" << r.out;
  };
  usage("render " + scene + " --width 40 --width 50", "--width given twice; give it once");
  usage("render " + scene + " --max_depth 3 --max-depth 4",
        "--max-depth given twice; give it once");
  usage("render " + scene + " --frobnicate 3", "unknown option --frobnicate");
  usage("render " + scene + " --sp=3", "unknown option --sp (did you mean --spp?)");
  usage("render " + scene + " extra", "unexpected argument 'extra'");
  usage("rendr " + scene,
        "unknown command 'rendr' (did you mean 'render'?); the commands are render, trace, check, "
        "convert, compare, grade, report, status, cancel, wait, jobs");
  usage("render " + scene + " --threads 2000",
        "--threads: must be an integer in 0..1024, got '2000'");
  usage("compare a.png b.png --threshold 300",
        "--threshold: must be an integer in 0..255, got '300'");
  // Spaces around an integer are refused on either side, as around every other number.
  usage("compare a.png b.png --threshold ' 5'", "--threshold: must be an integer in 0..255, got ' 5'");
  usage("compare a.png b.png --threshold '5 '", "--threshold: must be an integer in 0..255, got '5 '");
  usage("compare a.png b.png --threshold +-5", "--threshold: must be an integer in 0..255, got '+-5'");
  usage("compare a.png b.png --diff heatmap",
        "--diff: 'heatmap' has no extension: name the heat map .png or .ppm");
  usage("compare a.png b.png --diff -",
        "--diff: the report goes to standard output; give the heat map a file name (.png or .ppm)");
  usage("compare a.png b.png --diff d.jpg",
        "--diff: 'd.jpg': rayfarm writes PNG or PPM images; name the file .png or .ppm");
  usage("compare a.png b.png --max-bad-fraction x",
        "--max-bad-fraction: must be a number in 0..1, got 'x'");
  usage("render " + scene + " --background 255,0,0",
        "--background: must be at most 1, got 255 (colours are 0..1, not 0..255)");
  // Options a command would ignore are refused, not dropped.
  usage("report " + scene + " --format ppm",
        "--format: report writes report.md, report.csv and report.svg");
  usage("report " + scene + " --spp 4",
        "--spp: report renders a ladder of spp (1 to 64) against a reference of --reference-spp");
  usage("trace " + scene + " 1 1 --format ppm",
        "--format: trace prints the pixel's bytes, not an image");
  // A pixel is decimal: 010 is pixel 10 (not octal 8), 0x10 is refused.
  // Its bytes would not be the render's: the render stops where the whole image says.
  usage("trace " + scene + " 1 1 --target-error 2",
        "--target-error: trace follows a set number of samples; give --spp M --samples N for a "
        "render that stopped at spp N/M");
  usage("trace " + scene + " 1 1 --time-limit 1",
        "--time-limit: trace follows a set number of samples; give --spp M --samples N for a "
        "render that stopped at spp N/M");
  usage("trace " + scene + " 0x10 1", "x: '0x10' is not a pixel number (decimal digits, from 0)");
  usage("trace " + scene + " 1 1 --spp 4 --samples 5",
        "--samples 5 is more than the 4 samples a pixel of --spp: a render takes at most its spp");
  usage("trace " + scene + " 1 1 --spp 4 --samples 2 --profile cpsc102",
        "--samples: the cpsc102 profile takes a pixel's samples in one pass, so its renders never "
        "stop early; give --spp alone");
  EXPECT_EQ(run(kRayfarm + " trace " + scene + " 010 0").out.rfind("Pixel (10, 0) of ", 0), 0u);
  // Too large for any image is said so, not "not a number".
  usage("trace " + scene + " 1 4294967296",
        "y: '4294967296' is past every image: images are at most 65535 pixels wide or high");
  usage("convert " + scene + " --to json --camera nosuch", "error: no camera named 'nosuch'");
  {
    // A file whose name starts with '-' reads as an option: how to name it is said, and
    // both ways work.
    TempDir dir("dash-name");
    fs::copy_file(RAYFARM_SOURCE_DIR "/scenes/minimal.txt", dir.path / "-scene.txt");
    const std::string in = "cd " + q(dir.path.string()) + " && " + kRayfarm;
    Outcome r = run(in + " check -scene.txt 2>&1");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(r.out.rfind("rayfarm: scenes is required; '-scene.txt' was read as an option: "
                          "name the file ./-scene.txt, or give it last, after --\n", 0), 0u)
        << r.out;
    EXPECT_EQ(run(in + " check ./-scene.txt").code, 0);
    EXPECT_EQ(run(in + " render -q -o out.png -- -scene.txt").code, 0);
    EXPECT_TRUE(is_png(dir.path / "out.png"));
    // Not a file: nothing is suggested.
    Outcome none = run(in + " check -nothing.txt 2>&1");
    EXPECT_EQ(none.out.find("./-nothing.txt"), std::string::npos) << none.out;
  }
  // An image too large for render is refused by trace too, as render says it (with the
  // place in the file where the file gives the size).
  for (const std::string& command : {std::string(" render "), std::string(" trace ")}) {
    Outcome r = run(kRayfarm + command + scene + " --width 65535 --height 65535" +
                    (command == " trace " ? " 1 1" : " -o /dev/null") + " 2>&1");
    EXPECT_EQ(r.code, 2) << command << r.out;
    EXPECT_NE(r.out.find("minimal.txt: error: with the width and height asked for, the image "
                         "has 4294836225 pixels"),
              std::string::npos)
        << command << r.out;
  }
  usage("convert " + scene + " --to pov --spp 8",
        "--to pov cannot use --spp: the POV-Ray file takes --camera, --width, --height, "
        "--max-depth, --profile, --background and --highlight");
  usage("render " + scene + " --detach",
        "--detach needs a server: give --server URL or set RAYFARM_SERVER");
  usage("render " + scene + " --detach --server http://127.0.0.1:1 -o x.png",
        "--detach saves no image: give -o (or --format) to rayfarm wait ID");
  // A file that cannot be read is input to fix: 2 for every command.
  for (const char* command : {"render", "check", "convert --to json", "trace", "report"}) {
    Outcome r = run(kRayfarm + " " + command + " /nonexistent.txt" +
                    (std::string(command) == "trace" ? " 0 0" : "") + " 2>&1");
    EXPECT_EQ(r.code, 2) << command << ": " << r.out;
  }
}

TEST(UsageCli, EveryCommandsHelpHasExamplesDefaultsAndExitCodes) {
  REQUIRE_CLIENT();
  for (const char* command : {"render", "trace", "check", "convert", "compare", "grade", "report",
                              "status", "cancel", "wait", "jobs"}) {
    Outcome r = run(kRayfarm + " " + command + " --help");
    EXPECT_EQ(r.code, 0) << command;
    EXPECT_NE(r.out.find("Usage: rayfarm " + std::string(command)), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("\nExamples:\n  rayfarm " + std::string(command)), std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("Exit codes (the same for every command):\n  0    done\n"),
              std::string::npos)
        << r.out;
  }
  Outcome render = run(kRayfarm + " render --help");
  EXPECT_NE(render.out.find(
                "samples per pixel (stratified jitter; 1 = the exact pixel point) (default: 1)"),
            std::string::npos)
      << render.out;
  EXPECT_NE(render.out.find("colour of rays that hit nothing, each 0..1"), std::string::npos);
  EXPECT_NE(render.out.find("  1    the server's job failed or was canceled\n"), std::string::npos);
  // Options a command refuses are not offered.
  EXPECT_EQ(run(kRayfarm + " report --help").out.find("--spp"), std::string::npos);
  Outcome top = run(kRayfarm + " --help");
  EXPECT_NE(top.out.find("RAYFARM_TOKEN"), std::string::npos) << top.out;
  EXPECT_NE(top.out.find("  1    the answer is no: check found errors"), std::string::npos);
}

TEST(CheckCli, ErrorsComeInLineOrderWithACount) {
  REQUIRE_CLIENT();
  const fs::path bad =
      fs::temp_directory_path() / ("rayfarm-cli-check-" + std::to_string(getpid()) + ".txt");
  std::ofstream(bad) << "camera c\n{ pixeldim 8 6\n  worlddim 8 6\n  viewpoint 4 3 5 }\n"
                        "material m\n{ diffuse 1 1 1 }\nlight l\n{ location 4 3 2 }\n"
                        "sphere s\n{ material mm\n  center 4 3 -2\n  radious 1 }\n"
                        "plane p\n{ material m\n  normal 0 0 1\n  pont 0 0 -5\n}\n";
  for (const std::string flags : {"", " --course"}) {
    Outcome r = run(kRayfarm + " check" + flags + " " + q(bad.string()) + " 2>&1");
    EXPECT_EQ(r.code, 1) << r.out;
    std::vector<int> lines;
    const std::regex at(bad.filename().string() + ":(\\d+):\\d+: (error|warning)");
    for (std::sregex_iterator it(r.out.begin(), r.out.end(), at), end; it != end; ++it)
      lines.push_back(std::stoi((*it)[1]));
    EXPECT_GE(lines.size(), 3u) << r.out;
    EXPECT_TRUE(std::is_sorted(lines.begin(), lines.end())) << r.out;
    const std::string summary =
        bad.string() + (flags.empty() ? ": 3 errors, 0 warnings\n" : ": 3 errors, 4 warnings\n");
    EXPECT_NE(r.out.find(summary), std::string::npos) << r.out;
  }
  // Several files: a total; a missing one is trouble (2), which outranks errors (1).
  Outcome two = run(kRayfarm + " check " + q(bad.string()) + " " +
                    q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") + " /nonexistent.txt 2>&1");
  EXPECT_EQ(two.code, 2) << two.out;
  EXPECT_NE(two.out.find("3 files: 3 errors, 0 warnings\n"), std::string::npos) << two.out;
  // Past the cap the reading stops: the count says so rather than a number it did not reach.
  {
    std::ofstream many(bad);
    many << "camera c\n{ pixeldim 8 6\n  worlddim 8 6\n  viewpoint 4 3 5 }\nmaterial m\n{ diffuse 1 1 1 }\n";
    for (int i = 0; i < 100; ++i) many << "sphere { material m center 1 1 1 radius 1 bogus 1 }\n";
  }
  Outcome capped = run(kRayfarm + " check " + q(bad.string()) + " 2>&1");
  EXPECT_EQ(capped.code, 1);
  EXPECT_NE(capped.out.find(": more than 50 errors, 0 warnings (only the first 50 shown)\n"),
            std::string::npos)
      << capped.out.substr(capped.out.size() > 300 ? capped.out.size() - 300 : 0);
  fs::remove(bad);
}

// render refuses an image too large to hold; check says so first, with the camera's place.
// A command's printed answer that cannot be written is an error: trace, check and compare
// exited 0 with their output lost to a full disk.
TEST(CheckCli, StandardOutputThatCannotBeWrittenIsAnError) {
  REQUIRE_CLIENT();
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const std::string cho = q(RAYFARM_SOURCE_DIR "/scenes/cho.txt");
  for (const std::string& args : std::vector<std::string>{" trace " + cho + " 1 1", " check " + cho,
                                                         " trace " + cho + " 1 1 --json",
                                                         " render -q " + cho + " -o -"}) {
    SCOPED_TRACE(args);
    Outcome r = run(kRayfarm + args + " 2>&1 >/dev/full");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_EQ(r.out, "rayfarm: cannot write to standard output: No space left on device\n");
  }
}

// A camera too large to render is an error of the file for check, which looks at every
// camera; a render looks at the camera it renders, with or without --quiet.
TEST(CheckCli, ARenderIsRefusedOnlyForItsOwnCamerasSize) {
  REQUIRE_CLIENT();
  const TempDir dir("cli-cams");
  const fs::path scene = dir.path / "two.txt";
  std::ofstream(scene) << "camera a { pixeldim 10 10 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "camera b { pixeldim 65535 65535 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "material m { diffuse 1 }\nlight l { location 4 10 0 }\n"
                          "sphere s { material m center 4 3 -3 radius 1 }\n";
  const std::string out = " -o " + q((dir.path / "a.png").string());
  EXPECT_EQ(run(kRayfarm + " check " + q(scene.string()) + " >/dev/null 2>&1").code, 1);
  for (const std::string quiet : {"", " -q"}) {
    Outcome r = run(kRayfarm + " render" + quiet + " " + q(scene.string()) + out + " 2>&1");
    EXPECT_EQ(r.code, 0) << quiet << r.out;
    EXPECT_EQ(r.out.find("image-too-large"), std::string::npos) << r.out;
    Outcome b = run(kRayfarm + " render" + quiet + " " + q(scene.string()) + out +
                    " --camera b 2>&1");
    EXPECT_EQ(b.code, 2) << quiet << b.out;
    EXPECT_NE(b.out.find("two.txt:2:1: error: camera 'b'"), std::string::npos) << b.out;
  }
}

// A JSON scene's own format is the encoding where the output's name says none (standard
// output): it was PNG whatever the scene asked.
TEST(CheckCli, TheScenesFormatEncodesStandardOutput) {
  REQUIRE_CLIENT();
  const fs::path scene = fs::temp_directory_path() / ("rayfarm-cli-fmt-" + std::to_string(getpid()) + ".json");
  std::ofstream(scene) << R"({"camera": {"pixeldim": [4, 3], "worlddim": [8, 6], "viewpoint": [4, 3, 5]},
                              "render": {"format": "ppm"}})";
  EXPECT_EQ(run(kRayfarm + " render -q " + q(scene.string()) + " -o - | head -c 2").out, "P6");
  // The flag and a named file's extension still come first.
  EXPECT_EQ(run(kRayfarm + " render -q " + q(scene.string()) + " -o - --format png | head -c 4 | tail -c 3").out,
            "PNG");
  fs::remove(scene);
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// An output that is an input is refused, the input kept: `render scene.png` named its image
// after the scene and wrote it over the scene.
TEST(CheckCli, AnOutputThatIsAnInputIsRefused) {
  REQUIRE_CLIENT();
  const TempDir temp("cli-self");
  const fs::path& dir = temp.path;
  fs::copy_file(RAYFARM_SOURCE_DIR "/scenes/minimal.txt", dir / "scene.png");
  const std::string before = read_file(dir / "scene.png");
  Outcome r = run("cd " + q(dir.string()) + " && " + kRayfarm + " render scene.png 2>&1");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("is the input scene.png itself"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(dir / "scene.png"), before);
  const std::string a = q((dir / "a.png").string());
  ASSERT_EQ(run(kRayfarm + " render -q " + q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") + " -o " + a).code, 0);
  const std::string image = read_file(dir / "a.png");
  Outcome c = run(kRayfarm + " compare " + a + " " + a + " --diff " + q((dir / "." / "a.png").string()) + " 2>&1");
  EXPECT_EQ(c.code, 2) << c.out;
  EXPECT_EQ(read_file(dir / "a.png"), image);
  // convert onto its own scene, in any output form.
  fs::copy_file(RAYFARM_SOURCE_DIR "/scenes/minimal.txt", dir / "m.txt");
  const std::string scene = read_file(dir / "m.txt");
  for (const char* to : {"pov", "model", "json"}) {
    Outcome v = run("cd " + q(dir.string()) + " && " + kRayfarm + " convert m.txt --to " + to +
                    " -o ./m.txt 2>&1");
    EXPECT_EQ(v.code, 2) << to << v.out;
    EXPECT_NE(v.out.find("is the input m.txt itself"), std::string::npos) << v.out;
    EXPECT_EQ(read_file(dir / "m.txt"), scene) << to;
  }
}

TEST(CheckCli, AnImageTooLargeToRenderIsAnError) {
  REQUIRE_CLIENT();
  const TempDir temp("cli-huge");
  const fs::path& dir = temp.path;
  const fs::path scene = dir / "huge.txt";
  std::ofstream(scene) << "material m { ambient 1 }\n"
                          "camera c { pixeldim 65535 65535 worlddim 8 6 viewpoint 4 3 5 }\n"
                          "sphere s { material m center 4 3 -5 radius 1 }\n"
                          "material spare { ambient 1 }\n";
  Outcome check = run(kRayfarm + " check " + q(scene.string()) + " 2>&1");
  EXPECT_EQ(check.code, 1) << check.out;
  EXPECT_NE(check.out.find("huge.txt:2:1: error: camera 'c': the image has 4294836225 pixels"),
            std::string::npos)
      << check.out;
  EXPECT_NE(check.out.find(": 1 error, 1 warning\n"), std::string::npos) << check.out;
  // render stops with the same place, --quiet or not, and writes nothing.
  const fs::path out = dir / "huge.png";
  for (const std::string flags : {"", " -q"}) {
    Outcome r = run(kRayfarm + " render" + flags + " " + q(scene.string()) + " -o " +
                    q(out.string()) + " 2>&1");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("huge.txt:2:1: error: camera 'c'"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(out));
  }
  // The same view, smaller, renders: quietly with -q (the unused material not said), and
  // with its warning without.
  Outcome small = run(kRayfarm + " render -q " + q(scene.string()) +
                      " --width 80 --height 60 -o " + q(out.string()) + " 2>&1");
  EXPECT_EQ(small.code, 0) << small.out;
  EXPECT_EQ(small.out, "");
  EXPECT_TRUE(fs::exists(out));
  Outcome told = run(kRayfarm + " render " + q(scene.string()) + " --width 80 --height 60 -o " +
                     q(out.string()) + " 2>&1");
  EXPECT_EQ(told.code, 0) << told.out;
  EXPECT_NE(told.out.find("huge.txt:4:1: warning: "), std::string::npos) << told.out;
}

// Texture paths stay relative to the scene's folder: a scene converted into another folder
// says that its textures must follow it.
TEST(ConvertCli, AConvertedSceneElsewhereSaysWhereItsTexturesMustGo) {
  REQUIRE_CLIENT();
  const TempDir temp("cli-conv");
  const fs::path& dir = temp.path;
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/textures.txt");
  Outcome away = run(kRayfarm + " convert " + scene + " --to json -o " +
                     q((dir / "t.json").string()) + " 2>&1");
  EXPECT_EQ(away.code, 0) << away.out;
  EXPECT_NE(away.out.find("note: texture paths are relative to the scene's folder"),
            std::string::npos)
      << away.out;
  Outcome plain = run(kRayfarm + " convert " + q(RAYFARM_SOURCE_DIR "/scenes/cho.txt") +
                      " --to json -o " + q((dir / "c.json").string()) + " 2>&1");
  EXPECT_EQ(plain.code, 0);
  EXPECT_EQ(plain.out, "") << "no textures, no note";
}

// What a command cannot use is refused, not ignored: a queue class where nothing is queued,
// an empty camera name (not "the first"), standard input as both images.
TEST(Cli, OptionsACommandCannotUseAreRefused) {
  REQUIRE_CLIENT();
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/cho.txt");
  for (const auto& [command, says] : std::vector<std::pair<std::string, std::string>>{
           {" trace " + scene + " 1 1 --priority batch", "--priority: priority is a server's"},
           {" report " + scene + " --out /tmp/never --priority batch", "--priority"},
           {" render " + scene + " --camera '' -o /tmp/never.png", "--camera: must be a camera"},
           {" compare - - < /dev/null", "standard input is read once"}}) {
    Outcome r = run(kRayfarm + command + " 2>&1");
    EXPECT_EQ(r.code, 2) << command << r.out;
    EXPECT_NE(r.out.find(says), std::string::npos) << command << r.out;
  }
  EXPECT_FALSE(fs::exists("/tmp/never.png"));
}

// `-o "$OUT"` with OUT unset is a mistake to say, not a reason to write elsewhere.
TEST(Cli, AnEmptyFileNameIsRefused) {
  REQUIRE_CLIENT();
  const TempDir temp("cli-empty");
  const fs::path& dir = temp.path;
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt");
  for (const std::string& args : std::vector<std::string>{"render " + scene + " -o ''", "render ''", "convert " + scene + " --to json -o ''",
        "compare a.png b.png --diff ''", "check " + scene + " ''",
        "report " + scene + " --out ''", "trace '' 1 1"}) {
    Outcome r = run("cd " + q(dir.string()) + " && " + kRayfarm + " " + args + " 2>&1");
    EXPECT_EQ(r.code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find("a file name cannot be empty"), std::string::npos) << args << "\n" << r.out;
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "nothing is written under a default name";
}

// A memory limit (a grader's container, ulimit -v) is met with a message and exit 2, not
// an abort (exit 134), and no image is written.
TEST(RenderCli, RunningOutOfMemoryIsSaid) {
  REQUIRE_CLIENT();
  const TempDir dir("cli-oom");
  const fs::path out = dir.path / "big.png";
  Outcome r = run("ulimit -v 1000000; " + kRayfarm + " render " +
                  q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") + " -q --width 5792 --height 5792 " +
                  "--spp 2 -o " + q(out.string()) + " 2>&1");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_EQ(r.out.rfind("rayfarm: out of memory: ", 0), 0u) << r.out;
  EXPECT_FALSE(fs::exists(out));
}

TEST(ReportCli, TheSppLadderStopsBelowTheReference) {
  REQUIRE_CLIENT();
  const fs::path out =
      fs::temp_directory_path() / ("rayfarm-cli-report-" + std::to_string(getpid()));
  Outcome r = run(kRayfarm + " report " + q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") +
                  " -q --runs 1 --max-pixels 200 --reference-spp 16 --out " + q(out.string()) +
                  " 2>&1 >/dev/null");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(
      r.out.find("rayfarm: note: the spp ladder stops below --reference-spp 16: spp 1, 2, 4, 8\n"),
      std::string::npos)
      << r.out;
  std::ifstream csv(out / "report.csv");
  std::string header, line;
  std::getline(csv, header);
  const auto columns = [](const std::string& l) {
    std::vector<std::string> cells;
    std::stringstream ss(l);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    return cells;
  };
  const std::vector<std::string> names = columns(header);
  const size_t sweep = std::find(names.begin(), names.end(), "sweep") - names.begin();
  const size_t spp = std::find(names.begin(), names.end(), "spp") - names.begin();
  ASSERT_LT(spp, names.size()) << header;
  int spp_rows = 0;
  while (std::getline(csv, line)) {
    const auto cells = columns(line);
    if (sweep < names.size() && cells.at(sweep) != "spp") continue;
    ++spp_rows;
    EXPECT_LT(std::stoi(cells.at(spp)), 16) << line;
  }
  EXPECT_GT(spp_rows, 0);
  fs::remove_all(out);
  // A reference of 2 samples: the depth and bailout sweeps take 2, not 16 (their error would
  // be the reference's noise). The scene has no reflection: every row is the reference.
  Outcome two = run(kRayfarm + " report " + q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt") +
                    " -q --runs 1 --max-pixels 200 --reference-spp 2 --out " + q(out.string()) +
                    " 2>&1 >/dev/null");
  EXPECT_EQ(two.code, 0) << two.out;
  std::ifstream csv2(out / "report.csv");
  std::getline(csv2, header);
  const size_t rmse = std::find(names.begin(), names.end(), "rmse") - names.begin();
  ASSERT_LT(rmse, names.size()) << header;
  int swept = 0;
  while (std::getline(csv2, line)) {
    const auto cells = columns(line);
    if (cells.at(sweep) == "spp") continue;
    ++swept;
    EXPECT_EQ(cells.at(spp), "2") << line;
    EXPECT_EQ(std::stod(cells.at(rmse)), 0.0) << line;
  }
  EXPECT_GT(swept, 0);
  fs::remove_all(out);
}

// What the profile refuses is left out with a note, never written as a row of zeros; a
// reference it refuses is an error; and the output folder's parents must exist.
TEST(ReportCli, SettingsTheProfileRefusesAreLeftOutAndSaid) {
  REQUIRE_CLIENT();
  const fs::path out =
      fs::temp_directory_path() / ("rayfarm-cli-report-cpsc-" + std::to_string(getpid()));
  const std::string scene = q(RAYFARM_SOURCE_DIR "/scenes/cho.txt");
  // A quick report with `extra` options into `folder`: its exit code and standard error.
  const auto report = [&](const std::string& extra, const fs::path& folder) {
    return run(kRayfarm + " report " + scene + " -q --runs 1 --max-pixels 300 --reference-spp 4" +
               extra + " --out " + q(folder.string()) + " 2>&1 >/dev/null");
  };
  Outcome r = report(" --profile cpsc102", out);
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("rayfarm: note: spp sweep: left out where precision float is not "
                       "available in the cpsc102 profile"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("rayfarm: note: bailout sweep: left out where bailout is not available"),
            std::string::npos)
      << r.out;
  std::ifstream csv(out / "report.csv");
  std::string line;
  std::getline(csv, line);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    EXPECT_EQ(line.find(",float,"), std::string::npos) << line;
    EXPECT_NE(line.rfind("bailout,", 0), 0u) << line;
    EXPECT_EQ(line.find(",0.000,"), std::string::npos) << "a row that took no time: " << line;
  }
  EXPECT_GT(rows, 0);
  std::ifstream md(out / "report.md");
  const std::string text(std::istreambuf_iterator<char>(md), {});
  EXPECT_NE(text.find("- Note: bailout sweep: left out"), std::string::npos) << text;
  fs::remove_all(out);

  Outcome deep = report(" --profile cpsc102 --reference-depth 2000", out);
  EXPECT_EQ(deep.code, 2) << deep.out;
  EXPECT_NE(deep.out.find("rayfarm: error: the reference cannot be rendered: the cpsc102 "
                          "profile follows rays at most 1000 bounces deep"),
            std::string::npos)
      << deep.out;
  EXPECT_FALSE(fs::exists(out));

  Outcome raised = report(" --reference-depth 1", out);
  EXPECT_EQ(raised.code, 0) << raised.out;
  EXPECT_NE(raised.out.find("rayfarm: note: the reference's max_depth is 8, the renders' own, "
                            "not 1"),
            std::string::npos)
      << raised.out;
  fs::remove_all(out);

  const fs::path orphan = out / "no" / "such" / "folder";
  Outcome nowhere = report("", orphan);
  EXPECT_EQ(nowhere.code, 2) << nowhere.out;
  EXPECT_NE(nowhere.out.find("cannot write"), std::string::npos) << nowhere.out;
  EXPECT_FALSE(fs::exists(out));
  for (const char* flag : {" --precision float", " --bailout 0.2"}) {
    Outcome refused = report(flag, out);
    EXPECT_EQ(refused.code, 2) << flag << refused.out;
  }
}

TEST(RayfarmdCli, ABadValueFromTheEnvironmentNamesTheVariable) {
  if (!fs::exists(kRayfarmd)) GTEST_SKIP() << "no " << kRayfarmd << " in this build";
  Outcome env = run("RAYFARM_PORT=abc " + kRayfarmd + " 2>&1");
  EXPECT_EQ(env.code, 2);
  EXPECT_EQ(env.out.rfind(
                "rayfarmd: RAYFARM_PORT='abc' (from the environment) is not a valid --port: ", 0),
            0u)
      << env.out;
  // Given on the command line, it is the flag's error, whatever the environment says.
  Outcome flag = run("RAYFARM_PORT=abc " + kRayfarmd + " --port abc 2>&1");
  EXPECT_EQ(flag.code, 2);
  EXPECT_EQ(flag.out.find("RAYFARM_PORT"), std::string::npos) << flag.out;
}

// A real rayfarmd, started as its users start it, on a free loopback port; its access log in
// a file. Stopped with SIGTERM.
class Rayfarmd {
 public:
  explicit Rayfarmd(const std::string& flags) {
    static int count = 0;
    log_ = fs::temp_directory_path() / ("rayfarm-cli-rayfarmd-" + std::to_string(getpid()) + "-" +
                                        std::to_string(++count) + ".log");
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      const std::string command =
          "exec " + kRayfarmd + " --host 127.0.0.1 --port 0 --workers 2 " + flags;
      execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    const std::regex listening("listening on (http://127\\.0\\.0\\.1:\\d+)");
    for (int i = 0; i < 200 && url_.empty(); ++i) {
      std::smatch m;
      const std::string text = log();
      if (std::regex_search(text, m, listening))
        url_ = m[1];
      else
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  }
  ~Rayfarmd() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      waitpid(pid_, nullptr, 0);
    }
    fs::remove(log_);
  }
  const std::string& url() const { return url_; }
  std::string log() const {
    std::ifstream in(log_);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }
  // Requests of the access log for this path exactly ("GET /jobs/ID 200 ..."), waiting a
  // little for `at_least` of them: a streamed answer is logged once it has been sent.
  int requests(const std::string& method, const std::string& path, int at_least = 0) const {
    const std::string needle = " " + method + " " + path + " ";
    int n = 0;
    for (int tries = 0; tries < 40; ++tries) {
      const std::string text = log();
      n = 0;
      for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1))
        ++n;
      if (n >= at_least) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return n;
  }

 private:
  pid_t pid_ = -1;
  fs::path log_;
  std::string url_;
};

#define REQUIRE_SERVER() \
  REQUIRE_CLIENT();      \
  if (!fs::exists(kRayfarmd)) GTEST_SKIP() << "no " << kRayfarmd << " in this build"

class RemoteCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rayfarm-remote-cli-" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string out(const std::string& name) const { return q((dir_ / name).string()); }

  fs::path dir_;
  const std::string scene_ = q(RAYFARM_SOURCE_DIR "/scenes/minimal.txt");
};

TEST_F(RemoteCli, DetachPrintsTheIdThatJobsStatusAndWaitTakeUp) {
  REQUIRE_SERVER();
  Rayfarmd server("");
  ASSERT_FALSE(server.url().empty()) << server.log();
  const std::string at = " --server " + server.url();
  Outcome detached = run(kRayfarm + " render " + scene_ + " --spp 2 --detach" + at);
  ASSERT_EQ(detached.code, 0);
  ASSERT_TRUE(std::regex_match(detached.out, std::regex("[0-9a-f]{32}\n"))) << detached.out;
  const std::string id = detached.out.substr(0, 32);
  // Detached: submitted, nothing followed or fetched.
  EXPECT_EQ(server.requests("GET", "/jobs/" + id + "/events"), 0);
  EXPECT_EQ(server.requests("GET", "/jobs/" + id + "/image"), 0);

  Outcome jobs = run(kRayfarm + " jobs" + at);
  EXPECT_EQ(jobs.code, 0);
  EXPECT_EQ(jobs.out.rfind("ID", 0), 0u) << jobs.out;
  EXPECT_NE(jobs.out.find(id), std::string::npos) << jobs.out;
  EXPECT_NE(jobs.out.find("400x300"), std::string::npos) << jobs.out;

  Outcome waited = run(kRayfarm + " wait " + id + " -o " + out("w.png") + at + " 2>&1");
  EXPECT_EQ(waited.code, 0) << waited.out;
  EXPECT_TRUE(is_png(dir_ / "w.png"));
  EXPECT_NE(waited.out.find("w.png: 400x300, spp 2, "), std::string::npos) << waited.out;
  // The extension in any case names the encoding, as for render (".PPM" was PNG bytes).
  Outcome as_ppm = run(kRayfarm + " wait " + id + " -q -o " + out("w.PPM") + at + " 2>&1");
  EXPECT_EQ(as_ppm.code, 0) << as_ppm.out;
  std::ifstream ppm(dir_ / "w.PPM", std::ios::binary);
  std::string magic(2, '\0');
  ppm.read(magic.data(), 2);
  EXPECT_EQ(magic, "P6");

  Outcome status = run(kRayfarm + " status " + id + at);
  EXPECT_EQ(status.code, 0);
  EXPECT_NE(status.out.find("job       " + id + "\nstate     done"), std::string::npos)
      << status.out;
  EXPECT_NE(status.out.find("image     400x300, spp 2"), std::string::npos) << status.out;
  Json raw = Json::parse(run(kRayfarm + " status --json " + id + at).out);
  EXPECT_EQ(raw["id"], id);
  EXPECT_EQ(raw["state"], "done");
  Json listed = Json::parse(run(kRayfarm + " jobs --json" + at).out);
  EXPECT_EQ(listed["jobs"][0]["id"], id);

  // An ID the server does not know is the user's to fix.
  Outcome unknown = run(kRayfarm + " status " + std::string(32, '0') + at + " 2>&1");
  EXPECT_EQ(unknown.code, 2) << unknown.out;
}

TEST_F(RemoteCli, RenderFollowsTheEventStreamAndSaysWhenCached) {
  REQUIRE_SERVER();
  Rayfarmd server("");
  ASSERT_FALSE(server.url().empty()) << server.log();
  const std::string at = " --server " + server.url();
  Outcome first =
      run(kRayfarm + " render " + scene_ + " --spp 4 -o " + out("a.png") + at + " 2>&1");
  ASSERT_EQ(first.code, 0) << first.out;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(first.out, m, std::regex("rayfarm: job ([0-9a-f]{32}) on ")))
      << first.out;
  const std::string id = m[1];
  EXPECT_NE(first.out.find("a.png: 400x300, spp 4, "), std::string::npos) << first.out;
  EXPECT_NE(first.out.find("Mrays/s (job " + id + ")"), std::string::npos) << first.out;
  EXPECT_EQ(server.requests("GET", "/jobs/" + id + "/events", 1), 1) << server.log();
  EXPECT_EQ(server.requests("GET", "/jobs/" + id), 0) << server.log();  // no polling
  // The same render again comes from the server's cache, and says so.
  Outcome again =
      run(kRayfarm + " render " + scene_ + " --spp 4 -o " + out("b.png") + at + " 2>&1");
  ASSERT_EQ(again.code, 0) << again.out;
  EXPECT_NE(again.out.find("b.png: 400x300, spp 4, cached on " + server.url()), std::string::npos)
      << again.out;
}

TEST_F(RemoteCli, WithoutEventStreamsItPolls) {
  REQUIRE_SERVER();
  Rayfarmd server("--max-event-streams 0");
  ASSERT_FALSE(server.url().empty()) << server.log();
  Outcome r = run(kRayfarm + " render " + scene_ + " -o " + out("p.png") + " --server " +
                  server.url() + " 2>&1");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(is_png(dir_ / "p.png"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.out, m, std::regex("rayfarm: job ([0-9a-f]{32}) on "))) << r.out;
  EXPECT_GE(server.requests("GET", "/jobs/" + std::string(m[1]), 1), 1) << server.log();
}

TEST_F(RemoteCli, ExitCodesSayWhoseTroubleItIs) {
  REQUIRE_SERVER();
  Rayfarmd server("--token sesame --job-timeout 0.001");
  ASSERT_FALSE(server.url().empty()) << server.log();
  const std::string at = " --server " + server.url();
  // No token: the user's to fix, and the message says how.
  Outcome refused = run("RAYFARM_TOKEN= " + kRayfarm + " render " + scene_ + " -o " + out("x.png") +
                        at + " 2>&1");
  EXPECT_EQ(refused.code, 2) << refused.out;
  EXPECT_NE(refused.out.find("give your token with --token TOKEN or in RAYFARM_TOKEN"),
            std::string::npos)
      << refused.out;
  // A job that ran and failed (here: past the server's time limit) is a "no": 1.
  Outcome failed =
      run("RAYFARM_TOKEN=sesame " + kRayfarm + " render " +
          q(RAYFARM_SOURCE_DIR "/scenes/cho.txt") + " --spp 64 -o " + out("y.png") + at + " 2>&1");
  EXPECT_EQ(failed.code, 1) << failed.out;
  EXPECT_NE(failed.out.find(" failed: "), std::string::npos) << failed.out;
  EXPECT_FALSE(fs::exists(dir_ / "y.png"));
}

// The HTTP client is a module (client/http.h) found beside the program or in ../lib/rayfarm:
// without it a local render works and talking to a server says what is missing.
TEST_F(RemoteCli, TheHttpModuleIsNeededOnlyToTalkToAServer) {
  REQUIRE_CLIENT();
  const fs::path bin = dir_ / "bin", lib = dir_ / "lib" / "rayfarm";
  fs::create_directories(bin);
  fs::copy_file(kRayfarm, bin / "rayfarm");
  const std::string alone = q((bin / "rayfarm").string());
  Outcome local = run(alone + " render " + scene_ + " -q -o " + out("local.png") + " 2>&1");
  EXPECT_EQ(local.code, 0) << local.out;
  EXPECT_TRUE(is_png(dir_ / "local.png"));
  const std::string nowhere = " --server http://127.0.0.1:1 -o " + out("x.png") + " 2>&1";
  Outcome missing = run(alone + " render " + scene_ + nowhere);
  EXPECT_EQ(missing.code, 3) << missing.out;
  EXPECT_NE(missing.out.find("rayfarm-http.so is not installed"), std::string::npos) << missing.out;
  fs::create_directories(lib);
  fs::copy_file(RAYFARM_BINARY_DIR "/client/rayfarm-http.so", lib / "rayfarm-http.so");
  Outcome installed = run(alone + " render " + scene_ + nowhere);
  EXPECT_EQ(installed.code, 3) << installed.out;
  EXPECT_NE(installed.out.find("cannot connect"), std::string::npos) << installed.out;
}

// Answers a hostile or broken server might give, for the tests below.
const std::string kOkHead = "HTTP/1.1 200 OK\r\nConnection: close\r\n";

// Announces a body of 1 TiB and sends it until the client hangs up.
void endless_declared(rayfarm::test::HostileServer& s, int fd) {
  if (!s.send(fd, kOkHead + "Content-Type: application/json\r\nContent-Length: 1099511627776\r\n\r\n"))
    return;
  const std::string zeros(1 << 16, '0');
  while (s.send(fd, zeros)) {
  }
}

// A chunked body that never ends.
void endless_chunked(rayfarm::test::HostileServer& s, int fd) {
  if (!s.send(fd, kOkHead + "Transfer-Encoding: chunked\r\n\r\n")) return;
  const std::string chunk = "10000\r\n" + std::string(1 << 16, 'x') + "\r\n";
  while (s.send(fd, chunk)) {
  }
}

// The client's HTTP module itself, loaded as the program loads it, with a bound of 1 MiB:
// every method stops a body at the bound, whether announced or streamed, and keeps one of
// exactly that size, error statuses' bodies included.
TEST(HttpModule, ResponseBodiesStopAtTheBound) {
  REQUIRE_CLIENT();
  using namespace rayfarm::cli;
  void* module = dlopen(RAYFARM_BINARY_DIR "/client/rayfarm-http.so", RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(module, nullptr) << dlerror();
  auto factory = reinterpret_cast<HttpClientFactory>(dlsym(module, kHttpModuleEntry));
  ASSERT_NE(factory, nullptr);
  constexpr std::uint64_t kBound = 1 << 20;
  rayfarm::test::HostileServer server([&](rayfarm::test::HostileServer& s, int fd,
                                          const std::string& request) {
    const std::string path = request.substr(request.find(' ') + 1);
    if (path.rfind("/declared", 0) == 0) return endless_declared(s, fd);
    if (path.rfind("/chunked", 0) == 0) return endless_chunked(s, fd);
    const bool over = path.rfind("/over", 0) == 0;
    const std::string body(kBound + (over ? 1 : 0), 'b');
    const std::string status = path.rfind("/missing", 0) == 0 ? "404 Not Found" : "200 OK";
    s.send(fd, "HTTP/1.1 " + status + "\r\nConnection: close\r\nContent-Length: " +
                   std::to_string(body.size()) + "\r\n\r\n" + body);
  });
  ASSERT_FALSE(server.url().empty());
  HttpLimits limits;
  limits.max_body = kBound;
  limits.read = 10;
  std::unique_ptr<HttpClient> client(factory(server.url().c_str(), &limits));
  ASSERT_NE(client, nullptr);

  for (const char* path : {"/declared", "/chunked", "/over"}) {
    const auto start = std::chrono::steady_clock::now();
    HttpResult r = client->get(path, {});
    EXPECT_FALSE(r) << path;
    EXPECT_EQ(r.error(), HttpError::too_large) << path << ": " << r.why();
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(8)) << path;
  }
  EXPECT_EQ(client->post("/chunked", {}, "{}", "application/json").error(), HttpError::too_large);
  EXPECT_EQ(client->del("/declared", {}).error(), HttpError::too_large);
  EXPECT_EQ(client->post_multipart("/chunked", {}, {{"scene", "x", "scene", "text/plain"}}).error(),
            HttpError::too_large);

  HttpResult exact = client->get("/exact", {});
  ASSERT_TRUE(exact) << exact.why();
  EXPECT_EQ(exact->status, 200);
  EXPECT_EQ(exact->body, std::string(kBound, 'b'));
  HttpResult missing = client->get("/missing", {});
  ASSERT_TRUE(missing) << missing.why();
  EXPECT_EQ(missing->status, 404);
  EXPECT_EQ(missing->body.size(), kBound);
  client.reset();
  dlclose(module);
}

// The program against a server whose answers never end: a status and an image announced at
// 1 TiB, an event stream whose one event never ends (polling takes
// over and finds the job's end).
TEST_F(RemoteCli, AnswersThatNeverEndAreRefusedWithAReason) {
  REQUIRE_CLIENT();
  const std::string id(32, 'a');
  std::string state = "failed";
  std::mutex mutex;
  rayfarm::test::HostileServer server([&](rayfarm::test::HostileServer& s, int fd,
                                          const std::string& request) {
    const std::string path = request.substr(request.find(' ') + 1);
    if (path.rfind("/jobs/" + id + " ", 0) == 0) {
      std::string now;
      {
        std::lock_guard<std::mutex> lock(mutex);
        now = state;
      }
      if (now == "declared") return endless_declared(s, fd);
      const std::string body = R"({"id":")" + id + R"(","state":")" + now +
                               R"(","error":{"message":"scripted"}})";
      s.send(fd, kOkHead + "Content-Type: application/json\r\nContent-Length: " +
                     std::to_string(body.size()) + "\r\n\r\n" + body);
    } else if (path.rfind("/jobs/" + id + "/events", 0) == 0) {
      if (!s.send(fd, kOkHead + "Content-Type: text/event-stream\r\n\r\ndata: ")) return;
      const std::string more(1 << 16, 'x');
      while (s.send(fd, more)) {
      }
    } else if (path.rfind("/jobs/" + id + "/image", 0) == 0) {
      endless_declared(s, fd);  // streamed without end: HttpModule.ResponseBodiesStopAtTheBound
    }
  });
  ASSERT_FALSE(server.url().empty());
  const std::string at = " --server " + server.url() + " 2>&1";

  // The one event passes 1 MiB: the stream is dropped, and the status polled says "failed".
  Outcome waited = run(kRayfarm + " wait " + id + " -o " + out("w.png") + at);
  EXPECT_EQ(waited.code, 1) << waited.out;
  EXPECT_NE(waited.out.find("job " + id + " failed: scripted"), std::string::npos) << waited.out;

  // Done, with an image past 1 GiB: refused, and no file written.
  {
    std::lock_guard<std::mutex> lock(mutex);
    state = "done";
  }
  Outcome image = run(kRayfarm + " wait " + id + " -q -o " + out("i.png") + at);
  EXPECT_EQ(image.code, 3) << image.out;
  EXPECT_NE(image.out.find("fetching the image: the server's answer is larger than 1 GiB"),
            std::string::npos)
      << image.out;
  EXPECT_FALSE(fs::exists(dir_ / "i.png"));

  {
    std::lock_guard<std::mutex> lock(mutex);
    state = "declared";
  }
  Outcome status = run(kRayfarm + " status " + id + at);
  EXPECT_EQ(status.code, 3) << status.out;
  EXPECT_NE(status.out.find("job " + id + ": the server's answer is larger than 1 GiB"),
            std::string::npos)
      << status.out;
}

// A server whose answers have another shape than the API's: a field of the wrong type is the
// server's failure (exit 3), never a crash; an image that is not one is not saved.
TEST_F(RemoteCli, AnswersOfTheWrongShapeAreTheServersFailure) {
  REQUIRE_CLIENT();
  const std::string id(32, 'b');
  std::string status_body, image_body;
  std::mutex mutex;
  rayfarm::test::HostileServer server([&](rayfarm::test::HostileServer& s, int fd,
                                          const std::string& request) {
    const std::string path = request.substr(request.find(' ') + 1);
    std::string body, type = "application/json", status = "200 OK";
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (path.rfind("/jobs/" + id + "/image", 0) == 0) {
        body = image_body;
        type = "image/png";
      } else if (path.rfind("/jobs/" + id + "/events", 0) == 0) {
        status = "404 Not Found";
        body = R"({"error":{"code":"not_found","message":"no stream"}})";
      } else {
        body = status_body;
      }
    }
    s.send(fd, "HTTP/1.1 " + status + "\r\nConnection: close\r\nContent-Type: " + type +
                   "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
  });
  ASSERT_FALSE(server.url().empty());
  const std::string at = " --server " + server.url() + " 2>&1";
  auto serve = [&](const std::string& status_json, const std::string& image) {
    std::lock_guard<std::mutex> lock(mutex);
    status_body = status_json;
    image_body = image;
  };
  const std::string wait = " wait " + id + " -o " + out("s.png");
  for (const auto& [odd, commands] : std::vector<std::pair<std::string, std::vector<std::string>>>{
           {R"({"id":")" + id + R"(","state":7})", {" status " + id, wait}},
           {R"({"id":")" + id + R"(","state":"failed","error":{"message":42}})",
            {" status " + id, wait}},
           // (status shows no warning's line)
           {R"({"id":")" + id + R"(","state":"done","warnings":[{"message":"w","line":"one"}]})",
            {wait}}}) {
    serve(odd, "");
    for (const std::string& command : commands) {
      Outcome r = run(kRayfarm + command + at);
      EXPECT_EQ(r.code, 3) << odd << command << r.out;
      EXPECT_NE(r.out.find("the server's answer is not what rayfarm understands"),
                std::string::npos)
          << r.out;
    }
  }
  const std::string done = R"({"id":")" + id + R"(","state":"done","width":4,"height":3})";
  for (const std::string& image : {std::string("<html>oops</html>"), std::string(),
                                   std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16)}) {
    serve(done, image);
    Outcome r = run(kRayfarm + " wait " + id + " -o " + out("w.png") + at);
    EXPECT_EQ(r.code, 3) << r.out;
    EXPECT_NE(r.out.find("is not the image"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir_ / "w.png"));
  }
  // A PNG asked for as PPM is not the image either.
  serve(done, std::string("\x89PNG\r\n\x1a\n", 8) + std::string(20, '\0') +
                  std::string("\0\0\0\0IEND\xae\x42\x60\x82", 12));
  Outcome ppm = run(kRayfarm + " wait " + id + " -o " + out("w.ppm") + at);
  EXPECT_EQ(ppm.code, 3) << ppm.out;
  EXPECT_FALSE(fs::exists(dir_ / "w.ppm"));
  // A token that cannot go in a header line is refused before anything is sent.
  Outcome token =
      run(kRayfarm + " status " + id + " --token \"$(printf 'abc\\r\\nX-Injected: yes')\"" + at);
  EXPECT_EQ(token.code, 2) << token.out;
  EXPECT_NE(token.out.find("the token holds"), std::string::npos) << token.out;
}

// Ctrl-C while the server says nothing (an event stream kept open and silent): the job is
// canceled and the program ends with 130 within a moment, not at the read timeout.
TEST_F(RemoteCli, CtrlCEndsAFollowOnASilentServer) {
  REQUIRE_CLIENT();
  const std::string id(32, 'c');
  std::atomic<bool> deleted{false};
  rayfarm::test::HostileServer server([&](rayfarm::test::HostileServer& s, int fd,
                                          const std::string& request) {
    auto answer = [&](const std::string& status, const std::string& body) {
      s.send(fd, "HTTP/1.1 " + status + "\r\nConnection: close\r\nContent-Type: "
                 "application/json\r\nContent-Length: " + std::to_string(body.size()) +
                 "\r\n\r\n" + body);
    };
    if (request.rfind("POST /render", 0) == 0) {
      char drain[4096];  // the scene, so that closing sends no reset before the answer
      while (::recv(fd, drain, sizeof drain, MSG_DONTWAIT) > 0) {
      }
      answer("202 Accepted", R"({"id":")" + id + R"(","state":"queued"})");
    } else if (request.rfind("DELETE /jobs/" + id, 0) == 0) {
      deleted = true;
      answer("200 OK", R"({"id":")" + id + R"(","state":"canceled"})");
    } else if (request.find("/events") != std::string::npos) {
      if (!s.send(fd, "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\n\r\n")) return;
      std::ofstream(dir_ / "following");  // the program follows: Ctrl-C may come now
      for (int i = 0; i < 600 && !deleted; ++i)  // open and silent until the cancel
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  });
  ASSERT_FALSE(server.url().empty());
  const auto start = std::chrono::steady_clock::now();
  Outcome r = run("sh -c '" + kRayfarm + " render -q " + scene_ + " --server " + server.url() +
                  " -o " + out("c.png") + " & pid=$!; while [ ! -e " + out("following") +
                  " ]; do sleep 0.1; done; sleep 0.3; kill -INT $pid; wait $pid; "
                  "echo \\\"exit $?\\\"' 2>&1");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(15)) << r.out;
  EXPECT_NE(r.out.find("exit 130"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("interrupted; canceled job " + id), std::string::npos) << r.out;
  EXPECT_TRUE(deleted);
  EXPECT_FALSE(fs::exists(dir_ / "c.png"));
}

// docs/cli.md keeps up with --help: every option a command offers is in its section, and every
// render option in the table of render options.
TEST(DocsCli, EveryOptionOfEveryCommandIsDocumented) {
  REQUIRE_CLIENT();
  std::ifstream in(RAYFARM_SOURCE_DIR "/docs/cli.md");
  const std::string doc((std::istreambuf_iterator<char>(in)), {});
  ASSERT_FALSE(doc.empty());
  auto section = [&](const std::string& heading) {
    const size_t at = doc.find("\n## " + heading + "\n");
    if (at == std::string::npos) return std::string();
    return doc.substr(at, doc.find("\n## ", at + 1) - at);
  };
  const std::string render_options = section("Render options");
  ASSERT_FALSE(render_options.empty());
  const std::regex flag("--[a-z][a-z0-9_-]*");
  for (const char* command : {"render", "trace", "check", "convert", "compare", "grade", "report",
                              "status", "cancel", "wait", "jobs"}) {
    const std::string help = run(kRayfarm + " " + command + " --help").out;
    const std::string own = section("`rayfarm " + std::string(command) + "`");
    EXPECT_FALSE(own.empty()) << command;
    const size_t options = help.find("\nOptions:\n");
    const size_t render = help.find("\nRender options:\n");
    const size_t end = help.find("\nExamples:\n");
    ASSERT_NE(options, std::string::npos) << help;
    auto each_flag = [&](size_t from, size_t to, const std::string& where, const std::string& text) {
      const std::string part = help.substr(from, to - from);
      for (std::sregex_iterator it(part.begin(), part.end(), flag), e; it != e; ++it) {
        const std::string name = it->str();
        if (name == "--help" || name.find('_') != std::string::npos) continue;
        EXPECT_NE(text.find("`" + name), std::string::npos)
            << name << " of rayfarm " << command << " is not in " << where;
      }
    };
    each_flag(options, render != std::string::npos ? render : end,
              "the section of rayfarm " + std::string(command), own);
    if (render != std::string::npos) each_flag(render, end, "Render options", render_options);
  }
}

}  // namespace
