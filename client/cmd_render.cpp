// `rayfarm render SCENE [-o OUT] [options]`: renders locally on this machine's cores.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <unistd.h>

#include "cli_common.h"
#include "commands.h"
#include "progress_bar.h"
#include "remote.h"
#include "rayfarm/image_io.h"
#include "rayfarm/lint.h"
#include "rayfarm/render.h"

namespace rayfarm::cli {
namespace {

struct RenderArgs {
  std::string scene;
  std::string out;
  int threads = 0;
  bool quiet = false;
  std::string server;
  std::string token;
  OptionFlags flags;
};

std::string default_output(const std::string& scene) {
  if (scene == "-") return "out.png";
  return std::filesystem::path(scene).filename().replace_extension(".png").string();
}

ImageFormat format_for(const std::string& out, const OptionFlags& flags) {
  if (flags.values.count("format")) return flags.values.at("format") == "ppm" ? ImageFormat::ppm
                                                                              : ImageFormat::png;
  std::string ext = std::filesystem::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".ppm" ? ImageFormat::ppm : ImageFormat::png;
}

// An output the user would not expect is refused before any work: a name whose extension
// says another format, or image bytes sent to a terminal.
std::string check_output(const std::string& out, const OptionFlags& flags) {
  if (out == "-") {
    if (isatty(STDOUT_FILENO))
      return "not writing image bytes to a terminal: redirect standard output (> out.png) or "
             "give -o FILE";
    return "";
  }
  std::string ext = std::filesystem::path(out).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext.empty()) return "";
  if (ext != ".png" && ext != ".ppm")
    return "'" + out + "': rayfarm writes PNG or PPM images; name the file .png or .ppm";
  if (auto it = flags.values.find("format"); it != flags.values.end() && "." + it->second != ext)
    return "'" + out + "' says " + ext.substr(1) + " but --format is " + it->second;
  return "";
}

// "6.79 Mrays/s", "1.2 k primary", "12 rays/s", "0 shadow".
std::string si(double v, const char* unit) {
  char buf[64];
  if (v >= 1e9) std::snprintf(buf, sizeof buf, "%.2f G%s", v / 1e9, unit);
  else if (v >= 1e6) std::snprintf(buf, sizeof buf, "%.2f M%s", v / 1e6, unit);
  else if (v >= 1e3) std::snprintf(buf, sizeof buf, "%.1f k%s", v / 1e3, unit);
  else std::snprintf(buf, sizeof buf, "%.0f%s%s", v, unit[0] == ' ' ? "" : " ", unit);
  return buf;
}

void print_summary(const std::string& out, int w, int h, const RenderStats& st, double total_ms) {
  double secs = st.render_ms / 1000;
  std::string parts;
  for (const std::string& p : st.parts) parts += (parts.empty() ? "" : ",") + p;
  std::fprintf(stderr, "%s: %dx%d, spp %d", out == "-" ? "<stdout>" : out.c_str(), w, h,
               st.spp_done);
  if (st.spp_done != st.spp_target) std::fprintf(stderr, "/%d (%s)", st.spp_target,
                                                 st.stop_reason.c_str());
  std::fprintf(stderr, ", %.1f ms (render %.1f ms), %s (%s, %s, %s)", total_ms, st.render_ms,
               si(secs > 0 ? st.total_rays() / secs : 0, "rays/s").c_str(),
               si(static_cast<double>(st.primary_rays), " primary").c_str(),
               si(static_cast<double>(st.shadow_rays), " shadow").c_str(),
               si(static_cast<double>(st.reflection_rays), " reflection").c_str());
  if (st.error_estimate >= 0) std::fprintf(stderr, ", error estimate %.3f levels", st.error_estimate);
  std::fprintf(stderr, "; parts: %s\n", parts.c_str());
}

}  // namespace

Runner add_render(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  app.add_option("scene", args->scene, "scene file (model or JSON; - for stdin)")->required();
  app.add_option("-o,--output", args->out,
                 "output image: .png or .ppm, - for standard output (default: SCENE.png)");
  app.add_option("--threads", args->threads, "render threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  app.add_flag("-q,--quiet", args->quiet, "no summary line");
  app.add_option("--server", args->server,
                 "render on this rayfarmd (default: $RAYFARM_SERVER; none: render here)");
  app.add_option("--token", args->token, "bearer token for the server (default: $RAYFARM_TOKEN)");
  args->flags.add_to(app);
  return [args]() -> int {
    const auto t0 = std::chrono::steady_clock::now();
    auto text = read_input(args->scene);
    if (!text) return kInputError;
    std::string out_path = args->out.empty() ? default_output(args->scene) : args->out;
    if (std::string bad = check_output(out_path, args->flags); !bad.empty()) {
      std::cerr << "rayfarm: " << bad << "\n";
      return kUsage;
    }
    if (std::string url = server_url(args->server); !url.empty()) {
      if (std::string bad = check_server_url(url); !bad.empty()) {
        std::cerr << "rayfarm: " << bad << "\n";
        return kUsage;
      }
      // Checked here, its textures read as a local render reads them: the server has no
      // access to this machine's files, so they are uploaded with the scene.
      const FileResolver files = FileResolver::beside(args->scene);
      const RecordingResolver textures(files);
      if (!load_checked(args->scene, *text, false, LoadDetail::scene, &textures))
        return kInputError;
      ImageFormat format = format_for(out_path, args->flags);
      return remote_render(args->scene, *text, textures.files(), out_path, args->flags.as_set(),
                           std::string(to_string(format)), Remote{url, server_token(args->token)},
                           args->quiet);
    }
    auto loaded = load_checked(args->scene, *text, false);
    if (!loaded) return kInputError;
    auto options = resolve_options(*loaded->scene, args->flags);
    if (!options) return kInputError;
    const std::string& out = out_path;
    options->format = format_for(out, args->flags);
    if (!args->quiet) {
      // What `check` would warn about (a sphere behind the eye, a light inside an object):
      // a black image with no word is the worst answer to such a scene.
      Diagnostics lints;
      lint_scene(*loaded->scene, *options, lints);
      for (const Diagnostic& d : lints.items()) std::cerr << format_diagnostic(d, display_name(args->scene), *text);
    }

    ProgressBar bar(isatty(STDERR_FILENO) && !args->quiet);
    RenderStats stats;
    std::string error;
    Image image = render_image(*loaded->scene, *options, args->threads, &stats,
                               [&bar](const RenderStats& s) { bar.update(s.progress(), s); },
                               nullptr, &error);
    bar.finish();
    if (!error.empty()) {
      std::cerr << "rayfarm: error: " << error << "\n";
      return kInputError;
    }
    auto bytes = encode_image(image, options->format);
    if (!write_output(out, bytes.data(), bytes.size())) return kInputError;
    double total_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!args->quiet) print_summary(out, image.width, image.height, stats, total_ms);
    return kOk;
  };
}

}  // namespace rayfarm::cli
