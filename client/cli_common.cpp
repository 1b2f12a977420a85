// Command-line helpers.
#include "cli_common.h"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <unistd.h>

namespace rayfarm::cli {

std::string display_name(const std::string& path) { return path == "-" ? "<stdin>" : path; }

std::optional<std::string> read_input(const std::string& path, std::string* why,
                                      std::uintmax_t limit) {
  auto fail = [&](const std::string& reason) -> std::optional<std::string> {
    if (why) *why = reason;
    else std::cerr << "rayfarm: " << reason << "\n";
    return std::nullopt;
  };
  std::string text;
  if (path == "-") {
    if (!read_bounded(std::cin, {}, limit, text))
      return fail(display_name(path) + ": " + too_large(limit));
    return text;
  }
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return fail(path + ": is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int err = errno;  // before anything else can set it
    return fail("cannot open " + path + ": " + std::strerror(err));
  }
  if (!read_bounded(in, path, limit, text)) return fail(path + ": " + too_large(limit));
  return text;
}

namespace {

// Writes all of `data` to an open stream and closes it; errno's words when that fails.
std::string write_and_close(std::FILE* f, const void* data, size_t size) {
  const bool written = std::fwrite(data, 1, size, f) == size && std::fflush(f) == 0;
  const int err = errno;
  const bool closed = std::fclose(f) == 0;
  if (written && closed) return "";
  return std::strerror(written ? errno : err);
}

// Set once write_output has said that standard output could not be written.
bool stdout_failed = false;

}  // namespace

bool stdout_failure_said() { return stdout_failed; }

bool write_output(const std::string& path, const void* data, size_t size) {
  namespace fs = std::filesystem;
  auto fail = [&](const std::string& why) {
    std::cerr << "rayfarm: cannot write " << (path == "-" ? "to standard output" : path) << ": "
              << why << "\n";
    return false;
  };
  if (path == "-") {
    const bool ok = std::fwrite(data, 1, size, stdout) == size && std::fflush(stdout) == 0;
    stdout_failed = !ok;
    return ok || fail(std::strerror(errno));
  }
  std::error_code ec;
  const fs::file_status target = fs::status(path, ec);  // through symbolic links
  const bool link = fs::is_symlink(fs::symlink_status(path, ec));
  if (fs::is_directory(target)) return fail("it is a directory");
  // A device, a pipe or a socket (/dev/null, /dev/stdout, a FIFO), or a link to nothing yet:
  // written where it is, as a shell's redirection would. Replacing it with a file (as the
  // atomic write below does) would take /dev/null from everyone else on the machine.
  if ((fs::exists(target) && !fs::is_regular_file(target)) || (link && !fs::exists(target))) {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) return fail(std::strerror(errno));
    const std::string why = write_and_close(f, data, size);
    return why.empty() || fail(why);
  }
  // A file: written beside itself and renamed over it, so that no reader ever sees half an
  // image. Through a link, beside and over what it names (the link stays), and with the
  // permissions the file had.
  fs::path file = path;
  if (link) {
    file = fs::canonical(path, ec);
    if (ec) return fail(ec.message());
  }
  const fs::path tmp = file.string() + ".tmp" + std::to_string(::getpid());
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return fail(std::strerror(errno));
  if (const std::string why = write_and_close(f, data, size); !why.empty()) {
    fs::remove(tmp, ec);
    return fail(why);
  }
  if (fs::exists(target)) fs::permissions(tmp, target.permissions(), ec);
  fs::rename(tmp, file, ec);
  if (ec) {
    const std::string why = ec.message();
    fs::remove(tmp, ec);
    return fail(why);
  }
  return true;
}

namespace {

// ".ppm" for "x.PPM"; empty without one.
std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

ImageFormat output_format(const std::string& out, const std::string& format, ImageFormat otherwise) {
  if (!format.empty()) return format == "ppm" ? ImageFormat::ppm : ImageFormat::png;
  const std::string ext = lower_extension(out);
  return ext == ".ppm" ? ImageFormat::ppm : ext == ".png" ? ImageFormat::png : otherwise;
}

std::string check_not_input(const std::string& out, const std::vector<std::string>& inputs) {
  if (out == "-") return "";
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (in != "-" && std::filesystem::equivalent(out, in, ec) && !ec)
      return "'" + out + "' is the input " + in + " itself: writing it would lose that file; " +
             "give the output another name";
  }
  return "";
}

std::string check_output(const std::string& out, const std::string& format) {
  if (out == "-") {
    if (isatty(STDOUT_FILENO))
      return "not writing image bytes to a terminal: redirect standard output (> out.png) or "
             "give -o FILE";
    return "";
  }
  const std::string ext = lower_extension(out);
  if (ext.empty()) return "";
  if (ext != ".png" && ext != ".ppm")
    return "'" + out + "': rayfarm writes PNG or PPM images; name the file .png or .ppm";
  if (!format.empty() && "." + format != ext)
    return "'" + out + "' says " + ext.substr(1) + " but --format is " + format;
  return "";
}

