// The error-against-time report: sweep, measure, tabulate, plot.
#include "rayfarm/report.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "rayfarm/render.h"

namespace rayfarm {
namespace {

std::string fixed(double v, int digits) {
  if (std::isinf(v)) return "inf";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n == 0 ? 0 : n % 2 ? v[n / 2] : (v[n / 2 - 1] + v[n / 2]) / 2;
}

std::string setting_label(const ReportRow& r) {
  const RenderOptions& o = r.options;
  std::string s =
      "spp " + std::to_string(o.spp) + ", depth " + std::to_string(o.effective_max_depth());
  if (o.bailout > 0) s += ", bailout " + format_number(o.bailout);
  s += ", " + std::string(to_string(o.precision));
  return s;
}

}  // namespace

void mark_pareto(std::vector<ReportRow>& rows) {
  for (ReportRow& r : rows) {
    r.pareto = true;
    for (const ReportRow& other : rows) {
      if (&other == &r) continue;
      bool no_worse = other.time_ms <= r.time_ms && other.error.rmse <= r.error.rmse;
      bool better = other.time_ms < r.time_ms || other.error.rmse < r.error.rmse;
      if (no_worse && better) {
        r.pareto = false;
        break;
      }
    }
  }
}

Report run_report(const Scene& scene, const std::string& scene_name, const RenderOptions& base,
                  const ReportSettings& settings, const ReportProgress& progress) {
  Report report;
  report.scene_name = scene_name;
  const Camera& cam = scene.cameras.at(scene.find_camera(base.camera).value_or(0));
  RenderOptions sized = base;
  int w = base.width > 0 ? base.width : cam.width;
  int h = base.height > 0 ? base.height : cam.height;
  while (static_cast<long long>(w) * h > settings.max_pixels && w > 1 && h > 1) {
    w = std::max(1, w * 3 / 4);
    h = std::max(1, h * 3 / 4);
  }
  sized.width = w;
  sized.height = h;
  sized.target_error = 0;
  sized.time_limit = 0;
  // The sweeps set these themselves; outside its own sweep, each is the reference's.
  if (base.bailout > 0)
    report.notes.push_back("bailout " + format_number(base.bailout) +
                           " is not used: the bailout sweep sets it, and the other rows use none");
  if (base.precision != Precision::f64)
    report.notes.push_back("precision float is not used: the spp sweep renders both "
                           "precisions, and the other rows double");
  sized.bailout = 0;
  sized.precision = Precision::f64;
  report.width = w;
  report.height = h;

  report.reference = sized;
  report.reference.spp = settings.reference_spp;
  report.reference.max_depth = std::max(settings.reference_depth, base.effective_max_depth());
  if (report.reference.effective_max_depth() != settings.reference_depth)
    report.notes.push_back("the reference's max_depth is " +
                           std::to_string(report.reference.effective_max_depth()) +
                           ", the renders' own, not " +
                           std::to_string(settings.reference_depth) +
                           ": a shallower reference would count their deeper bounces as error");
  if (std::string conflict = profile_conflict(report.reference); !conflict.empty()) {
    report.error = "the reference cannot be rendered: " + conflict;
    return report;
  }

  std::vector<RenderOptions> settings_list;
  std::vector<std::string> sweeps;
  // A setting the profile refuses is left out, said once per reason (not a row of zeros).
  std::vector<std::string> refused;
  auto add = [&](const RenderOptions& o, const char* sweep) {
    if (std::string conflict = profile_conflict(o); !conflict.empty()) {
      const std::string note = std::string(sweep) + " sweep: left out where " + conflict;
      if (std::find(refused.begin(), refused.end(), note) == refused.end()) refused.push_back(note);
      return;
    }
    settings_list.push_back(o);
    sweeps.push_back(sweep);
  };
  for (Precision p : {Precision::f64, Precision::f32})
    for (int spp : settings.spp) {
      RenderOptions o = sized;
      o.spp = spp;
      o.precision = p;
      add(o, "spp");
    }
  // The depth and bailout sweeps at 16 samples, or the reference's if it has fewer: against
  // a reference of fewer samples, the difference would be the reference's noise.
  const int sweep_spp = std::min(16, std::max(1, settings.reference_spp));
  for (int d : settings.depths) {
    if (d == base.effective_max_depth()) continue;  // already in the spp sweep
    RenderOptions o = sized;
    o.max_depth = d;
    o.spp = sweep_spp;
    add(o, "max_depth");
  }
  for (double b : settings.bailouts) {
    RenderOptions o = sized;
    o.bailout = b;
    o.spp = sweep_spp;
    add(o, "bailout");
  }
  report.notes.insert(report.notes.end(), refused.begin(), refused.end());

  const int stability_steps = settings.stability ? 5 : 0;
  const int total = 1 + static_cast<int>(settings_list.size()) + stability_steps;
  int done = 0;
  auto step = [&](const std::string& what) {
    if (progress) progress(done, total, what);
  };

  step("reference (spp " + std::to_string(report.reference.spp) + ")");
  auto t0 = std::chrono::steady_clock::now();
  std::string why;
  Image reference =
      render_image(scene, report.reference, settings.threads, nullptr, {}, nullptr, &why);
  report.reference_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (reference.width == 0) {
    report.error = "the reference cannot be rendered: " + why;
    return report;
  }
  ++done;

  for (size_t i = 0; i < settings_list.size(); ++i) {
    ReportRow row;
    row.sweep = sweeps[i];
    row.options = settings_list[i];
    step(setting_label(row));
    Image image;
    std::string error;
    for (int run = 0; run < std::max(1, settings.runs) && error.empty(); ++run) {
      auto start = std::chrono::steady_clock::now();
      image = render_image(scene, row.options, settings.threads, nullptr, {}, nullptr, &error);
      row.times_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count());
    }
    ++done;
    std::optional<CompareResult> measured;
    if (image.width > 0) measured = compare_images(reference, image, {}, &error);
    if (!measured) {
      report.notes.push_back(setting_label(row) + ": left out, it cannot be rendered: " + error);
      continue;
    }
    row.time_ms = median(row.times_ms);
    row.error = *measured;
    report.rows.push_back(row);
  }
  mark_pareto(report.rows);

