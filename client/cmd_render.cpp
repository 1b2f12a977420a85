// `rayfarm render SCENE [-o OUT] [options]`: renders locally on this machine's cores.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <mutex>
#include <unistd.h>

#include "cli_common.h"
#include "commands.h"
#include "large_pages.h"
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
  bool detach = false;
  OptionFlags flags;
};

std::string format_flag(const OptionFlags& flags) {
  auto it = flags.values.find("format");
  return it == flags.values.end() ? "" : it->second;
}

std::string default_output(const std::string& scene) {
  if (scene == "-") return "out.png";
  return std::filesystem::path(scene).filename().replace_extension(".png").string();
}

// --format, else the output's extension, else (standard output, a name without .png or .ppm)
// the scene's own render object's format, else PNG.
ImageFormat format_for(const std::string& out, const OptionFlags& flags,
                       ImageFormat scene_format = ImageFormat::png) {
  const auto given = flags.values.find("format");
  return output_format(out, given == flags.values.end() ? "" : given->second, scene_format);
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
  file_name(app.add_option("scene", args->scene, "scene file (model or JSON; - for stdin)"))
      ->required();
  auto* output = file_name(app.add_option(
      "-o,--output", args->out,
      "output image: .png or .ppm, - for standard output (default: SCENE's name with .png, here)"));
  int_range(app.add_option("--threads", args->threads, "render threads (default: all cores)"), 0,
            1024);
  app.add_flag("-q,--quiet", args->quiet, "no progress bar, warnings or summary line");
  auto* server = app.add_option(
      "--server", args->server,
      "render on this rayfarmd, http://HOST[:PORT] (default: $RAYFARM_SERVER; none or '': "
      "render here)");
  app.add_option("--token", args->token, "bearer token for the server (default: $RAYFARM_TOKEN)");
  app.add_flag("--detach", args->detach,
               "with a server: submit, print the job ID and return (then: rayfarm wait ID)");
  args->flags.add_to(app);
  app.footer(
      help_footer("  rayfarm render scenes/cho.txt                     # writes cho.png\n"
                  "  rayfarm render scenes/cho.txt -o aa.png --spp 16 --seed 3\n"
                  "  rayfarm render scenes/cho.txt -o - --format ppm > cho.ppm\n"
                  "  rayfarm render scenes/cameras.txt --camera above --width 400 --height 400\n"
                  "  rayfarm render scenes/cho.txt --server http://localhost:8080 -o cho.png\n"
                  "  id=$(rayfarm render scenes/cho.txt --server http://localhost:8080 --detach)\n",
                  "the server's job failed or was canceled", true));
  return [args, server, output]() -> int {
    const auto t0 = std::chrono::steady_clock::now();
    // `--server ''` renders here as `none` does, whatever RAYFARM_SERVER says.
    if (server->count() > 0 && args->server.empty()) args->server = "none";
    const std::string url = server_url(args->server);
    if (args->detach && url.empty()) {
      std::cerr << "rayfarm: --detach needs a server: give --server URL or set RAYFARM_SERVER\n";
      return kBadInput;
    }
    if (args->detach && (output->count() > 0 || !format_flag(args->flags).empty())) {
      std::cerr << "rayfarm: --detach saves no image: give -o (or --format) to rayfarm wait ID\n";
      return kBadInput;
    }
    // Reading the file and the general parser run on this thread alone (the reader of large
    // sphere files uses a second thread): meanwhile the other core faults in the heap's page
    // after next.
    large_pages::Warming warming;
    auto text = read_input(args->scene);
    if (!text) return kBadInput;
    std::string out_path = args->out.empty() ? default_output(args->scene) : args->out;
    if (!args->detach)
      for (const std::string& bad : {check_output(out_path, format_flag(args->flags)),
                                     check_not_input(out_path, {args->scene})})
        if (!bad.empty()) {
          std::cerr << "rayfarm: " << bad << "\n";
          return kBadInput;
        }
    if (!url.empty()) {
      for (const std::string& bad : {check_server_url(url), check_token(server_token(args->token))})
        if (!bad.empty()) {
          std::cerr << "rayfarm: " << bad << "\n";
          return kBadInput;
        }
      // Checked here, its textures read as a local render reads them: the server has no
      // access to this machine's files, so they are uploaded with the scene.
      const FileResolver files = FileResolver::beside(args->scene);
      const RecordingResolver textures(files);
      if (!load_checked(args->scene, *text, false, LoadDetail::scene, &textures)) return kBadInput;
      warming.stop();
      ImageFormat format = format_for(out_path, args->flags);
      return remote_render(args->scene, *text, textures.files(), out_path, args->flags.as_set(),
                           std::string(to_string(format)), Remote{url, server_token(args->token)},
                           args->quiet, args->detach);
    }
    auto loaded = load_checked(args->scene, *text, false);
    if (!loaded) return kBadInput;
    auto options = resolve_options(*loaded->scene, args->flags);
    if (!options) return kBadInput;
    const std::string& out = out_path;
    options->format = format_for(out, args->flags, options->format);
    {
      // What `check` would warn about (a sphere behind the eye, a light inside an object):
      // a black image with no word is the worst answer to such a scene. Its errors (an image
      // too large) are said with their place whatever --quiet says, and stop here.
      // (A camera the scene lacks is the render's error, said once, not also as a warning.)
      Diagnostics lints;
      if (loaded->scene->find_camera(options->camera)) {
        if (args->quiet)
          lint_image_size(*loaded->scene, *options, lints);
        else
          lint_scene(*loaded->scene, *options, lints, /*every_camera=*/false);
      }
      for (const Diagnostic& d : lints.items())
        std::cerr << format_diagnostic(d, display_name(args->scene), *text);
      if (lints.has_errors()) return kBadInput;
    }

    // Neither the text, its parsed description nor the scene's objects are read past this
    // point: freed (the text and description here, the objects once prepared), their memory
    // goes to the acceleration structures and the render's buffers instead of fresh pages,
    // which cost a large scene more than parsing it (docs/performance.md).
    std::string().swap(*text);
    loaded->desc = SceneDesc{};
    warming.stop();
    const bool show_progress = isatty(STDERR_FILENO) && !args->quiet;
    ProgressBar bar(show_progress);
    RenderStats stats;
    std::string error;
    // No bar, no callback: the render then does not gather its statistics after every tile,
    // under the job's lock that the render threads take turns at.
    std::function<void(const RenderStats&)> progress;
    if (show_progress) progress = [&bar](const RenderStats& s) { bar.update(s.progress(), s); };
    Image image = render_image(std::move(*loaded->scene), *options, args->threads, &stats,
                               progress, nullptr, &error);
    bar.finish();
    if (!error.empty()) {
      std::cerr << "rayfarm: error: " << error << "\n";
      return kBadInput;
    }
    auto bytes = encode_image(image, options->format);
    if (!write_output(out, bytes.data(), bytes.size())) return kBadInput;
    double total_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (!args->quiet) print_summary(out, image.width, image.height, stats, total_ms);
    return kOk;
  };
}

}  // namespace rayfarm::cli
