// Shared pieces of the command line: exit codes, file I/O, render-option flags.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "rayfarm/load.h"
#include "rayfarm/options.h"
#include "read_file.h"

namespace rayfarm::cli {

// The exit codes of docs/cli.md, one table for every command, as diff and grep exit: 1 is
// an answer, "no" (check found errors, the images differ, the score is too low, the server's
// job failed); 2 is trouble the user must fix (usage, unreadable files, a scene with errors
// for render, a request the server refused); 3 is the server's or the network's trouble.
enum Exit { kOk = 0, kNo = 1, kBadInput = 2, kServerError = 3, kInterrupted = 130 };

// The help's footer: examples, then the exit codes with what 1 means for this command
// (empty: it never answers 1); `server` for the commands that talk to rayfarmd.
std::string help_footer(const std::string& examples, const std::string& exit_one,
                        bool server = false);

// Range checks whose message names the option and the accepted range, as the render
// options' own do: "--threads: must be an integer in 0..1024, got '2000'".
CLI::Option* int_range(CLI::Option* option, long long lo, long long hi);
CLI::Option* number_range(CLI::Option* option, double lo, double hi);
// A file name that may not be empty: `-o "$OUT"` with OUT unset must not fall back to a
// default name, to standard output, or to nothing at all.
CLI::Option* file_name(CLI::Option* option);

// A command-line error in plain words: "--width given twice", "unknown option --frobnicate
// (did you mean --format?)", "unknown command 'rendr' (did you mean 'render'?)".
std::string usage_message(const CLI::App& app, const CLI::ParseError& e);

// An output the user would not expect is refused before any work: a name whose extension
// says another format, or image bytes sent to a terminal. Empty when the output is fine;
// `format` is --format's value, empty when not given.
std::string check_output(const std::string& out, const std::string& format);
// Refuses an output that is one of the command's inputs (`render scene.png` named its image
// after its scene; `compare a.png b.png --diff a.png`): the input would be lost. Empty when not.
std::string check_not_input(const std::string& out, const std::vector<std::string>& inputs);
inline std::string check_not_input(const std::string& out,
                                   std::initializer_list<std::string> inputs) {
  return check_not_input(out, std::vector<std::string>(inputs));
}
// The encoding of an image output: `format` ("png" or "ppm") when given, else the name's
// extension in any case (".ppm", ".PPM"), else `otherwise` (render: the scene's own render
// object's); the one rule of render, wait and compare.
ImageFormat output_format(const std::string& out, const std::string& format = "",
                          ImageFormat otherwise = ImageFormat::png);

// Reads a file, or standard input for "-", whole: at most `limit` bytes (read_file.h). nullopt
// on failure, with the reason in `why` or, without it, said on stderr.
std::optional<std::string> read_input(const std::string& path, std::string* why = nullptr,
                                      std::uintmax_t limit = kMaxInputBytes);
// Writes to a file (atomically: temp + rename, through a symbolic link to what it names, the
// file's permissions kept), in place to a device, pipe or socket (/dev/null stays a device),
// or to standard output for "-". False, with the reason said on stderr, when it cannot.
bool write_output(const std::string& path, const void* data, size_t size);
// Whether write_output has already said that standard output could not be written.
bool stdout_failure_said();

// `--spp 4`, `--max-depth 3` (or `--max_depth`), ...: every option of the table as a flag.
// Values are kept as text, in the order of the table, to be applied after the scene's own.
struct OptionFlags {
  std::map<std::string, std::string> values;
  // `refused`: options this command cannot use (name -> why), refused rather than ignored.
  void add_to(CLI::App& app, const std::map<std::string, std::string>& refused = {});
  OptionSet as_set() const;
};

// Texture files of a local render: paths as the scene writes them, relative to the model
// file's folder (the user's own files: `..` and absolute paths are theirs to use).
class FileResolver final : public ResourceResolver {
 public:
  explicit FileResolver(std::filesystem::path base) : base_(std::move(base)) {}
  // Beside the scene file `scene_path` (beside the working directory for "-", stdin).
  static FileResolver beside(const std::string& scene_path);
  std::optional<std::string> read(const std::string& path, std::string& error) const override;
  // Each file asked for is added to `paths` (whether or not it can be read).
  void record_into(std::vector<std::string>* paths) { seen_ = paths; }

 private:
  std::filesystem::path base_;
  std::vector<std::string>* seen_ = nullptr;
};

// Loads and checks a scene file, printing diagnostics. nullopt when it has errors. With
// `textures`, the scene's texture files are read too (their problems are errors).
std::optional<LoadedScene> load_checked(const std::string& path, const std::string& text,
                                        bool print_warnings, LoadDetail detail = LoadDetail::scene,
                                        bool textures = true);
// The same, with the texture files read through `textures` (none read when null).
std::optional<LoadedScene> load_checked(const std::string& path, const std::string& text,
                                        bool print_warnings, LoadDetail detail,
                                        const ResourceResolver* textures);

// The scene's own options, then the command line's; errors printed. nullopt on error.
std::optional<RenderOptions> resolve_options(const Scene& scene, const OptionFlags& flags);

std::string display_name(const std::string& path);

}  // namespace rayfarm::cli
