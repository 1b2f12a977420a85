// `rayfarm check [--course] SCENE...`: errors and lint warnings for each file; with --course
// also where the course's reference program would stop on or misread it.
#include <algorithm>
#include <iostream>
#include <utility>

#include "cli_common.h"
#include "commands.h"
#include "rayfarm/lint.h"

namespace rayfarm::cli {

namespace {

std::string counted(size_t n, const char* what) {
  return std::to_string(n) + " " + what + (n == 1 ? "" : "s");
}

struct Tally {
  size_t errors = 0;
  size_t warnings = 0;
};

// One file: every error and warning in line order (the loader's, the linter's and the
// course's come from separate passes), then one line that says how it went.
int check_file(const std::string& path, bool quiet, bool course, Tally& total) {
  auto text = read_input(path);
  if (!text) return kBadInput;
  const std::string name = display_name(path);
  const FileResolver files = FileResolver::beside(path);
  LoadedScene loaded = load_scene(*text, LoadDetail::scene, &files);
  std::vector<Diagnostic> all = loaded.diags.items();
  size_t lint_errors = 0;  // an image too large to render
  if (loaded.scene && !loaded.diags.has_errors()) {
    RenderOptions options;
    Diagnostics scratch, lints;
    apply_options(options, loaded.scene->render, scratch);
    lint_scene(*loaded.scene, options, lints);
    all.insert(all.end(), lints.items().begin(), lints.items().end());
    lint_errors = lints.error_count();
  }
  // Course warnings also for files rayfarm rejects: the student wants every problem.
  if (course) {
    if (detect_format(*text) == SceneFormat::model) {
      Diagnostics course_lints;
      lint_course(*text, course_lints);
      all.insert(all.end(), course_lints.items().begin(), course_lints.items().end());
    } else {
      std::cerr << name << ": note: --course applies to model files only\n";
    }
  }
  in_file_order(*text, all);  // a JSON scene's by where their paths lie
  size_t warnings = 0;
  for (const Diagnostic& d : all) {
    std::cerr << format_diagnostic(d, name, *text);
    warnings += d.severity == Severity::warning;
  }
  const size_t errors = loaded.diags.error_count() + lint_errors;
  total.errors += errors;
  total.warnings += warnings;
  if (errors > 0) {
    const std::string errors_said = loaded.diags.counted_all()
                                        ? counted(errors, "error")
                                        : loaded.diags.error_count_text() + " errors";
    std::cout << name << ": " << errors_said << ", " << counted(warnings, "warning")
              << (loaded.diags.truncated()
                      ? " (only the first " + std::to_string(Diagnostics::kMaxErrors) + " shown)"
                      : "")
              << "\n";
    return kNo;
  }
  if (!quiet || warnings > 0) {
    const Scene& s = *loaded.scene;
    std::cout << name << ": ok: " << s.cameras.size() << " camera(s), " << s.materials.size()
              << " material(s), " << s.lights.size() << " light(s), " << s.objects.size()
              << " object(s)"
              << (warnings > 0 ? ", " + std::to_string(warnings) + " warning(s)" : "") << "\n";
  }
  return kOk;
}

}  // namespace

Runner add_check(CLI::App& app) {
  auto files = std::make_shared<std::vector<std::string>>();
  auto quiet = std::make_shared<bool>(false);
  auto course = std::make_shared<bool>(false);
  file_name(app.add_option("scenes", *files, "scene files (model or JSON; - for stdin)"))
      ->required();
  app.add_flag("-q,--quiet", *quiet, "print nothing for files without errors or warnings");
  app.add_flag("--course", *course,
               "also warn where the course's reference program (CPSC 102, 2014-18) would stop "
               "on or misread a model file");
  app.footer(help_footer(
      "  rayfarm check scenes/cho.txt\n"
      "  rayfarm check -q scenes/*.txt       # only the files with something to say\n"
      "  rayfarm check --course student.txt  # ... and where the course's program would stop\n",
      "a scene has errors (warnings alone do not change the exit code)"));
  return [files, quiet, course] {
    int status = kOk;
    Tally total;
    for (const std::string& path : *files)
      status = std::max(status, check_file(path, *quiet, *course, total));
    if (files->size() > 1 && (total.errors > 0 || total.warnings > 0))
      std::cout << counted(files->size(), "file") << ": " << counted(total.errors, "error") << ", "
                << counted(total.warnings, "warning") << "\n";
    return status;
  };
}

}  // namespace rayfarm::cli
