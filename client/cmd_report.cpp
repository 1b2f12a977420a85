// `rayfarm report SCENE [--out DIR]`: error against run time (docs/numerics.md).
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
  file_name(app.add_option("scene", args->scene, "scene file"))->required();
  const ReportSettings& d = args->settings;  // the defaults, for the help
  file_name(app.add_option("--out", args->out,
                           "directory for report.md, report.csv and report.svg (default: report)"));
  int_range(
      app.add_option("--runs", args->settings.runs,
                     "timed runs per setting (median) (default: " + std::to_string(d.runs) + ")"),
      1, 100);
  int_range(app.add_option("--reference-spp", args->settings.reference_spp,
                           "spp of the reference; the spp ladder stops below it (default: " +
                               std::to_string(d.reference_spp) + ")"),
            1, 1 << 16);
  int_range(app.add_option(
                "--reference-depth", args->settings.reference_depth,
                "max_depth of the reference (default: " + std::to_string(d.reference_depth) + ")"),
            0, 100000);
  int_range(app.add_option("--max-pixels", args->settings.max_pixels,
                           "larger images are rendered smaller, same window (default: " +
                               std::to_string(d.max_pixels) + ")"),
            1, 1LL << 26);
  int_range(
      app.add_option("--threads", args->settings.threads, "render threads (default: all cores)"), 0,
      1024);
  app.add_flag("-q,--quiet", args->quiet, "no progress bar");
  // The sweep sets these itself: given here they would be ignored.
  const std::string ladder =
      "report renders a ladder of spp (1 to 64) against a reference of "
      "--reference-spp";
  args->flags.add_to(app, {{"spp", ladder},
                           {"precision", "report renders the spp ladder in both precisions"},
                           {"bailout", "report sweeps bailout itself"},
                           {"format", "report writes report.md, report.csv and report.svg"},
                           {"priority", "priority is a server's queue class; report runs here"},
                           {"target_error", ladder + ", each to the end"},
                           {"time_limit", ladder + ", each to the end"}});
  app.footer(help_footer(
      "  rayfarm report scenes/cho.txt --out report/\n"
      "  rayfarm report scenes/mirrors.txt --runs 1 --max-pixels 20000 --reference-spp 128\n",
      ""));
  return [args]() -> int {
    auto text = read_input(args->scene);
    if (!text) return kBadInput;
    auto loaded = load_checked(args->scene, *text, false);
    if (!loaded) return kBadInput;
    auto options = resolve_options(*loaded->scene, args->flags);
    if (!options) return kBadInput;
    if (!loaded->scene->find_camera(options->camera)) {
      std::cerr << "rayfarm: error: no camera named '" << options->camera << "'\n";
      return kBadInput;
    }
    // A rung at or above the reference's spp would be measured against itself (an error
    // of 0 and a PSNR of inf, marked optimal): the ladder stops below the reference.
    auto& ladder_spp = args->settings.spp;
    const size_t rungs = ladder_spp.size();
    std::erase_if(ladder_spp, [&](int spp) { return spp >= args->settings.reference_spp; });
    if (ladder_spp.size() != rungs) {
      std::string kept;
      for (int spp : ladder_spp) kept += (kept.empty() ? "" : ", ") + std::to_string(spp);
      std::cerr << "rayfarm: note: the spp ladder stops below --reference-spp "
                << args->settings.reference_spp << ": "
                << (kept.empty() ? "no spp rows" : "spp " + kept) << "\n";
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
    if (!report.error.empty()) {
      std::cerr << "rayfarm: error: " << report.error << "\n";
      return kBadInput;
    }
    for (const std::string& note : report.notes) std::cerr << "rayfarm: note: " << note << "\n";
    namespace fs = std::filesystem;
    // The folder itself is made, not its parents: a mistyped path is an error, not a tree.
    std::error_code ec;
    fs::create_directory(args->out, ec);
    if (ec || !fs::is_directory(args->out, ec)) {
      std::cerr << "rayfarm: cannot write " << args->out << ": "
                << (ec ? ec.message() : "it is not a folder") << "\n";
      return kBadInput;
    }
    std::string md = report_markdown(report), csv = report_csv(report), svg = report_svg(report);
    if (!write_output((fs::path(args->out) / "report.md").string(), md.data(), md.size()) ||
        !write_output((fs::path(args->out) / "report.csv").string(), csv.data(), csv.size()) ||
        !write_output((fs::path(args->out) / "report.svg").string(), svg.data(), svg.size()))
      return kBadInput;
    std::cout << md;
    std::cerr << "rayfarm: wrote " << (fs::path(args->out) / "report.md").string()
              << ", report.csv, report.svg\n";
    return kOk;
  };
}

}  // namespace rayfarm::cli
