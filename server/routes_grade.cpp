// POST /grade: a student's images graded against an assignment, answered in a platform's
// format (docs/grading.md). The assignment is uploaded (part 'assignment', its scenes as parts
// named by the paths it writes, their textures by the paths the scenes write) or named
// (assignment=NAME, from rayfarmd --assignments-dir). The images are parts named as the
// tests name them. References render through the job queue (and its cache); the server
// never runs a student's program.
#include <filesystem>
#include <fstream>
#include <map>

#include "http_util.h"
#include "rayfarm/grade.h"
#include "rayfarm/image_io.h"
#include "routes.h"

namespace rayfarm::server {
namespace {

namespace fs = std::filesystem;
using httplib::Request;
using httplib::Response;
using namespace rayfarm::grading;

constexpr size_t kMaxTests = 64;

// Files by name: the request's parts, or a stored assignment's folder (never outside it).
class Files {
 public:
  virtual ~Files() = default;
  virtual std::optional<std::string> read(const std::string& path, std::string& error) const = 0;
};

class PartFiles final : public Files {
 public:
  explicit PartFiles(const Request& req) : req_(req) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    auto it = req_.files.find(path);
    if (it == req_.files.end()) {
      error = "it was not uploaded (send it as a multipart part named '" + path.substr(0, 200) + "')";
      return std::nullopt;
    }
    return it->second.content;
  }

 private:
  const Request& req_;
};

class FolderFiles final : public Files {
 public:
  explicit FolderFiles(fs::path root) : root_(fs::weakly_canonical(root)) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    std::error_code ec;
    const fs::path file = fs::weakly_canonical(root_ / path, ec);
    const std::string root = root_.string() + "/";
    if (ec || fs::path(path).is_absolute() || file.string().rfind(root, 0) != 0) {
      error = "'" + path.substr(0, 200) + "' is outside the assignment's folder";
      return std::nullopt;
    }
    std::ifstream in(file, std::ios::binary);
    if (!in || fs::is_directory(file, ec)) {
      error = "'" + path.substr(0, 200) + "' was not found in the assignment's folder";
      return std::nullopt;
    }
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

 private:
  fs::path root_;
};

// A scene's textures resolve against the scene's own folder, to the path relative to the
// assignment that names their part ("files/texplane/../images/b.ppm" is "files/images/b.ppm");
// Files checks that it stays inside.
class SceneTextures final : public ResourceResolver {
 public:
  SceneTextures(const Files& files, std::string folder, long long max_pixels)
      : files_(files), folder_(std::move(folder)), max_pixels_(max_pixels) {}
  std::optional<std::string> read(const std::string& path, std::string& error) const override {
    const fs::path joined = folder_.empty() ? fs::path(path) : fs::path(folder_) / path;
    const std::string name = joined.lexically_normal().generic_string();
    if (joined.is_absolute() || name == ".." || name.rfind("../", 0) == 0) {
      error = "'" + path.substr(0, 200) + "' is outside the assignment's folder";
      return std::nullopt;
    }
    return files_.read(name, error);
  }
  long long max_pixels() const override { return max_pixels_; }

 private:
  const Files& files_;
  std::string folder_;
  long long max_pixels_;
};

class ServerBackend final : public Backend {
 public:
  ServerBackend(Service& svc, const Slot& slot, const Request& req, const Files& scenes)
      : svc_(svc), slot_(slot), req_(req), scenes_(scenes), client_(client_of(req)) {}

  std::optional<SceneFiles> scene(const std::string& path, std::string* error) override {
    std::string why;
    auto text = scenes_.read(path, why);
    if (!text) {
      *error = "scene '" + path.substr(0, 200) + "': " + why;
      return std::nullopt;
    }
    const size_t slash = path.find_last_of('/');
    const SceneTextures textures(scenes_, slash == std::string::npos ? "" : path.substr(0, slash),
                                 svc_.settings().max_pixels);
    const LoadGate::Pass pass = svc_.enter_load(text->size());
    return load_scene_files(path, *text, textures, path, error);
  }

