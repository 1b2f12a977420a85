// `rayfarm grade ASSIGNMENT (--images DIR | --run 'CMD {scene} {out}')`: renders each test's
// reference here (cached by content key), compares the student's image, and writes the
// platform's result file. Exit 0 whenever grading ran: the platforms read the file.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/grade.h"
#include "rayfarm/image_io.h"
#include "rayfarm/render.h"

namespace rayfarm::cli {
namespace {

namespace fs = std::filesystem;
using namespace rayfarm::grading;

struct GradeArgs {
  std::string assignment;
  std::string images;
  std::string run;
  std::string format = "md";
  std::string out = "-";
  std::string lock;
  std::string cache;
  bool no_cache = false;
  bool freeze = false;
  bool no_hints = false;
  double timeout = 60;
  double memory_mb = 2048;
  double fail_under = -1;
  int threads = 0;
};

constexpr size_t kLogTail = 2048;
constexpr rlim_t kMaxOutputBytes = 512ull << 20;

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The command with each placeholder replaced in one pass over it, so that a value (a scene's
// path holding "{name}") is never expanded again inside another's quotes.
std::string expand(const std::string& command,
                   const std::vector<std::pair<std::string, std::string>>& values) {
  std::string out;
  for (std::size_t i = 0; i < command.size();) {
    bool replaced = false;
    for (const auto& [key, value] : values)
      if (command.compare(i, key.size(), key) == 0) {
        out += value;
        i += key.size();
        replaced = true;
        break;
      }
    if (!replaced) out += command[i++];
  }
  return out;
}

fs::path default_cache() {
  if (const char* c = std::getenv("RAYFARM_CACHE"); c && *c) return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return fs::path(x) / "rayfarm/references";
  if (const char* h = std::getenv("HOME"); h && *h) return fs::path(h) / ".cache/rayfarm/references";
  return {};
}

// The result of running a student's program on one scene.
struct RunOutcome {
  bool started = false;
  bool timed_out = false;
  int status = 0;  // wait status
  std::string output;  // standard output (the image, when the command has no {out})
  std::string log;     // standard error, and standard output when it is not the image
  double seconds = 0;
};

// Runs `command` with /bin/sh in its own process group, under a CPU, memory and file-size
// limit, killing the whole group at the wall-clock limit. This is a resource fence, not a
// sandbox: the program runs as this user, sees this file system and network.
RunOutcome run_limited(const std::string& command, bool stdout_is_image, double timeout,
                       double memory_mb) {
  RunOutcome r;
  int out_pipe[2], err_pipe[2];
  if (pipe(out_pipe) != 0 || pipe(err_pipe) != 0) return r;
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) return r;
  if (pid == 0) {
    setpgid(0, 0);
    rlimit mem{static_cast<rlim_t>(memory_mb * 1024 * 1024), static_cast<rlim_t>(memory_mb * 1024 * 1024)};
    setrlimit(RLIMIT_AS, &mem);
    rlimit cpu{static_cast<rlim_t>(timeout) + 1, static_cast<rlim_t>(timeout) + 2};
    setrlimit(RLIMIT_CPU, &cpu);
    rlimit fsize{kMaxOutputBytes, kMaxOutputBytes};
    setrlimit(RLIMIT_FSIZE, &fsize);
    rlimit core{0, 0};
    setrlimit(RLIMIT_CORE, &core);
    int devnull = open("/dev/null", O_RDONLY);
    dup2(devnull, 0);
    dup2(out_pipe[1], 1);
    dup2(err_pipe[1], 2);
    close(out_pipe[0]);
    close(err_pipe[0]);
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid, pid);
  r.started = true;
  close(out_pipe[1]);
  close(err_pipe[1]);
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {stdout_is_image ? &r.output : &r.log, &r.log};
  int open_fds = 2;
  char buf[65536];
  bool reaped = false;
  // Reads until both pipes close, or the program has exited and left something holding them
  // (a background child): then what is already there is read, and the group is ended.
  while (open_fds > 0) {
    const double left =
        timeout - std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (left <= 0) {
      r.timed_out = true;
      break;
    }
    if (!reaped && waitpid(pid, &r.status, WNOHANG) == pid) reaped = true;
    const int wait_ms = reaped ? 50 : static_cast<int>(std::min(left, 0.2) * 1000) + 1;
    const int ready = poll(fds, 2, wait_ms);
    if (ready < 0 && errno != EINTR) break;
    if (ready == 0 && reaped) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || !(fds[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const ssize_t n = read(fds[i].fd, buf, sizeof buf);
      if (n <= 0) {
        close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
        continue;
      }
      std::string& sink = *sinks[i];
      if (sink.size() < kMaxOutputBytes) sink.append(buf, static_cast<size_t>(n));
      // Only the log's end is shown: keep it from growing without bound.
      if (&sink == &r.log && r.log.size() > 4 * kLogTail) r.log.erase(0, r.log.size() - kLogTail);
    }
  }
  // The whole group goes, including anything the program left running.
  kill(-pid, SIGKILL);
  for (pollfd& f : fds)
    if (f.fd >= 0) close(f.fd);
  if (!reaped) waitpid(pid, &r.status, 0);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

class LocalBackend final : public Backend {
 public:
  LocalBackend(const GradeArgs& args, fs::path base) : args_(args), base_(std::move(base)) {
    if (!args.no_cache) cache_ = args.cache.empty() ? default_cache() : fs::path(args.cache);
  }
  ~LocalBackend() override {
    std::error_code ec;
    if (!run_dir_.empty()) fs::remove_all(run_dir_, ec);
  }
  LocalBackend(const LocalBackend&) = delete;
  LocalBackend& operator=(const LocalBackend&) = delete;

  std::optional<SceneFiles> scene(const std::string& path, std::string* error) override {
    const fs::path file = base_ / path;
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) {
      *error = "scene '" + path + "' was not found beside the assignment (" + file.string() + ")";
      return std::nullopt;
    }
    std::string why;
    auto text = read_input(file.string(), &why);
    if (!text) {
      *error = "cannot read scene '" + path + "': " + why;
      return std::nullopt;
    }
    FileResolver textures = FileResolver::beside(file.string());
    textures.record_into(&textures_read_);
    return load_scene_files(path, *text, textures, file.string(), error);
  }

  // The texture files the scenes asked for (read or not): inputs the result may not be
  // written over.
  const std::vector<std::string>& textures_read() const { return textures_read_; }

  std::optional<Image> render(const SceneFiles& scene, const RenderOptions& options,
                              std::string* error) override {
    const std::string key = reference_key(scene, options);
    const fs::path cached = cache_.empty() ? fs::path() : cache_ / (key + ".png");
    std::error_code ec;
    std::string unread;  // a cached image that cannot be read is rendered again
    if (!cached.empty() && fs::is_regular_file(cached, ec))
      if (auto bytes = read_input(cached.string(), &unread))
        if (auto image = decode_image(*bytes, error)) return image;
    RenderStats stats;
    Image image = render_image(*scene.loaded->scene, options, args_.threads, &stats, {}, nullptr, error);
    if (image.width == 0) return std::nullopt;
    if (!cached.empty()) {
      fs::create_directories(cache_, ec);
      const auto png = encode_png(image);
      // A cache that cannot be written is no cache, not an error.
      const fs::path tmp = cached.string() + ".tmp" + std::to_string(getpid());
      if (FILE* f = std::fopen(tmp.c_str(), "wb")) {
        const bool ok = std::fwrite(png.data(), 1, png.size(), f) == png.size();
        if (std::fclose(f) == 0 && ok) fs::rename(tmp, cached, ec);
        else fs::remove(tmp, ec);
      }
    }
    return image;
  }

  // An image as the assignment names it: its path within the student's folder.
  std::string shown(const fs::path& file) const {
    return file.lexically_relative(args_.images).generic_string();
  }

  StudentImage student(const TestSpec& test, const SceneFiles* scene) override {
    if (!args_.run.empty()) return run(test, scene);
    StudentImage s;
    if (args_.images.empty()) {
      s.error = "no student images were given";
      return s;
    }
    fs::path file = fs::path(args_.images) / test.image;
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) {
      // The other of the two formats under the same name is graded, with a note.
      for (const std::string& name : other_image_names(test.image)) {
        const fs::path other = fs::path(args_.images) / name;
        if (fs::is_regular_file(other, ec)) {
          s.note = "graded " + name + ": no " + test.image + " was found";
          file = other;
          break;
        }
      }
    }
    if (!fs::is_regular_file(file, ec)) {
      s.error = "your image " + test.image +
                (fs::is_directory(file, ec) ? " is a folder, not an image file"
                 : fs::exists(file, ec)     ? " is not a regular file"
                 : fs::is_symlink(fs::symlink_status(file, ec))
                     ? " is a link to a file that does not exist"
                     : " was not found" + found_like(test.image));
      return s;
    }
    // Links within the folder are fine; one out of it could hand in any file this grader
    // can read (a cached reference among them).
    std::error_code folder_ec, real_ec;
    const fs::path folder = fs::canonical(args_.images, folder_ec);
    const fs::path real = fs::canonical(file, real_ec);
    const auto [stop, rest] = std::mismatch(folder.begin(), folder.end(), real.begin(), real.end());
    if (folder_ec || real_ec || stop != folder.end()) {
      s.error = "your image " + shown(file) + " is a link to a file outside your folder";
      return s;
    }
    std::string error;
    auto bytes = read_input(file.string(), &error);
    if (bytes) s.image = decode_image(*bytes, &error);
    if (!s.image) s.error = "your image " + shown(file) + " cannot be read: " + error;
    return s;
  }

 private:
  // "; a file named 'mirorr.png' is there" when a file of the image's folder has a name close
  // to it: a misnamed image is otherwise just missing.
  std::string found_like(const std::string& image) const {
    const fs::path wanted = fs::path(args_.images) / image;
    std::vector<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(wanted.parent_path(), ec), end; !ec && it != end && names.size() < 500;
         it.increment(ec))
      if (std::string name = it->path().filename().string(); name.size() <= 200) names.push_back(name);
    const std::vector<std::string_view> views(names.begin(), names.end());
    const std::string near = nearest_word(wanted.filename().string(), views);
    return near.empty() ? "" : "; a file named '" + near + "' is there";
  }

