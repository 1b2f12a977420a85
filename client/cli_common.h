// Shared pieces of the command line: exit codes, file I/O, render-option flags.
#pragma once

#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "rayfarm/load.h"
#include "rayfarm/options.h"

namespace rayfarm::cli {

// SPEC §6.
enum Exit { kOk = 0, kInputError = 1, kUsage = 2, kServerError = 3 };
// `compare` exits as diff does: 1 for images that differ, 2 for trouble.
constexpr int kDiffer = 1;

// Reads a file, or standard input for "-". nullopt with a message on stderr on failure.
std::optional<std::string> read_input(const std::string& path);
// Writes to a file (atomically: temp + rename), or standard output for "-".
bool write_output(const std::string& path, const void* data, size_t size);

// `--spp 4`, `--max-depth 3` (or `--max_depth`), ...: every option of the table as a flag.
// Values are kept as text, in the order of the table, to be applied after the scene's own.
struct OptionFlags {
  std::map<std::string, std::string> values;
  void add_to(CLI::App& app);
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

 private:
  std::filesystem::path base_;
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
