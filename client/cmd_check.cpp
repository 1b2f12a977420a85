// `rayfarm check SCENE...`: errors and lint warnings for each file.
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/lint.h"

namespace rayfarm::cli {

Runner add_check(CLI::App& app) {
  auto files = std::make_shared<std::vector<std::string>>();
  auto quiet = std::make_shared<bool>(false);
  app.add_option("scenes", *files, "scene files (model or JSON; - for stdin)")->required();
  app.add_flag("-q,--quiet", *quiet, "print nothing for files without errors or warnings");
  return [files, quiet] {
    int status = kOk;
    for (const std::string& path : *files) {
      auto text = read_input(path);
      if (!text) {
        status = kInputError;
        continue;
      }
      auto loaded = load_checked(path, *text, true);
      if (!loaded) {
        status = kInputError;
        continue;
      }
      RenderOptions options;
      Diagnostics scratch, lints;
      apply_options(options, loaded->scene->render, scratch);
      lint_scene(*loaded->scene, options, lints);
      for (const Diagnostic& d : loaded->diags.items())  // build-stage warnings, if any
        if (d.severity == Severity::warning) lints.warning(d.code, d.message, d.where);
      for (const Diagnostic& d : lints.items())
        std::cerr << format_diagnostic(d, display_name(path), *text);
      if (!*quiet || !lints.items().empty()) {
        const Scene& s = *loaded->scene;
        std::cout << display_name(path) << ": ok: " << s.cameras.size() << " camera(s), "
                  << s.materials.size() << " material(s), " << s.lights.size() << " light(s), "
                  << s.objects.size() << " object(s)"
                  << (lints.items().empty() ? "" : ", " + std::to_string(lints.items().size()) +
                                                       " warning(s)")
                  << "\n";
      }
    }
    return status;
  };
}

}  // namespace rayfarm::cli
