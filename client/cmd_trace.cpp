// `rayfarm trace SCENE X Y [--json] [options]`: follows one pixel through the renderer and
// prints every term of its colour, down to the bytes the render writes.
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/explain.h"
#include "rayfarm/lint.h"

namespace rayfarm::cli {
namespace {

struct TraceArgs {
  std::string scene;
  std::string x, y;  // decimal digits (checked), read here: CLI11 reads 010 as 8
  bool json = false;
  int samples = 0;  // of a render stopped early: its N of spp N/M
  OptionFlags flags;
};

}  // namespace

Runner add_trace(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  file_name(app.add_option("scene", args->scene, "scene file (model or JSON; - for stdin)"))
      ->required();
  // Decimal digits only: the library's own integer reading takes 010 for 8 and 0x10 for 16.
  const CLI::Validator decimal(
      [](std::string& s) -> std::string {
        const bool digits = !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
        if (!digits) return "'" + s.substr(0, 40) + "' is not a pixel number (decimal digits, from 0)";
        // No image has a pixel past 65534 (the explanation then says the image's size).
        if (s.find_first_not_of('0') != std::string::npos && s.size() - s.find_first_not_of('0') > 5)
          return "'" + s.substr(0, 40) + "' is past every image: images are at most 65535 pixels wide or high";
        return "";
      },
      "PIXEL");
  app.add_option("x", args->x, "pixel column, 0 at the left")->required()->check(decimal);
  app.add_option("y", args->y, "pixel row, 0 at the top")->required()->check(decimal);
  app.add_flag("--json", args->json, "print the explanation as JSON");
  int_range(app.add_option("--samples", args->samples,
                           "a render stopped early (its summary says spp N/M): follow its first "
                           "N of --spp M samples"),
            1, 1 << 30);
  // A render with these stops where its whole image's estimate says: one pixel cannot know
  // that, and its bytes would not be the render's.
  const char* stop_rule =
      "trace follows a set number of samples; give --spp M --samples N for a render that "
      "stopped at spp N/M";
  args->flags.add_to(app, {{"format", "trace prints the pixel's bytes, not an image"},
                           {"priority", "priority is a server's queue class; trace runs here"},
                           {"target_error", stop_rule},
                           {"time_limit", stop_rule}});
  app.footer(
      help_footer("  rayfarm trace scenes/cho.txt 400 300\n"
                  "  rayfarm trace scenes/cho.txt 400 300 --profile cpsc102 --json\n",
                  ""));
  return [args]() -> int {
    auto text = read_input(args->scene);
    if (!text) return kBadInput;
    auto loaded = load_checked(args->scene, *text, false);
    if (!loaded) return kBadInput;
    auto options = resolve_options(*loaded->scene, args->flags);
    if (!options) return kBadInput;
    {
      // An image render refuses for its size is refused here as there, with its place.
      Diagnostics lints;
      lint_image_size(*loaded->scene, *options, lints);
      for (const Diagnostic& d : lints.items())
        std::cerr << format_diagnostic(d, display_name(args->scene), *text);
      if (lints.has_errors()) return kBadInput;
    }
    if (args->samples > 0 && args->samples < options->spp &&
        options->profile == Profile::cpsc102) {
      std::cerr << "rayfarm: --samples: the cpsc102 profile takes a pixel's samples in one pass, "
                   "so its renders never stop early; give --spp alone\n";
      return kBadInput;
    }
    if (args->samples > options->spp) {
      std::cerr << "rayfarm: --samples " << args->samples << " is more than the " << options->spp
                << " samples a pixel of --spp: a render takes at most its spp\n";
      return kBadInput;
    }
    // The scene's own stop rule (a JSON render block) cannot be followed for one pixel.
    if (args->samples == 0 && (options->target_error > 0 || options->time_limit > 0))
      std::cerr << "rayfarm: note: the scene's "
                << (options->target_error > 0 ? "target_error" : "time_limit")
                << " may stop its render early: trace follows all " << options->spp
                << " samples; for a render that stopped at spp N/" << options->spp
                << ", give --samples N\n";
    std::string error;
    const auto explainer = Explainer::create(*loaded->scene, *options, &error);
    if (!explainer) {
      std::cerr << "rayfarm: error: " << error << "\n";
      return kBadInput;
    }
    const auto explanation =
        explainer->explain(std::stoi(args->x), std::stoi(args->y), &error, args->samples);
    if (!explanation) {  // the only refusal left: a pixel outside the image
      std::cerr << "rayfarm: error: " << error << "\n";
      return kBadInput;
    }
    if (args->json)
      std::cout << explanation_json(*explanation).dump(2) << "\n";
    else
      std::cout << explanation_text(*explanation);
    return kOk;
  };
}

}  // namespace rayfarm::cli
