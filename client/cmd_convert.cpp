// `rayfarm convert SCENE --to json|model|pov [-o OUT]`.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/render.h"
#include "rayfarm/writers.h"

namespace rayfarm::cli {

namespace {
struct ConvertArgs {
  std::string scene;
  std::string to;
  std::string out = "-";
  OptionFlags flags;  // for --to pov: size, camera, depth, shadows, highlight
};
}  // namespace

Runner add_convert(CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  file_name(app.add_option("scene", args->scene, "scene file (- for stdin)"))->required();
  app.add_option("--to", args->to, "target format")
      ->required()
      ->check(CLI::IsMember({"json", "model", "pov"}));
  file_name(app.add_option("-o,--output", args->out, "output file (default: standard output)"));
  args->flags.add_to(app);
  app.footer(help_footer(
      "  rayfarm convert scenes/cho.txt --to json -o cho.json\n"
      "  rayfarm convert scenes/cho.json --to model            # the course's format\n"
      "  rayfarm convert scenes/cho.txt --to json --spp 16     # render options into the JSON\n"
      "  rayfarm convert scenes/cho.txt --to pov --width 400 --height 300 -o cho.pov\n"
      "\nRender options: --to json writes them into the scene's render object; --to model "
      "refuses them\n(the format has none); --to pov uses --camera, --width, --height, "
      "--max-depth, --profile,\n--background and --highlight, and refuses the others.\n",
      ""));
  return [args] {
    auto text = read_input(args->scene);
    if (!text) return int(kBadInput);
    auto loaded = load_checked(args->scene, *text, false, LoadDetail::full, false);
    if (!loaded) return int(kBadInput);
    // The options as a render would take them, and a camera that exists: what is written
    // must load and render.
    auto checked_options = [&]() -> std::optional<RenderOptions> {
      auto options = resolve_options(*loaded->scene, args->flags);
      if (!options) return std::nullopt;
      const auto camera = loaded->scene->find_camera(options->camera);
      if (!camera) {
        std::cerr << "rayfarm: error: no camera named '" << options->camera << "'\n";
        return std::nullopt;
      }
      // A size the scene's own camera gives is lint's to report; options given here that
      // make the image too large would be written into a JSON scene that no render takes.
      const Camera& cam = loaded->scene->cameras[*camera];
      const std::string size =
          image_size_error(options->width > 0 ? options->width : cam.width,
                           options->height > 0 ? options->height : cam.height, options->spp);
      if (args->to == "json" && !args->flags.values.empty() && !size.empty()) {
        std::cerr << "rayfarm: error: with the options given, " << size << "\n";
        return std::nullopt;
      }
      return options;
    };
    std::string out;
    if (args->to == "json") {
      if (!checked_options()) return int(kBadInput);
      // Render options given here go into the scene's "render" object, over its own.
      for (const OptionValue& flag : args->flags.as_set()) {
        auto& render = loaded->desc.render;
        render.erase(std::remove_if(render.begin(), render.end(),
                                    [&](const OptionValue& o) { return o.name == flag.name; }),
                     render.end());
        render.push_back(flag);
      }
      out = write_json(loaded->desc);
    } else if (args->to == "model") {
      if (!args->flags.values.empty()) {
        std::cerr << "rayfarm: the model format has no render options: give --"
                  << args->flags.values.begin()->first << " when rendering, or convert --to json\n";
        return int(kBadInput);
      }
      out = write_model(loaded->desc);
      if (!loaded->desc.render.empty())
        std::cerr << "rayfarm: note: the model format has no render options; the scene's "
                     "\"render\" object is not in the output\n";
    } else {
      // What POV-Ray's SDL can say; the rest would be dropped without a word.
      static const std::set<std::string> kPov = {"camera",  "width",      "height",   "max_depth",
                                                 "profile", "background", "highlight"};
      for (const auto& [name, value] : args->flags.values)
        if (!kPov.count(name)) {
          std::string flag = name;
          std::replace(flag.begin(), flag.end(), '_', '-');
          std::cerr << "rayfarm: --to pov cannot use --" << flag
                    << ": the POV-Ray file takes --camera, --width, --height, --max-depth, "
                       "--profile, --background and --highlight\n";
          return int(kBadInput);
        }
      auto options = checked_options();
      if (!options) return int(kBadInput);
      out = write_pov(*loaded->scene, *options);
    }
    if (const std::string bad = check_not_input(args->out, {args->scene}); !bad.empty()) {
      std::cerr << "rayfarm: " << bad << "\n";
      return int(kBadInput);
    }
    if (!write_output(args->out, out.data(), out.size())) return int(kBadInput);
    // Texture paths are relative to the scene's folder and written as they were: a scene
    // written elsewhere finds its textures only if they are copied beside it.
    if (!loaded->scene->textures.empty() && args->out != "-" && !args->out.empty() &&
        args->scene != "-") {
      namespace fs = std::filesystem;
      std::error_code ec;
      const fs::path from = fs::absolute(fs::path(args->scene), ec).parent_path();
      const fs::path to = fs::absolute(fs::path(args->out), ec).parent_path();
      if (!ec && fs::weakly_canonical(from, ec) != fs::weakly_canonical(to, ec))
        std::cerr << "rayfarm: note: texture paths are relative to the scene's folder ('"
                  << loaded->scene->textures.front().path
                  << "') and are written as they were: copy the textures to the same paths "
                     "beside "
                  << args->out << "\n";
    }
    return int(kOk);
  };
}

}  // namespace rayfarm::cli
