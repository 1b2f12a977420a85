// rayfarm: the command line. Renders locally (no server needed) and checks and converts
// scenes (SPEC §6).
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
  add("check", "validate and lint scenes; exit 1 on errors", add_check);
  add("convert", "convert a scene to JSON, model file or POV-Ray SDL", add_convert);
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
