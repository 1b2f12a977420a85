// rayfarm: the command line (docs/cli.md). Renders locally with no server, or as rayfarmd's
// client; checks, converts and compares.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <map>
#include <new>
#include <nlohmann/json.hpp>

#include "cli_common.h"
#include "commands.h"

int main(int argc, char** argv) {
  using namespace rayfarm::cli;
  CLI::App app{"rayfarm: ray-trace the course's model files and JSON scenes", "rayfarm"};
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
  add("jobs", "list your jobs on a server", add_jobs);
  app.footer(
      "\nrayfarm COMMAND --help shows a command's options and examples.\n"
      "\nEnvironment:\n"
      "  RAYFARM_SERVER  the server of render, status, cancel, wait and jobs (--server)\n"
      "  RAYFARM_TOKEN   the bearer token for that server (--token)\n"
      "  RAYFARM_CACHE   grade's folder of cached references (--cache)\n"
      "\nExit codes (the same for every command):\n"
      "  0    done\n"
      "  1    the answer is no: check found errors, compare's images differ, grade's score is\n"
      "       below --fail-under, the server's job failed or was canceled\n"
      "  2    usage, or input to fix: a file that cannot be read or written, a scene with\n"
      "       errors, a request the server refused (401, 404, 422, ...)\n"
      "  3    the server cannot be reached, is busy (429) or failed (5xx)\n"
      "  130  interrupted (Ctrl-C)\n");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const std::string message = usage_message(app, e);
    std::cerr << message;
    if (argc > 1 && std::string(argv[1]) == "grade")
      grade_command_line_refused(argc, argv, message.substr(9, message.find('\n') - 9));
    return kBadInput;
  }
  for (auto& [sub, run] : runners)
    if (sub->parsed()) {
      int code = kOk;
      try {
        code = run();
      } catch (const std::bad_alloc&) {
        // A memory limit (ulimit -v, a grader's container) met by the image, its samples or
        // the scene: said, and input to fix, not an abort.
        std::cerr << "rayfarm: out of memory: this needs more memory than the process may "
                     "have (a smaller image, fewer samples a pixel or a smaller scene needs "
                     "less)\n";
        return kBadInput;
      } catch (const nlohmann::json::exception& e) {
        // The one JSON the commands read without checking each field's type is a server's
        // answer (status, events, errors): one of another shape is the server's failure.
        std::cerr << "rayfarm: the server's answer is not what rayfarm understands (" << e.what()
                  << ")\n";
        return kServerError;
      }
      // What a command printed (trace, compare, check, report) is its answer: one lost to a
      // full disk or a closed pipe is an error, not a quiet exit 0 (or 1).
      errno = 0;
      std::cout.flush();
      if (!std::cout || std::fflush(stdout) != 0 || std::ferror(stdout)) {
        const int err = errno;
        if (!stdout_failure_said())
          std::cerr << "rayfarm: cannot write to standard output"
                  << (err ? std::string(": ") + std::strerror(err) : std::string()) << "\n";
        return code == kOk || code == kNo ? kBadInput : code;
      }
      return code;
    }
  return kBadInput;
}