  StudentImage run(const TestSpec& test, const SceneFiles* scene) {
    StudentImage s;
    const bool to_file = args_.run.find("{out}") != std::string::npos;
    std::error_code ec;
    // A folder of this grade's own (mkdtemp: new, private), not a name another user could
    // have made, or linked elsewhere, beforehand; removed when the grade ends.
    if (run_dir_.empty()) {
      std::string templ = (fs::temp_directory_path() / "rayfarm-grade-XXXXXX").string();
      if (!::mkdtemp(templ.data())) {
        s.error = "the grader could not make a folder for your program's image";
        return s;
      }
      run_dir_ = templ;
    }
    const fs::path& dir = run_dir_;
    const fs::path out = dir / fs::path(test.image).filename();
    fs::remove(out, ec);
    const fs::path scene_path = fs::absolute(base_ / (scene ? scene->path : test.scene), ec);
    const std::string command = expand(args_.run, {{"{scene}", shell_quote(scene_path.string())},
                                                   {"{out}", shell_quote(out.string())},
                                                   {"{name}", shell_quote(test.name)}});
    RunOutcome r = run_limited(command, !to_file, args_.timeout, args_.memory_mb);
    s.log_tail = output_tail(r.log, kLogTail);
    if (!r.started) {
      s.error = "your program could not be started";
      return s;
    }
    char took[64];
    std::snprintf(took, sizeof took, "%.2f s", r.seconds);
    if (r.timed_out) {
      s.error = "your program ran past the time limit of " + format_number(args_.timeout) +
                " s and was stopped";
      return s;
    }
    if (WIFSIGNALED(r.status)) {
      const int sig = WTERMSIG(r.status);
      s.note = std::string("your program was killed by signal ") + std::to_string(sig) + " (" +
               strsignal(sig) + ")" + (sig == SIGXCPU ? ": CPU time limit" : "") + " after " + took;
    } else if (WEXITSTATUS(r.status) != 0) {
      s.note = "your program exited with status " + std::to_string(WEXITSTATUS(r.status)) +
               " after " + took;
    } else {
      s.note = std::string("your program ran in ") + took;
    }
    std::string bytes;
    if (to_file) {
      // A link would let the program hand in any file this grader can read (a cached
      // reference among them): the image must be a file of its own.
      // A hard link is a second name of a file that was there before the run.
      if (fs::is_symlink(fs::symlink_status(out, ec)) ||
          (fs::is_regular_file(out, ec) && fs::hard_link_count(out, ec) > 1)) {
        fs::remove(out, ec);
        s.error = "your program wrote a link, not an image (" + s.note + ")";
        return s;
      }
      if (!fs::is_regular_file(out, ec)) {
        s.error = "your program wrote no image (" + s.note + ")";
        return s;
      }
      std::string why;
      auto written = read_input(out.string(), &why);
      fs::remove(out, ec);
      if (!written) {
        s.error = "your program's image cannot be read: " + why + " (" + s.note + ")";
        return s;
      }
      bytes = std::move(*written);
    } else {
      bytes = std::move(r.output);
    }
    std::string error;
    s.image = decode_image(bytes, &error);
    if (!s.image) s.error = "your program's image cannot be read: " + error + " (" + s.note + ")";
    return s;
  }

