// `rayfarm check [--course] SCENE...`: errors and lint warnings for each file; with --course
// also where the course's reference program would stop on or misread it.
#include <iostream>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/lint.h"

namespace rayfarm::cli {

Runner add_check(CLI::App& app) {
  auto files = std::make_shared<std::vector<std::string>>();
  auto quiet = std::make_shared<bool>(false);
  auto course = std::make_shared<bool>(false);
  app.add_option("scenes", *files, "scene files (model or JSON; - for stdin)")->required();
  app.add_flag("-q,--quiet", *quiet, "print nothing for files without errors or warnings");
  app.add_flag("--course", *course,
               "also warn where the course's reference program (CPSC 102, 2014-18) would stop "
               "on or misread a model file");
  return [files, quiet, course] {
    int status = kOk;
    for (const std::string& path : *files) {
      auto text = read_input(path);
      if (!text) {
        status = kInputError;
        continue;
      }
      auto loaded = load_checked(path, *text, true);
      // Course warnings also for files rayfarm rejects: the student wants every problem.
      Diagnostics course_lints;
      if (*course) {
        if (detect_format(*text) == SceneFormat::model)
          lint_course(*text, course_lints);
        else
          std::cerr << display_name(path) << ": note: --course applies to model files only\n";
      }
      if (!loaded) {
        for (const Diagnostic& d : course_lints.items())
          std::cerr << format_diagnostic(d, display_name(path), *text);
        status = kInputError;
        continue;
      }
      RenderOptions options;
      Diagnostics scratch, lints;
      apply_options(options, loaded->scene->render, scratch);
      lint_scene(*loaded->scene, options, lints);
      for (const Diagnostic& d : loaded->diags.items())  // build-stage warnings, if any
        if (d.severity == Severity::warning) lints.warning(d.code, d.message, d.where);
      for (const Diagnostic& d : course_lints.items()) lints.warning(d.code, d.message, d.where);
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
