// The command line's own words: help footers, range checks that name the option and the
// accepted range, and CLI11's parse errors rephrased ("--width given twice").
#include <charconv>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "cli_common.h"
#include "rayfarm/diagnostic.h"
#include "rayfarm/model_parser.h"
#include "rayfarm/options.h"

namespace rayfarm::cli {
namespace {

// "16..1000000", "0.1..86400": whole numbers in full, as people type them.
std::string number_text(double v) {
  if (v == static_cast<double>(static_cast<long long>(v)))
    return std::to_string(static_cast<long long>(v));
  return format_number(v);
}

std::string range_text(double lo, double hi) { return number_text(lo) + ".." + number_text(hi); }

// The subcommand the user named (CLI11 marks it parsed even when its own parse failed).
const CLI::App* chosen(const CLI::App& app) {
  for (const CLI::App* sub : app.get_subcommands({}))
    if (sub->parsed()) return sub;
  return nullptr;
}

std::string did_you_mean(const std::string& word, const std::vector<std::string>& names,
                         const char* quote) {
  std::vector<std::string_view> views(names.begin(), names.end());
  const std::string near = nearest_word(word, views);
  return near.empty() ? "" : std::string(" (did you mean ") + quote + near + quote + "?)";
}

std::string times(size_t n) { return n == 2 ? "twice" : std::to_string(n) + " times"; }

std::string specific(const CLI::App& app, const CLI::App* sub, const CLI::ParseError& e) {
  const CLI::App& where = sub ? *sub : app;
  if (dynamic_cast<const CLI::ExtrasError*>(&e) || (!sub && !app.remaining().empty())) {
    const std::vector<std::string> extras = where.remaining();
    if (extras.empty()) return e.what();
    std::vector<std::string> names;
    if (!sub) {
      for (const CLI::App* s : app.get_subcommands({})) names.push_back(s->get_name());
      std::string list;
      for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
      return "unknown command '" + extras.front() + "'" + did_you_mean(extras.front(), names, "'") +
             "; the commands are " + list;
    }
    for (const std::string& arg : extras) {
      if (arg.size() < 2 || arg[0] != '-') continue;
      const std::string flag = arg.substr(0, arg.find('='));
      for (const CLI::Option* o : where.get_options())
        for (const std::string& n : o->get_lnames()) names.push_back("--" + n);
      return "unknown option " + flag + did_you_mean(flag, names, "");
    }
    return "unexpected argument '" + extras.front() + "'";
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&e))
    for (const CLI::Option* o : where.get_options())
      if (o->count() > 1 && o->get_expected_max() == 1)
        return (o->get_lnames().empty() ? o->get_name() : "--" + o->get_lnames().front()) +
               " given " + times(o->count()) + "; give it once";
  if (sub && dynamic_cast<const CLI::RequiredError*>(&e)) {
    // A file whose name starts with '-' is read as an option: say how to name it.
    for (const std::string& arg : where.remaining()) {
      std::error_code ec;
      if (arg.size() > 1 && arg[0] == '-' && std::filesystem::exists(arg, ec))
        return std::string(e.what()) + "; '" + arg + "' was read as an option: name the file ./" +
               arg + ", or give it last, after --";
    }
  }
  if (!sub && dynamic_cast<const CLI::RequiredError*>(&e)) {
    std::string list;
    for (const CLI::App* s : app.get_subcommands({}))
      list += (list.empty() ? "" : ", ") + s->get_name();
    return "give a command: " + list;
  }
  if (dynamic_cast<const CLI::ConversionError*>(&e)) {
    // "Could not convert: --runs = abc"
    std::string what = e.what();
    const size_t colon = what.find(": "), eq = what.find(" = ");
    if (colon != std::string::npos && eq != std::string::npos)
      return what.substr(colon + 2, eq - colon - 2) + ": '" + what.substr(eq + 3) +
             "' is not a number";
  }
  return e.what();
}

}  // namespace

std::string help_footer(const std::string& examples, const std::string& exit_one, bool server) {
  return "\nExamples:\n" + examples + "\nExit codes (the same for every command):\n" +
         "  0    done\n" + (exit_one.empty() ? "" : "  1    " + exit_one + "\n") +
         "  2    usage, or input to fix: a file that cannot be read or written, a scene with\n"
         "       errors" +
         (server ? ", a request the server refused (401, 404, 422, ...)" : "") + "\n" +
         (server ? "  3    the server cannot be reached, is busy (429) or failed (5xx)\n" : "") +
         "  130  interrupted (Ctrl-C)\n";
}

CLI::Option* int_range(CLI::Option* option, long long lo, long long hi) {
  const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
  return option
      ->check(CLI::Validator(
          [lo, hi, range](std::string& v) -> std::string {
            // As strict as number_range and the render options: digits with an optional sign,
            // no spaces around them (std::stoll took " 5" and refused "5 ").
            long long n = 0;
            const char* first = v.data() + (v.starts_with('+') ? 1 : 0);
            const char* last = v.data() + v.size();
            const auto [end, ec] = std::from_chars(first, last, n);
            const bool whole =
                ec == std::errc() && end == last && first != last && !v.starts_with("+-");
            if (!whole || n < lo || n > hi)
              return "must be an integer in " + range + ", got '" + v + "'";
            return "";
          },
          "", "int_range"))
      ->type_name(range);
}

CLI::Option* file_name(CLI::Option* option) {
  return option->check(CLI::Validator(
      [](std::string& v) -> std::string {
        return v.empty() ? "a file name cannot be empty (an unset variable?)" : "";
      },
      "", "file_name"));
}

CLI::Option* number_range(CLI::Option* option, double lo, double hi) {
  const std::string range = range_text(lo, hi);
  return option
      ->check(CLI::Validator(
          [lo, hi, range](std::string& v) -> std::string {
            // As a scene's numbers are read: a subnormal (2e-308) is a number too.
            const std::optional<double> n = parse_number(v);
            if (!n || !(*n >= lo && *n <= hi))
              return "must be a number in " + range + ", got '" + v + "'";
            return "";
          },
          "", "number_range"))
      ->type_name(range);
}

std::string usage_message(const CLI::App& app, const CLI::ParseError& e) {
  const CLI::App* sub = chosen(app);
  const std::string command = sub ? "rayfarm " + sub->get_name() : "rayfarm";
  return "rayfarm: " + specific(app, sub, e) + "\n(" + command + " --help lists the " +
         (sub ? "options" : "commands") + ")\n";
}

}  // namespace rayfarm::cli
