// The subcommands of `rayfarm`: each registers its flags and returns its runner.
#pragma once

#include <functional>
#include <string>

#include <CLI/CLI.hpp>

namespace rayfarm::cli {

using Runner = std::function<int()>;

Runner add_render(CLI::App& app);
Runner add_trace(CLI::App& app);
Runner add_check(CLI::App& app);
Runner add_convert(CLI::App& app);
Runner add_compare(CLI::App& app);
Runner add_grade(CLI::App& app);
Runner add_report(CLI::App& app);
Runner add_status(CLI::App& app);
Runner add_cancel(CLI::App& app);
Runner add_wait(CLI::App& app);
Runner add_jobs(CLI::App& app);

// grade's command line was refused before its runner could start: the result file that -o
// names (if any) still gets a grader error, as docs/grading.md promises the platform.
void grade_command_line_refused(int argc, char** argv, const std::string& why);

}  // namespace rayfarm::cli
