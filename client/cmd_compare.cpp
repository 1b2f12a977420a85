// `rayfarm compare A B`: the grader's metrics, locally (the same as POST /compare). Exits as
// diff does: 0 when the images match within the threshold, 1 when they differ (a different
// size too), 2 when an image cannot be read.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/compare.h"
#include "rayfarm/image_io.h"

namespace rayfarm::cli {
namespace {
struct CompareArgs {
  std::string a, b, diff;
  int threshold = 0;
  int neighborhood = 0;
  double max_bad_fraction = 0;
  bool json = false;
};
}  // namespace

Runner add_compare(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  file_name(app.add_option("a", args->a, "first image (PNG or PPM)"))->required();
  file_name(app.add_option("b", args->b, "second image (PNG or PPM)"))->required();
  file_name(app.add_option("--diff", args->diff, "write a heat map of the differences (.png or .ppm)"));
  int_range(app.add_option("--threshold", args->threshold,
                           "a channel differs when it is off by more than this many levels "
                           "(default: 0)"),
            0, 255);
  int_range(app.add_option("--neighborhood", args->neighborhood,
                           "1: a pixel matches if any pixel of its 3x3 neighbourhood does "
                           "(default: 0)"),
            0, 1);
  number_range(app.add_option("--max-bad-fraction", args->max_bad_fraction,
                              "the images match with at most this fraction of differing pixels "
                              "(default: 0)"),
               0, 1);
  app.add_flag("--json", args->json, "print the metrics as JSON");
  app.footer(
      help_footer("  rayfarm compare student.png reference.png\n"
                  "  rayfarm compare student.png reference.png --threshold 2 --neighborhood 1 "
                  "--diff where.png\n"
                  "  rayfarm compare a.ppm b.png --max-bad-fraction 0.01 --json\n",
                  "the images differ (more pixels than --max-bad-fraction, or another size)"));
  return [args]() -> int {
    // The report is on standard output: the heat map goes to a file, PNG or PPM by its name.
    if (args->diff == "-") {
      std::cerr << "rayfarm: --diff: the report goes to standard output; give the heat map a "
                   "file name (.png or .ppm)\n";
      return kBadInput;
    }
    // The heat map's format is its name's: a name without .png or .ppm says neither.
    const std::string ext = std::filesystem::path(args->diff).extension().string();
    const std::string unnamed =
        !args->diff.empty() && ext.empty()
            ? "'" + args->diff + "' has no extension: name the heat map .png or .ppm"
            : "";
    if (!args->diff.empty())
      for (const std::string& bad : {unnamed, check_output(args->diff, ""),
                                     check_not_input(args->diff, {args->a, args->b})})
        if (!bad.empty()) {
          std::cerr << "rayfarm: --diff: " << bad << "\n";
          return kBadInput;
        }
    if (args->a == "-" && args->b == "-") {
      std::cerr << "rayfarm: standard input is read once: give at most one of the images as -\n";
      return kBadInput;
    }
    std::optional<Image> images[2];
    const std::string* names[2] = {&args->a, &args->b};
    for (int i = 0; i < 2; ++i) {
      auto bytes = read_input(*names[i]);
      if (!bytes) return kBadInput;
      std::string error;
      images[i] = decode_image(*bytes, &error);
      if (!images[i]) {
        std::cerr << "rayfarm: " << *names[i] << ": " << error << "\n";
        return kBadInput;
      }
    }
    CompareOptions options{args->threshold, args->neighborhood == 1};
    std::string error;
    auto r = compare_images(*images[0], *images[1], options, &error);
    if (!r) {
      if (args->json)
        std::cout << nlohmann::json{{"match", false}, {"error", error}}.dump(2) << "\n";
      std::cerr << "rayfarm: " << error << "\n";
      return kNo;
    }
    const bool match = r->differing_fraction <= args->max_bad_fraction;
    if (!args->diff.empty()) {
      const ImageFormat format = output_format(args->diff);
      auto bytes = encode_image(diff_image(*images[0], *images[1], options), format);
      if (!write_output(args->diff, bytes.data(), bytes.size())) return kBadInput;
    }
    if (args->json) {
      nlohmann::json j = compare_json(*r, options);
      j["match"] = match;
      j["max_bad_fraction"] = args->max_bad_fraction;
      std::cout << j.dump(2) << "\n";
    } else {
      std::printf("size                %dx%d\n", r->width, r->height);
      std::printf("rmse                %.4f levels\n", r->rmse);
      if (std::isinf(r->psnr)) std::printf("psnr                inf (identical)\n");
      else std::printf("psnr                %.2f dB\n", r->psnr);
      std::printf("max_abs             %d\n", r->max_abs);
      std::printf("mean_abs            %.4f\n", r->mean_abs);
      std::printf("differing_pixels    %lld (%.4f%%, threshold %d%s)\n", r->differing_pixels,
                  100 * r->differing_fraction, options.threshold,
                  options.neighborhood ? ", 3x3 neighbourhood" : "");
      std::printf("off_by_more_than_1  %lld\n", r->off_by_more_than_1);
      std::printf("differing_channels  %lld of %lld\n", r->differing_channels,
                  3LL * r->width * r->height);
      std::printf("match               %s\n", match ? "yes" : "no");
    }
    return match ? kOk : kNo;
  };
}

}  // namespace rayfarm::cli
