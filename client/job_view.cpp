// A job's status as people read it: `rayfarm status`, the table of `rayfarm jobs`, and the
// summary line of a remote render (raw JSON stays one --json away).
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "remote.h"

namespace rayfarm::cli {
namespace {

std::string text_of(const nlohmann::json& j, const char* key) {
  return j.contains(key) && j[key].is_string() ? j[key].get<std::string>() : "";
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

const nlohmann::json& options_of(const nlohmann::json& status) {
  static const nlohmann::json kNone = nlohmann::json::object();
  return status.contains("options") && status["options"].is_object() ? status["options"] : kNone;
}

std::string size_of(const nlohmann::json& status) {
  const auto& o = options_of(status);
  return std::to_string(o.value("width", 0)) + "x" + std::to_string(o.value("height", 0));
}

// "19/64" while rendering, "64" when all were done.
std::string spp_of(const nlohmann::json& status) {
  const auto& o = options_of(status);
  // (64-bit: a hostile server's 2^40 must not wrap to a negative number)
  const auto done =
      status.contains("spp_done") && status["spp_done"].is_number_integer()
          ? status["spp_done"].get<long long>()
          : 0LL;
  const auto asked =
      o.contains("spp") && o["spp"].is_number_integer() ? o["spp"].get<long long>() : 0LL;
  if (asked == 0 || done == asked) return std::to_string(done);
  return std::to_string(done) + "/" + std::to_string(asked);
}

bool cached(const nlohmann::json& status) {
  return status.contains("stats") && status["stats"].is_object() &&
         status["stats"].value("cache", "") == "hit";
}

std::string state_of(const nlohmann::json& status) {
  const std::string state = status.value("state", "?");
  std::string out = state;
  if (state == "queued" && status.value("queue_position", 0) > 0)
    out += ", position " + std::to_string(status.value("queue_position", 0)) + " in the queue";
  if (state == "running") {
    out += ", " + fixed(100 * status.value("progress", 0.0), 0) + "%";
    if (status.contains("eta_ms") && status["eta_ms"].is_number())
      out += ", about " + fixed(status["eta_ms"].get<double>() / 1000, 1) + " s left";
  }
  if (state == "done" && cached(status)) out += " (from the server's cache)";
  if (status.contains("error") && status["error"].is_object())
    out += ": " + status["error"].value("message", "");
  return out;
}

}  // namespace

std::string status_text(const nlohmann::json& status, const std::string& url) {
  std::ostringstream o;
  auto row = [&](const char* label, const std::string& value) {
    if (!value.empty()) o << std::left << std::setw(10) << label << value << "\n";
  };
  const std::string id = status.value("id", "");
  const std::string state = status.value("state", "");
  const auto& opts = options_of(status);
  row("job", id);
  row("state", state_of(status));
  std::string image = size_of(status) + ", spp " + spp_of(status);
  for (const char* key : {"max_depth", "profile", "camera"})
    if (opts.contains(key) && !(opts[key].is_string() && opts[key].get<std::string>().empty()))
      image += std::string(", ") + key + " " +
               (opts[key].is_string() ? opts[key].get<std::string>() : opts[key].dump());
  row("image", image);
  row("owner", text_of(status, "owner"));
  row("created", text_of(status, "created_at"));
  row("started", text_of(status, "started_at"));
  row("finished", text_of(status, "finished_at"));
  if (state == "done" && !cached(status) && status.contains("stats")) {
    const auto& st = status["stats"];
    row("render", fixed(st.value("render_ms", 0.0), 1) + " ms, " +
                      fixed(st.value("rays_per_second", 0.0) / 1e6, 2) + " Mrays/s");
  }
  if (status.contains("warnings") && status["warnings"].is_array())
    for (const auto& w : status["warnings"])
      if (w.is_object()) row("warning", w.value("message", ""));
  if (state == "done")
    row("fetch", "rayfarm wait " + id + " -o FILE.png");
  else if (state == "queued" || state == "running")
    row("follow", "rayfarm wait " + id + " -o FILE.png");
  row("status", url + "/jobs/" + id);
  return o.str();
}

std::string jobs_table(const nlohmann::json& jobs) {
  std::ostringstream o;
  auto line = [&](const std::string& id, const std::string& state, const std::string& done,
                  const std::string& size, const std::string& spp, const std::string& created) {
    // A space after each column, however wide its value (SPP 219/1024, SIZE 65535x65535).
    o << std::left << std::setw(33) << id << ' ' << std::setw(9) << state << ' ' << std::right
      << std::setw(5) << done << "  " << std::left << std::setw(10) << size << ' '
      << std::setw(7) << spp << ' ' << created << "\n";
  };
  line("ID", "STATE", "DONE", "SIZE", "SPP", "CREATED");
  for (const auto& j : jobs)
    line(j.value("id", ""), j.value("state", ""), fixed(100 * j.value("progress", 0.0), 0) + "%",
         size_of(j), spp_of(j), text_of(j, "created_at"));
  return o.str();
}

std::string summary_line(const nlohmann::json& status, const std::string& out,
                         const std::string& url) {
  std::string line = (out == "-" ? std::string("<stdout>") : out) + ": " + size_of(status) +
                     ", spp " + spp_of(status);
  if (cached(status)) {
    line += ", cached on " + url;
  } else {
    const nlohmann::json& st =
        status.contains("stats") ? status["stats"] : nlohmann::json::object();
    line += ", " + fixed(st.value("render_ms", 0.0), 1) + " ms on " + url + ", " +
            fixed(st.value("rays_per_second", 0.0) / 1e6, 2) + " Mrays/s";
  }
  return line + " (job " + status.value("id", "") + ")";
}

}  // namespace rayfarm::cli