void OptionFlags::add_to(CLI::App& app, const std::map<std::string, std::string>& refused) {
  const RenderOptions defaults;
  for (const OptionSpec& spec : option_specs()) {
    std::string name(spec.name);
    std::string dashed = name;
    for (char& c : dashed)
      if (c == '_') c = '-';
    std::string flags = "--" + dashed + (dashed != name ? ",--" + name : "");
    if (auto why = refused.find(name); why != refused.end()) {
      // Not in the help; said when given, rather than silently ignored.
      app.add_option_function<std::string>(flags,
                                           [dashed, why = why->second](const std::string&) {
                                             throw CLI::ValidationError("--" + dashed, why);
                                           })
          ->group("");
      continue;
    }
    std::string help(spec.help);
    if (help.find("default") == std::string::npos) {
      std::string value = spec.print(defaults);
      if (name == "format") value = "by the output's extension, else png";
      if (name == "target_error" || name == "time_limit") value += " = off";
      help += " (default: " + value + ")";
    }
    app.add_option_function<std::string>(
           flags,
           [this, name, dashed](const std::string& v) {
             // A value the option cannot take is a usage error (exit 2), said at once.
             RenderOptions probe;
             if (auto bad = apply_option(probe, name, v))
               throw CLI::ValidationError("--" + dashed, *bad);
             // ("" is how the default prints; given, it names no camera: "$CAM" unset)
             if (name == "camera" && v.empty())
               throw CLI::ValidationError("--camera", "must be a camera name (leave --camera "
                                                      "out for the scene's first)");
             values[name] = v;
           },
           help)
        ->type_name(std::string(spec.value_help))
        ->group("Render options");
  }
}

OptionSet OptionFlags::as_set() const {
  OptionSet set;
  for (const OptionSpec& spec : option_specs()) {
    auto it = values.find(std::string(spec.name));
    if (it != values.end()) set.push_back({it->first, it->second, {0, 0, "--" + it->first}});
  }
  return set;
}

std::optional<std::string> FileResolver::read(const std::string& path, std::string& error) const {
  const std::filesystem::path file = std::filesystem::path(path).is_absolute()
                                         ? std::filesystem::path(path)
                                         : base_ / path;
  if (seen_) seen_->push_back(file.string());
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    error = file.string() + " is a directory";
    return std::nullopt;
  }
  // Opening a pipe waits for a writer, for ever if none comes, and a device (/dev/zero) reads
  // a gigabyte before its bytes are seen to be no image: a texture is a file.
  if (std::filesystem::is_fifo(file, ec) || std::filesystem::is_socket(file, ec)) {
    error = file.string() + " is a pipe, not a file";
    return std::nullopt;
  }
  if (std::filesystem::is_character_file(file, ec) || std::filesystem::is_block_file(file, ec)) {
    error = file.string() + " is a device, not a file";
    return std::nullopt;
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    const int err = errno;
    error = file.string() + ": " + std::strerror(err);
    return std::nullopt;
  }
  std::string bytes;
  if (!read_bounded(in, file, kMaxInputBytes, bytes)) {
    error = file.string() + ": " + too_large(kMaxInputBytes);
    return std::nullopt;
  }
  return bytes;
}

FileResolver FileResolver::beside(const std::string& scene_path) {
  return FileResolver(scene_path == "-" ? std::filesystem::path(".")
                                        : std::filesystem::path(scene_path).parent_path());
}

std::optional<LoadedScene> load_checked(const std::string& path, const std::string& text,
                                        bool print_warnings, LoadDetail detail, bool textures) {
  const FileResolver files = FileResolver::beside(path);
  return load_checked(path, text, print_warnings, detail, textures ? &files : nullptr);
}

std::optional<LoadedScene> load_checked(const std::string& path, const std::string& text,
                                        bool print_warnings, LoadDetail detail,
                                        const ResourceResolver* textures) {
  LoadedScene loaded = load_scene(text, detail, textures);
  for (const Diagnostic& d : loaded.diags.items())
    if (d.severity == Severity::error || print_warnings)
      std::cerr << format_diagnostic(d, display_name(path), text);
  if (loaded.diags.truncated())
    std::cerr << display_name(path) << ": note: too many errors (" << loaded.diags.error_count_text()
              << "); only the first " << Diagnostics::kMaxErrors << " are shown\n";
  if (loaded.diags.has_errors() || !loaded.scene) return std::nullopt;
  return loaded;
}

std::optional<RenderOptions> resolve_options(const Scene& scene, const OptionFlags& flags) {
  RenderOptions options;
  Diagnostics diags;
  apply_options(options, scene.render, diags);
  apply_options(options, flags.as_set(), diags);
  if (!diags.has_errors())
    if (std::string conflict = profile_conflict(options); !conflict.empty())
      diags.error("bad-option", conflict, {});
  for (const Diagnostic& d : diags.items())
    std::cerr << "rayfarm: error: " << (d.where.path.empty() ? "" : d.where.path + ": ")
              << d.message << "\n";
  if (diags.has_errors()) return std::nullopt;
  return options;
}

}  // namespace rayfarm::cli