  if (settings.stability) {
    if (scene.count<Sphere>() > 2000) {
      report.stability_note = "left out: " + std::to_string(scene.count<Sphere>()) +
                              " spheres is too many for the brute-force analysis";
      done += stability_steps;
    } else {
      for (RootForm form : {RootForm::naive, RootForm::stable})
        for (Precision p : {Precision::f32, Precision::f64}) {
          step(std::string("root forms: ") + std::string(to_string(form)) + " " +
               std::string(to_string(p)));
          report.stability.push_back(root_errors(scene, base, form, p));
          ++done;
        }
      ++done;
    }
  }
  if (progress) progress(total, total, "done");
  return report;
}

std::string report_markdown(const Report& r) {
  std::ostringstream o;
  o << "# Error against run time: " << r.scene_name << "\n\n"
    << "Rendered at " << r.width << "x" << r.height << ". Reference: spp " << r.reference.spp
    << ", max_depth " << r.reference.effective_max_depth() << ", double ("
    << fixed(r.reference_ms, 0) << " ms). Times are medians of "
    << (r.rows.empty() ? 0 : r.rows[0].times_ms.size()) << " runs; errors are in 8-bit levels against the reference. **Bold** settings: no other "
       "setting is both at least as fast and at least as accurate.\n\n";
  for (const std::string& note : r.notes) o << "- Note: " << note << ".\n";
  if (!r.notes.empty()) o << "\n";
  o
    << "| sweep | spp | max_depth | bailout | precision | time ms | RMSE | PSNR dB | max | "
       "pixels off > 1 |\n|---|---:|---:|---:|---|---:|---:|---:|---:|---:|\n";
  for (const ReportRow& row : r.rows) {
    const RenderOptions& x = row.options;
    std::string b = row.pareto ? "**" : "";
    double total = static_cast<double>(row.error.width) * row.error.height;
    o << "| " << row.sweep << " | " << b << x.spp << b << " | " << x.effective_max_depth() << " | "
      << format_number(x.bailout) << " | " << to_string(x.precision) << " | " << b
      << fixed(row.time_ms, 1) << b << " | " << b << fixed(row.error.rmse, 3) << b << " | "
      << fixed(row.error.psnr, 1) << " | " << row.error.max_abs << " | "
      << fixed(total > 0 ? 100.0 * row.error.off_by_more_than_1 / total : 0, 2) << "% |\n";
  }
  o << "\n## Ray/sphere roots: textbook and stable forms\n\n";
  if (r.stability.empty()) {
    o << (r.stability_note.empty() ? "Not computed." : r.stability_note) << "\n";
  } else {
    o << "Primary rays against the stable form in long double.\n\n"
      << "| form | precision | rays | reference hits | wrong hit/miss | wrong sphere | max "
         "relative error of t |\n|---|---|---:|---:|---:|---:|---:|\n";
    for (const RootErrors& e : r.stability)
      o << "| " << to_string(e.form) << " | " << to_string(e.precision) << " | " << e.rays
        << " | " << e.reference_hits << " | " << e.wrong_hit_miss << " | " << e.wrong_object
        << " | " << (e.max_relative_t_error > 0 ? format_number(e.max_relative_t_error) : "0")
        << " |\n";
  }
  return o.str();
}

