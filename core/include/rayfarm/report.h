// Error against run time (docs/numerics.md): a high-quality reference render, a sweep of settings
// timed over several runs, each setting's error against the reference, the settings no
// other beats on both time and error, and the root-form stability table.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "rayfarm/compare.h"
#include "rayfarm/options.h"
#include "rayfarm/scene.h"
#include "rayfarm/stability.h"

namespace rayfarm {

struct ReportSettings {
  int reference_spp = 256;
  int reference_depth = 32;
  int runs = 3;                // timed runs per setting (the median is reported)
  long long max_pixels = 320 * 240;  // larger images are rendered smaller (same window)
  int threads = 0;
  std::vector<int> spp = {1, 2, 4, 8, 16, 32, 64};
  std::vector<int> depths = {0, 1, 2, 4, 8, 16};
  std::vector<double> bailouts = {0.01, 0.05, 0.2, 0.5};
  bool stability = true;
};

struct ReportRow {
  std::string sweep;  // "spp", "max_depth", "bailout"
  RenderOptions options;
  double time_ms = 0;  // median
  std::vector<double> times_ms;
  CompareResult error;
  bool pareto = false;  // no other setting is at least as fast and at least as accurate
};

struct Report {
  std::string scene_name;
  int width = 0;
  int height = 0;
  RenderOptions reference;
  double reference_ms = 0;
  std::vector<ReportRow> rows;
  std::vector<RootErrors> stability;
  std::string stability_note;  // why the table is empty, when it is
  // What the report left out or changed, and why (a setting the profile refuses, a render
  // that failed): said in report.md and by the command line.
  std::vector<std::string> notes;
  std::string error;  // no report at all: the reference cannot be rendered
};

using ReportProgress = std::function<void(int done, int total, const std::string& what)>;

Report run_report(const Scene& scene, const std::string& scene_name, const RenderOptions& base,
                  const ReportSettings& settings, const ReportProgress& progress = {});

std::string report_markdown(const Report& report);
std::string report_csv(const Report& report);
std::string report_svg(const Report& report);

// Marks the rows no other row beats on both time and RMSE.
void mark_pareto(std::vector<ReportRow>& rows);

}  // namespace rayfarm