  std::optional<Image> render(const SceneFiles& scene, const RenderOptions& options,
                              std::string* error) override {
    Params params;
    for (auto& [k, v] : option_pairs(options))
      if (k != "format") params.emplace_back(k, v);
    ApiError e;
    auto image =
        render_and_wait(svc_, slot_, scene.text, params, client_, scene.textures, {}, e, nullptr);
    if (!image) *error = e.message;
    return image;
  }

  StudentImage student(const TestSpec& test, const SceneFiles*) override {
    StudentImage s;
    std::string name = test.image;
    auto it = req_.files.find(name);
    // As the command line grades a folder: the other format under the same name, said so.
    for (const std::string& other : other_image_names(test.image)) {
      if (it != req_.files.end()) break;
      it = req_.files.find(other);
      if (it != req_.files.end()) {
        name = other;
        s.note = "graded " + other + ": no " + test.image + " was uploaded";
      }
    }
    if (it == req_.files.end()) {
      s.error = "your image " + test.image + " was not uploaded" + uploaded_like(test.image);
      return s;
    }
    std::string error;
    s.image = decode_image(it->second.content, &error, svc_.settings().max_pixels);
    if (!s.image) s.error = "your image " + name + " cannot be read: " + error;
    return s;
  }

 private:
  // "; a part named 'spheres.jpg' was" when one of the uploaded parts' names is close: a
  // misnamed image is otherwise just missing.
  std::string uploaded_like(const std::string& image) const {
    std::vector<std::string_view> names;
    for (const auto& [name, part] : req_.files)
      if (name != "assignment" && name.size() <= 200 && names.size() < 200) names.push_back(name);
    const std::string near = nearest_word(image, names);
    return near.empty() ? "" : "; a part named '" + near.substr(0, 200) + "' was";
  }

  Service& svc_;
  const Slot& slot_;
  const Request& req_;
  const Files& scenes_;
  std::string client_;
};

const char* content_type(Format f) {
  switch (f) {
    case Format::junit: return "application/xml";
    case Format::html: return "text/html; charset=utf-8";
    case Format::md: return "text/markdown; charset=utf-8";
    case Format::autolab: return "text/plain; charset=utf-8";
    default: return "application/json";
  }
}

bool plain_name(const std::string& name) {
  if (name.empty() || name.size() > 100 || name.front() == '.') return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') return false;
  return true;
}

}  // namespace

