// `rayfarm convert SCENE --to json|model|pov [-o OUT]`.
#include <algorithm>
#include <iostream>

#include "cli_common.h"
#include "commands.h"
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
  app.add_option("scene", args->scene, "scene file (- for stdin)")->required();
  app.add_option("--to", args->to, "target format")
      ->required()
      ->check(CLI::IsMember({"json", "model", "pov"}));
  app.add_option("-o,--output", args->out, "output file (default: standard output)");
  args->flags.add_to(app);
  return [args] {
    auto text = read_input(args->scene);
    if (!text) return int(kInputError);
    auto loaded = load_checked(args->scene, *text, false, LoadDetail::full, false);
    if (!loaded) return int(kInputError);
    std::string out;
    if (args->to == "json") {
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
        return int(kUsage);
      }
      out = write_model(loaded->desc);
      if (!loaded->desc.render.empty())
        std::cerr << "rayfarm: note: the model format has no render options; the scene's "
                     "\"render\" object is not in the output\n";
    } else {
      auto options = resolve_options(*loaded->scene, args->flags);
      if (!options) return int(kInputError);
      if (!loaded->scene->find_camera(options->camera)) {
        std::cerr << "rayfarm: error: no camera named '" << options->camera << "'\n";
        return int(kInputError);
      }
      out = write_pov(*loaded->scene, *options);
    }
    return write_output(args->out, out.data(), out.size()) ? int(kOk) : int(kInputError);
  };
}

}  // namespace rayfarm::cli