  const GradeArgs& args_;
  fs::path base_;
  fs::path cache_;
  fs::path run_dir_;  // where --run programs write their images
  std::vector<std::string> textures_read_;
};

fs::path lock_path(const GradeArgs& args) {
  if (!args.lock.empty()) return args.lock;
  fs::path p = args.assignment;
  return p.replace_extension(".lock.json");
}

// Writes the result: always something the platform can read.
bool emit(const GradeArgs& args, const GradeResult& result, Format format) {
  const std::string text = write_result(result, format);
  if (args.out != "-") {
    std::error_code ec;
    const fs::path parent = fs::path(args.out).parent_path();
    if (!parent.empty()) fs::create_directories(parent, ec);  // PrairieLearn's results/
  }
  return write_output(args.out, text.data(), text.size());
}

// The score is below `percent` of the points: compared as products, so that 57 of 100 points
// is not below 57% (100 * 0.57 is 56.99999999999999).
bool below(const GradeResult& result, double percent) {
  if (result.max_score > 0) return 100 * result.score < percent * result.max_score;
  return 100 * result.fraction() < percent;
}

}  // namespace

void grade_command_line_refused(int argc, char** argv, const std::string& why) {
  GradeArgs args;
  for (int i = 2; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](const std::string& flag, std::string& into) {
      if (arg == flag && i + 1 < argc) {
        into = argv[++i];
        return true;
      }
      if (arg.rfind(flag + "=", 0) != 0) return false;
      into = arg.substr(flag.size() + 1);
      return true;
    };
    if (value("-o", args.out) || value("--output", args.out) || value("--format", args.format))
      continue;
    if (arg.size() > 2 && arg.rfind("-o", 0) == 0) args.out = arg.substr(2);  // -oFILE
  }
  if (args.out.empty() || args.out == "-") return;
  GradeResult result;
  set_grader_error(result, "the grader's command line is wrong: " + why);
  emit(args, result, parse_format(args.format).value_or(Format::md));
}

