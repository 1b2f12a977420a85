// rayfarm: the command line (SPEC §6). Renders locally with no server, or as rayfarmd's
// client; checks, converts and compares.
#include <iostream>
#include <map>

#include "cli_common.h"
#include "commands.h"

int main(int argc, char** argv) {
  using namespace rayfarm::cli;
  CLI::App app{"rayfarm: ray-trace the course's model files and JSON scenes"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rayfarm 0.1.0");
  std::map<CLI::App*, Runner> runners;
  auto add = [&](const char* name, const char* help, Runner (*make)(CLI::App&)) {
    CLI::App* sub = app.add_subcommand(name, help);
    runners[sub] = make(*sub);
  };
  add("render", "render a scene to PNG or PPM", add_render);
  add("trace", "follow one pixel through the renderer: every term of its colour", add_trace);
  add("check", "validate and lint scenes; exit 1 on errors", add_check);
  add("convert", "convert a scene to JSON, model file or POV-Ray SDL", add_convert);
  add("compare", "compare two images (RMSE, PSNR, differing pixels)", add_compare);
  add("grade", "grade a student's images against an assignment's references", add_grade);
  add("report", "error against run time over a sweep of settings", add_report);
  add("status", "show a job's status on a server", add_status);
  add("cancel", "cancel a job on a server", add_cancel);
  add("wait", "wait for a job on a server and fetch its image", add_wait);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }
  for (auto& [sub, run] : runners)
    if (sub->parsed()) return run();
  return kUsage;
}