std::string report_csv(const Report& r) {
  std::ostringstream o;
  o << "sweep,spp,max_depth,bailout,precision,time_ms,rmse,psnr,max_abs,mean_abs,"
       "off_by_more_than_1,pareto\n";
  for (const ReportRow& row : r.rows) {
    const RenderOptions& x = row.options;
    o << row.sweep << "," << x.spp << "," << x.effective_max_depth() << ","
      << format_number(x.bailout) << "," << to_string(x.precision) << "," << fixed(row.time_ms, 3) << ","
      << fixed(row.error.rmse, 6) << "," << fixed(row.error.psnr, 3) << "," << row.error.max_abs
      << "," << fixed(row.error.mean_abs, 6) << "," << row.error.off_by_more_than_1 << ","
      << (row.pareto ? 1 : 0) << "\n";
  }
  return o.str();
}

std::string report_svg(const Report& r) {
  constexpr double kW = 720, kH = 480, kLeft = 70, kRight = 200, kTop = 40, kBottom = 50;
  constexpr double kFloor = 0.01;  // RMSE 0 is drawn at this level on the log axis
  double tmin = 1e300, tmax = 0, emin = 1e300, emax = 0;
  for (const ReportRow& row : r.rows) {
    double e = std::max(row.error.rmse, kFloor);
    tmin = std::min(tmin, row.time_ms), tmax = std::max(tmax, row.time_ms);
    emin = std::min(emin, e), emax = std::max(emax, e);
  }
  if (r.rows.empty()) tmin = tmax = emin = emax = 1;
  double lt0 = std::floor(std::log10(std::max(tmin, 1e-3))), lt1 = std::ceil(std::log10(std::max(tmax, 1e-3)));
  double le0 = std::floor(std::log10(emin)), le1 = std::ceil(std::log10(emax));
  if (lt1 <= lt0) lt1 = lt0 + 1;
  if (le1 <= le0) le1 = le0 + 1;
  auto x = [&](double t) {
    return kLeft + (std::log10(std::max(t, 1e-3)) - lt0) / (lt1 - lt0) * (kW - kLeft - kRight);
  };
  auto y = [&](double e) {
    return kH - kBottom - (std::log10(std::max(e, kFloor)) - le0) / (le1 - le0) * (kH - kTop - kBottom);
  };
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
    << "\" font-family=\"sans-serif\" font-size=\"11\">\n"
    << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    << "<text x=\"" << kLeft << "\" y=\"22\" font-size=\"14\">Error against time: "
    << r.scene_name << " (" << r.width << "x" << r.height << ")</text>\n";
  for (double d = lt0; d <= lt1; ++d) {
    double px = x(std::pow(10, d));
    o << "<line x1=\"" << px << "\" y1=\"" << kTop << "\" x2=\"" << px << "\" y2=\""
      << kH - kBottom << "\" stroke=\"#ddd\"/><text x=\"" << px << "\" y=\"" << kH - kBottom + 16
      << "\" text-anchor=\"middle\">" << format_number(std::pow(10, d)) << "</text>\n";
  }
  for (double d = le0; d <= le1; ++d) {
    double py = y(std::pow(10, d));
    o << "<line x1=\"" << kLeft << "\" y1=\"" << py << "\" x2=\"" << kW - kRight << "\" y2=\""
      << py << "\" stroke=\"#ddd\"/><text x=\"" << kLeft - 6 << "\" y=\"" << py + 4
      << "\" text-anchor=\"end\">" << format_number(std::pow(10, d)) << "</text>\n";
  }
  o << "<text x=\"" << (kLeft + kW - kRight) / 2 << "\" y=\"" << kH - 10
    << "\" text-anchor=\"middle\">time (ms, median, log)</text>\n"
    << "<text transform=\"translate(16," << (kTop + kH - kBottom) / 2
    << ") rotate(-90)\" text-anchor=\"middle\">RMSE vs reference (8-bit levels, log)</text>\n";
  std::vector<const ReportRow*> front;
  for (const ReportRow& row : r.rows)
    if (row.pareto) front.push_back(&row);
  std::sort(front.begin(), front.end(), [](auto* a, auto* b) { return a->time_ms < b->time_ms; });
  if (front.size() > 1) {
    o << "<polyline fill=\"none\" stroke=\"#c00\" stroke-width=\"1.5\" points=\"";
    for (auto* row : front) o << x(row->time_ms) << "," << y(row->error.rmse) << " ";
    o << "\"/>\n";
  }
  for (const ReportRow& row : r.rows) {
    double px = x(row.time_ms), py = y(row.error.rmse);
    const char* colour = row.sweep == "spp" ? (row.options.precision == Precision::f64 ? "#1f5fbf" : "#2a9d3a")
                         : row.sweep == "max_depth" ? "#8a4fbf" : "#d08a00";
    if (row.options.precision == Precision::f32)
      o << "<rect x=\"" << px - 4 << "\" y=\"" << py - 4 << "\" width=\"8\" height=\"8\" fill=\""
        << colour << "\"";
    else
      o << "<circle cx=\"" << px << "\" cy=\"" << py << "\" r=\"4\" fill=\"" << colour << "\"";
    if (row.pareto) o << " stroke=\"#c00\" stroke-width=\"2\"";
    o << "><title>" << setting_label(row) << ": " << fixed(row.time_ms, 1) << " ms, RMSE "
      << fixed(row.error.rmse, 3) << "</title></" << (row.options.precision == Precision::f32 ? "rect" : "circle") << ">\n";
    if (row.sweep == "spp" && row.options.precision == Precision::f64)
      o << "<text x=\"" << px + 6 << "\" y=\"" << py - 6 << "\" fill=\"#555\">" << row.options.spp
        << "</text>\n";
  }
  double lx = kW - kRight + 15;
  const char* names[] = {"spp sweep, double", "spp sweep, float", "max_depth sweep (spp 16)",
                         "bailout sweep (spp 16)", "not beaten on both axes"};
  const char* colours[] = {"#1f5fbf", "#2a9d3a", "#8a4fbf", "#d08a00", "#c00"};
  for (int i = 0; i < 5; ++i) {
    double ly = kTop + 10 + i * 20;
    if (i == 4)
      o << "<line x1=\"" << lx - 5 << "\" y1=\"" << ly << "\" x2=\"" << lx + 5 << "\" y2=\"" << ly
        << "\" stroke=\"#c00\" stroke-width=\"2\"/>";
    else if (i == 1)
      o << "<rect x=\"" << lx - 4 << "\" y=\"" << ly - 4 << "\" width=\"8\" height=\"8\" fill=\""
        << colours[i] << "\"/>";
    else
      o << "<circle cx=\"" << lx << "\" cy=\"" << ly << "\" r=\"4\" fill=\"" << colours[i] << "\"/>";
    o << "<text x=\"" << lx + 10 << "\" y=\"" << ly + 4 << "\">" << names[i] << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace rayfarm