Runner add_grade(CLI::App& app) {
  auto args = std::make_shared<GradeArgs>();
  file_name(app.add_option("assignment", args->assignment, "the assignment file (JSON)"))->required();
  auto* images =
      file_name(app.add_option("--images", args->images, "folder of the student's images"));
  app.add_option("--run", args->run,
                 "run the student's program per test: {scene} is the scene's path, {out} the "
                 "image to write (without {out}, standard output is the image)")
      ->excludes(images);
  app.add_option("--format", args->format,
                 "gradescope, prairielearn, autolab, junit, json, html or md (default: md)");
  file_name(app.add_option("-o,--output", args->out,
                           "where to write the result (default: -, standard output)"));
  number_range(app.add_option("--timeout", args->timeout,
                              "seconds each run of the program may take (default: 60)"),
               0.1, 86400);
  number_range(
      app.add_option("--memory", args->memory_mb, "MiB of memory each run may map (default: 2048)"),
      16, 1e6);
  app.add_flag("--freeze", args->freeze,
               "render the references and write their hashes to the lock file");
  app.add_option("--lock", args->lock,
                 "the lock file (default: ASSIGNMENT with .lock.json); grading refuses "
                 "references that differ from it");
  file_name(app.add_option("--cache", args->cache, "folder of cached references"));
  app.add_flag("--no-cache", args->no_cache, "render every reference afresh");
  app.add_flag("--no-hints", args->no_hints, "compare only");
  number_range(app.add_option("--fail-under", args->fail_under,
                              "exit 1 when the score is below this percentage (default: never)"),
               0, 100);
  int_range(app.add_option("--threads", args->threads, "render threads (default: all cores)"), 0,
            1024);
  app.footer(help_footer(
      "  rayfarm grade scenes/assignments/lab1/lab1.json --freeze\n"
      "  rayfarm grade scenes/assignments/lab1/lab1.json --images "
      "scenes/assignments/lab1/students/ben\n"
      "  rayfarm grade lab1.json --run './raytrace {scene} > {out}' --format gradescope "
      "-o results.json\n"
      "  rayfarm grade lab1.json --images submission/ --fail-under 100   # pass/fail\n",
      "the score is below --fail-under (grading ran: the result is written)"));
  return [args]() -> int {
    const std::optional<Format> format = parse_format(args->format);
    if (!format) {
      std::cerr << "rayfarm: --format must be gradescope, prairielearn, autolab, junit, json, "
                   "html or md\n";
      return kBadInput;
    }
    GradeResult result;
    // Neither the result nor a lock may be written over what the grade reads: the assignment
    // and the lock it is checked against first (even a result saying "grader error" is written),
    // then its scenes and the student's images once it is read.
    const std::string lock_file = lock_path(*args).string();
    auto refused_output = [&](const std::vector<std::string>& inputs) {
      std::vector<std::pair<std::string, std::string>> outputs{{"-o", args->out}};
      if (args->freeze) outputs.emplace_back("--lock", lock_file);
      for (const auto& [flag, out] : outputs) {
        std::vector<std::string> read = inputs;
        if (!args->freeze) read.push_back(lock_file);  // read, to check the references
        if (std::string clash = check_not_input(out, read); !clash.empty()) {
          std::cerr << "rayfarm: " << flag << " " << clash << "\n";
          return true;
        }
      }
      return false;
    };
    if (refused_output({args->assignment})) return kBadInput;
    if (!args->freeze && args->images.empty() && args->run.empty()) {
      std::cerr << "rayfarm: give the student's images (--images DIR) or program (--run CMD)\n";
      set_grader_error(result, "the grader's command line is wrong: it names neither the "
                               "student's images (--images) nor their program (--run)");
      if (args->out != "-") emit(*args, result, *format);
      return kBadInput;
    }
    std::string why;
    auto text = read_input(args->assignment, &why);
    if (!text) {
      result.error = "cannot read the assignment: " + why;
      emit(*args, result, *format);
      return kBadInput;
    }
    Diagnostics diags;
    std::optional<Assignment> assignment = parse_assignment(*text, diags);
    if (!assignment) {
      std::cerr << format_diagnostics(diags, args->assignment, *text);
      // The platform shows only the result file: the error's place goes in with it.
      const Where& at = diags.first_error()->where;
      const std::string place = at.line > 0 ? "line " + std::to_string(at.line) + ", column " +
                                                  std::to_string(at.column) + ": "
                                : !at.path.empty() ? "at " + at.path + ": "
                                                   : "";
      result.error = "the assignment has errors: " + place + diags.first_error()->message;
      if (args->out != "-") emit(*args, result, *format);
      return kBadInput;
    }
    {
      const fs::path dir = fs::path(args->assignment).parent_path();
      std::vector<std::string> inputs{args->assignment};
      for (const TestSpec& t : assignment->tests) {
        inputs.push_back((dir / t.scene).string());
        if (!args->images.empty()) inputs.push_back((fs::path(args->images) / t.image).string());
      }
      if (refused_output(inputs)) return kBadInput;
    }
    std::error_code dir_ec;
    if (!args->images.empty() && !fs::is_directory(args->images, dir_ec)) {
      result.assignment = assignment->name;
      result.error = "the images folder " + args->images +
                     (fs::exists(args->images, dir_ec) ? " is not a folder" : " does not exist");
      std::cerr << "rayfarm: " << result.error << "\n";
      if (args->out != "-") emit(*args, result, *format);
      return kBadInput;
    }
    const fs::path base = fs::path(args->assignment).parent_path();
    LocalBackend backend(*args, base.empty() ? fs::path(".") : base);
    GradeSettings settings;
    settings.hints = !args->no_hints && !args->freeze;
    settings.threads = args->threads;
    const fs::path lock = lock_path(*args);
    std::error_code ec;
    // Once the references are had, before any student's image is read or program run: the
    // scenes' textures are known inputs now, and the lock is checked.
    bool clobbers_texture = false;
    std::function<std::string(const GradeResult&)> check_lock_file;
    if (!args->freeze && (!args->lock.empty() || fs::exists(lock, ec))) {
      // Graded against references that are not the frozen ones, the tests' feedback would
      // mislead, so the result says only why nothing was graded.
      check_lock_file = [&lock](const GradeResult& had) -> std::string {
        std::string unread;
        auto lock_text = read_input(lock.string(), &unread);
        if (!lock_text) {
          std::cerr << "rayfarm: the lock file cannot be read: " << unread << "\n";
          return "the references are not the ones in " + lock.string() +
                 ": the lock file cannot be read: " + unread;
        }
        std::vector<std::string> problems;
        std::string mismatch = lock_mismatch(had, *lock_text, lock.string(), &problems);
        for (const std::string& p : problems) std::cerr << "rayfarm: " << p << "\n";
        return mismatch;
      };
    }
    settings.check_references = [&](const GradeResult& had) -> std::string {
      if (refused_output(backend.textures_read())) {
        clobbers_texture = true;
        return "an output would be written over a texture";
      }
      return check_lock_file ? check_lock_file(had) : "";
    };
    result = grade(*assignment, backend, settings);
    if (clobbers_texture) return kBadInput;  // said; nothing is written

    // The platform shows the students a result; the grader's own trouble goes to its log.
    for (const TestResult& t : result.tests)
      if (t.status == "error") std::cerr << "rayfarm: test '" << t.name << "': " << t.message << "\n";
    if (args->freeze) {
      int errors = 0;
      for (const TestResult& t : result.tests)
        if (t.reference_sha256.empty()) {
          std::cerr << "rayfarm: test '" << t.name << "': " << t.message << "\n";
          ++errors;
        }
      if (errors) return kBadInput;
      const std::string body = lock_json(result).dump(2) + "\n";
      if (!write_output(lock.string(), body.data(), body.size())) return kBadInput;
      std::cerr << "rayfarm: froze " << result.tests.size() << " references in " << lock.string() << "\n";
      return kOk;
    }
    if (!emit(*args, result, *format)) return kBadInput;
    if (!result.error.empty()) return kBadInput;  // written for the platform, said above
    if (args->out != "-")
      std::cerr << "rayfarm: " << result.assignment << ": " << result.score << " / "
                << result.max_score << " points\n";
    if (args->fail_under >= 0 && below(result, args->fail_under)) return kNo;
    return kOk;
  };
}

}  // namespace rayfarm::cli