void post_grade(Service& svc, const Request& req, Response& res) {
  std::string repeated;
  const std::map<std::string, std::string> fields =
      request_fields(req, {"format", "assignment", "hints"}, &repeated);
  if (!repeated.empty()) {
    ApiError e = api_error(400, "invalid_option",
                           "'" + repeated + "' is given more than once; give it once");
    e.path = repeated;
    return send_error(res, e);
  }
  for (const auto& [k, v] : req.params)
    if (k != "format" && k != "assignment" && k != "hints") {
      ApiError e = api_error(400, "invalid_option",
                             "unknown option '" + k.substr(0, 64) + "': /grade takes format, "
                             "assignment and hints (render options belong in the assignment)");
      e.path = k.substr(0, 64);
      return send_error(res, e);
    }
  bool hints = true;
  if (auto it = fields.find("hints"); it != fields.end()) {
    const std::optional<bool> on = yes_no(it->second);
    if (!on) return send_error(res, not_yes_no("hints", it->second));
    hints = *on;
  }
  // One part per name: which of two images would be graded is no one's guess to make.
  for (auto it = req.files.begin(); it != req.files.end(); it = req.files.upper_bound(it->first))
    if (req.files.count(it->first) > 1) {
      ApiError e = api_error(400, "duplicate_part",
                             "part '" + it->first.substr(0, 200) + "' is sent more than once");
      e.path = it->first.substr(0, 200);
      return send_error(res, e);
    }
  Format format = Format::json;
  if (auto it = fields.find("format"); it != fields.end()) {
    auto f = parse_format(it->second);
    if (!f) {
      ApiError e = api_error(400, "invalid_option",
                             "format must be gradescope, prairielearn, autolab, junit, json, html "
                             "or md, got '" + it->second.substr(0, 32) + "'");
      e.path = "format";
      return send_error(res, e);
    }
    format = *f;
  }
  if (!req.is_multipart_form_data())
    return send_error(res, 400, "bad_request",
                      "send multipart form data: the student's images as parts named as the "
                      "assignment's tests name them, and the assignment (part 'assignment', or "
                      "assignment=NAME for one stored on the server)");
  std::string text;
  std::unique_ptr<Files> files;
  std::optional<std::string> lock;  // a stored assignment's lock, when it has one
  std::string lock_name;
  // An uploaded assignment is a file part, or a field holding JSON (curl -F 'assignment=<x');
  // a field holding a plain name names a stored one.
  const auto uploaded = req.files.find("assignment");
  const auto is_json = [](const std::string& v) {
    const size_t first = v.find_first_not_of(" \t\r\n");
    return first != std::string::npos && v[first] == '{';
  };
  if (uploaded != req.files.end() &&
      (!uploaded->second.filename.empty() || is_json(uploaded->second.content))) {
    // An uploaded one and a stored one named in the query: which was meant?
    if (req.has_param("assignment")) {
      ApiError e = api_error(400, "invalid_option",
                             "'assignment' is given twice: as an uploaded part and as "
                             "assignment=NAME in the query; give one");
      e.path = "assignment";
      return send_error(res, e);
    }
    text = uploaded->second.content;
    files = std::make_unique<PartFiles>(req);
  } else if (auto named = fields.find("assignment"); named != fields.end()) {
    const std::string& name = named->second;
    const std::string& dir = svc.settings().assignments_dir;
    if (dir.empty())
      return send_error(res, 404, "unknown_assignment",
                        "this server stores no assignments (rayfarmd --assignments-dir)");
    std::string error;
    FolderFiles folder(dir);
    // (NAME.lock.json beside NAME.json is its lock, not an assignment of its own.)
    const bool a_lock = name.size() >= 5 && name.compare(name.size() - 5, 5, ".lock") == 0;
    std::optional<std::string> stored =
        plain_name(name) && !a_lock ? folder.read(name + ".json", error) : std::nullopt;
    if (!stored)
      return send_error(res, 404, "unknown_assignment",
                        "no assignment named '" + name.substr(0, 64) + "' on this server");
    text = *stored;
    files = std::make_unique<FolderFiles>(dir);
    // A stored assignment frozen with `rayfarm grade --freeze` is checked against its lock,
    // as the command line checks it: references that differ grade nothing.
    std::string no_lock;
    lock = folder.read(name + ".lock.json", no_lock);
    lock_name = name + ".lock.json";
  } else {
    return send_error(res, 400, "bad_request",
                      "upload the assignment as a file part named 'assignment', or name a "
                      "stored one with assignment=NAME");
  }
  Diagnostics diags;
  std::optional<Assignment> assignment = parse_assignment(text, diags);
  if (!assignment) {
    const Diagnostic* d = diags.first_error();
    ApiError e = api_error(400, "invalid_assignment", d->message);
    e.path = d->where.path;
    if (d->where.line > 0) {  // a syntax error: placed as a scene's are, and in the message
      e.line = d->where.line;
      e.column = d->where.column;
      e.message = "line " + std::to_string(d->where.line) + ", column " +
                  std::to_string(d->where.column) + ": " + d->message;
    }
    return send_error(res, e);
  }
  if (assignment->tests.size() > kMaxTests)
    return send_error(res, 413, "too_many_tests",
                      "the assignment has " + std::to_string(assignment->tests.size()) +
                          " tests; at most " + std::to_string(kMaxTests) + " are graded at once");
  // Grading waits for its references: one waiting slot for the whole request.
  auto slot = svc.take_slot(Slot::Kind::waiting);
  if (!slot) {
    ApiError e = api_error(503, "busy", "too many requests are waiting for renders; try again");
    e.retry_after = 2;
    return send_error(res, e);
  }
  ServerBackend backend(svc, *slot, req, *files);
  GradeSettings settings;
  settings.base.profile = svc.settings().default_profile;
  settings.hints = hints;
  settings.threads = 1;  // the hints' per-pixel record runs on this request's thread only
  if (lock) {
    settings.check_references = [&lock, &lock_name](const GradeResult& had) {
      return lock_mismatch(had, *lock, lock_name);
    };
  }
  GradeResult result = grade(*assignment, backend, settings);
  res.status = 200;
  res.set_content(write_result(result, format), content_type(format));
}

}  // namespace rayfarm::server
