// `rayfarm report SCENE [--out DIR]`: error against run time (SPEC §7).
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/report.h"

namespace rayfarm::cli {
namespace {
struct ReportArgs {
  std::string scene;
  std::string out = "report";
  ReportSettings settings;
  bool quiet = false;
  OptionFlags flags;
};
}  // namespace

Runner add_report(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();
  app.add_option("scene", args->scene, "scene file")->required();
  app.add_option("--out", args->out, "directory for report.md, report.csv and report.svg")
      ->capture_default_str();
  app.add_option("--runs", args->settings.runs, "timed runs per setting (median)")
      ->check(CLI::Range(1, 100))->capture_default_str();
  app.add_option("--reference-spp", args->settings.reference_spp, "spp of the reference")
      ->check(CLI::Range(1, 1 << 16))->capture_default_str();
  app.add_option("--reference-depth", args->settings.reference_depth,
                 "max_depth of the reference")->check(CLI::Range(0, 100000))->capture_default_str();
  app.add_option("--max-pixels", args->settings.max_pixels,
                 "larger images are rendered smaller, same window")
      ->check(CLI::Range(1LL, 1LL << 26))->capture_default_str();
  app.add_option("--threads", args->settings.threads, "render threads (default: all cores)")
      ->check(CLI::Range(0, 1024));
  app.add_flag("-q,--quiet", args->quiet, "no progress bar");
  args->flags.add_to(app);
  return [args]() -> int {
    auto text = read_input(args->scene);
    if (!text) return kInputError;
    auto loaded = load_checked(args->scene, *text, false);
    if (!loaded) return kInputError;
    auto options = resolve_options(*loaded->scene, args->flags);
    if (!options) return kInputError;
    if (!loaded->scene->find_camera(options->camera)) {
      std::cerr << "rayfarm: error: no camera named '" << options->camera << "'\n";
      return kInputError;
    }
    const bool terminal = isatty(STDERR_FILENO) && !args->quiet;
    std::string name = std::filesystem::path(args->scene).filename().string();
    Report report = run_report(
        *loaded->scene, name, *options, args->settings,
        [&](int done, int total, const std::string& what) {
          if (args->quiet) return;
          constexpr int kWidth = 30;
          int filled = total > 0 ? done * kWidth / total : 0;
          std::string bar(filled, '#');
          bar.resize(kWidth, '.');
          if (terminal)
            std::fprintf(stderr, "\r[%s] %d/%d %-45.45s", bar.c_str(), done, total, what.c_str());
          else
            std::fprintf(stderr, "report: %d/%d %s\n", done, total, what.c_str());
          std::fflush(stderr);
        });
    if (terminal) std::fprintf(stderr, "\n");
    std::error_code ec;
    std::filesystem::create_directories(args->out, ec);
    if (ec) {
      std::cerr << "rayfarm: cannot create " << args->out << ": " << ec.message() << "\n";
      return kInputError;
    }
    namespace fs = std::filesystem;
    std::string md = report_markdown(report), csv = report_csv(report), svg = report_svg(report);
    if (!write_output((fs::path(args->out) / "report.md").string(), md.data(), md.size()) ||
        !write_output((fs::path(args->out) / "report.csv").string(), csv.data(), csv.size()) ||
        !write_output((fs::path(args->out) / "report.svg").string(), svg.data(), svg.size()))
      return kInputError;
    std::cout << md;
    std::cerr << "rayfarm: wrote " << args->out << "/report.md, report.csv, report.svg\n";
    return kOk;
  };
}

}  // namespace rayfarm::cli
