// Following a job on rayfarmd to its end: its event stream (GET /jobs/ID/events), or polling
// GET /jobs/ID where the stream is not available (an older server, or too many streams open).
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <memory>
#include <cstdio>
#include <iostream>
#include <thread>

#include "cli_common.h"
#include "remote.h"

namespace rayfarm::cli {
namespace {

using Clock = std::chrono::steady_clock;

std::atomic<bool> interrupted{false};
std::atomic<bool> interrupt_handled{false};
void on_sigint(int) { interrupted = true; }

// Ctrl-C while a read waits on a silent server (an event stream with nothing to say, an image
// that stalls): the reads see the flag only when bytes come. A watchdog gives them a moment,
// then cancels the job itself (waiting at most two seconds for the answer) and ends the
// program with 130; nothing has been written by then (an image is saved only once whole).
void start_watchdog(const Remote& remote, const std::string& id) {
  std::thread([remote, id] {
    while (!interrupted) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (int i = 0; i < 10 && !interrupt_handled; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (interrupt_handled.exchange(true)) return;  // the reads saw it: theirs to cancel
    auto said = std::make_shared<std::atomic<bool>>(false);
    std::thread([remote, id, said] {
      auto res = remote.client()->del("/jobs/" + id, remote.headers());
      if (said->exchange(true)) return;
      std::cerr << "\nrayfarm: interrupted; "
                << (res && res->status == 200 ? "canceled job " : "could not cancel job ") << id
                << "\n";
      std::_Exit(kInterrupted);
    }).detach();
    std::this_thread::sleep_for(std::chrono::seconds(2));
    if (said->exchange(true)) return;
    std::cerr << "\nrayfarm: interrupted; the server did not answer the cancel of job " << id
              << "\n";
    std::_Exit(kInterrupted);
  }).detach();
}

bool is_final(const std::string& state) {
  return state == "done" || state == "failed" || state == "canceled";
}

// The remote job's bar reads as the local one (spp done of the spp asked for) and names the
// job, so that another shell can wait for it or cancel it.
class RemoteBar {
 public:
  RemoteBar(const std::string& id, bool quiet)
      : id_(id.substr(0, 8)), quiet_(quiet), terminal_(isatty(STDERR_FILENO)) {}

  void show(const nlohmann::json& status) {
    if (quiet_) return;
    const std::string state = status.value("state", "?");
    const bool final_state = is_final(state);
    const auto now = Clock::now();
    // A log gets a line every few seconds, and a last one only if it had others.
    if (!terminal_ && (final_state ? !drawn_ : now - last_ < std::chrono::seconds(2))) return;
    last_ = now;
    const double fraction = status.value("progress", 0.0);
    std::string spp = std::to_string(status.value("spp_done", 0));
    if (status.contains("options") && status["options"].is_object() &&
        status["options"].contains("spp") && status["options"]["spp"].is_number_integer())
      spp += "/" + std::to_string(status["options"]["spp"].get<int>());
    if (terminal_) {
      constexpr int kWidth = 30;
      std::string bar(static_cast<size_t>(fraction * kWidth + 0.5), '#');
      bar.resize(kWidth, '.');
      std::fprintf(stderr, "\r[%s] %5.1f%%  %-8s spp %s", bar.c_str(), fraction * 100,
                   state.c_str(), spp.c_str());
      if (status.value("queue_position", 0) > 0)
        std::fprintf(stderr, "  queue %d", status.value("queue_position", 0));
      if (status.contains("error_estimate") && status["error_estimate"].is_number())
        std::fprintf(stderr, "  error %.2f", status["error_estimate"].get<double>());
      std::fprintf(stderr, "  job %s   ", id_.c_str());
    } else {
      std::fprintf(stderr, "job %s: %s %.1f%% spp %s\n", id_.c_str(), state.c_str(), fraction * 100,
                   spp.c_str());
    }
    std::fflush(stderr);
    drawn_ = true;
  }

  // Ends the bar's line, before any other message.
  void end() {
    if (drawn_ && terminal_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  std::string id_;
  bool quiet_;
  bool terminal_;
  bool drawn_ = false;
  Clock::time_point last_ = Clock::now();
};

// One server-sent event: its name and its data (the job's status, as JSON).
struct Event {
  std::string name = "message";
  std::string data;
};

Event parse_event(const std::string& block) {
  Event e;
  size_t start = 0;
  while (start <= block.size()) {
    size_t end = block.find('\n', start);
    if (end == std::string::npos) end = block.size();
    const std::string line = block.substr(start, end - start);
    auto value = [&](size_t prefix) {
      std::string v = line.substr(prefix);
      if (!v.empty() && v.front() == ' ') v.erase(0, 1);
      return v;
    };
    if (line.rfind("event:", 0) == 0)
      e.name = value(6);
    else if (line.rfind("data:", 0) == 0)
      e.data += value(5);
    start = end + 1;
  }
  return e;
}

constexpr size_t kMaxEventBytes = size_t{1} << 20;

enum class StreamEnd { final_status, user_interrupt, shutdown, unavailable };

// Reads the event stream until the job ends. `unavailable` when the server offers none or
// the stream breaks off: polling then finds out why, or carries on.
StreamEnd read_events(const Remote& remote, const std::string& id, RemoteBar& bar,
                      bool cancel_on_interrupt, nlohmann::json& final_status) {
  StreamEnd end = StreamEnd::unavailable;
  std::string buffer;
  remote.client()->get_stream(
      "/jobs/" + id + "/events", remote.headers(), [&](const char* data, size_t size) {
        if (interrupted && cancel_on_interrupt) {
          end = StreamEnd::user_interrupt;
          return false;
        }
        size_t from = buffer.empty() ? 0 : buffer.size() - 1;  // where a "\n\n" can start
        for (size_t i = 0; i < size; ++i)
          if (data[i] != '\r') buffer += data[i];
        for (size_t at; (at = buffer.find("\n\n", from)) != std::string::npos; from = 0) {
          const Event e = parse_event(buffer.substr(0, at));
          buffer.erase(0, at + 2);
          if (e.name == "shutdown") {
            end = StreamEnd::shutdown;
            return false;
          }
          if (e.data.empty()) continue;  // a keep-alive comment
          auto status = nlohmann::json::parse(e.data, nullptr, false);
          if (status.is_discarded() || !status.is_object()) continue;
          bar.show(status);
          if (is_final(status.value("state", ""))) {
            final_status = std::move(status);
            end = StreamEnd::final_status;
            return false;
          }
        }
        // A job's status is a few hundred bytes: an event that never ends is no status, and
        // polling takes over.
        return buffer.size() <= kMaxEventBytes;
      });
  return end;
}

}  // namespace

std::optional<nlohmann::json> follow_job(const Remote& remote, const std::string& id, bool quiet,
                                         bool cancel_on_interrupt, int& exit_code) {
  if (cancel_on_interrupt) {
    std::signal(SIGINT, on_sigint);
    start_watchdog(remote, id);
  }
  RemoteBar bar(id, quiet);
  auto cancel = [&]() -> std::optional<nlohmann::json> {
    // (the watchdog took it: it ends the program)
    if (interrupt_handled.exchange(true)) std::this_thread::sleep_for(std::chrono::hours(1));
    bar.end();
    auto res = remote.client()->del("/jobs/" + id, remote.headers());
    std::cerr << "rayfarm: interrupted; "
              << (res && res->status == 200 ? "canceled job " : "could not cancel job ") << id
              << "\n";
    exit_code = kInterrupted;
    return std::nullopt;
  };

  nlohmann::json status;
  switch (read_events(remote, id, bar, cancel_on_interrupt, status)) {
    case StreamEnd::final_status:
      bar.end();
      return status;
    case StreamEnd::user_interrupt:
      return cancel();
    case StreamEnd::shutdown:
      bar.end();
      std::cerr << "rayfarm: the server at " << remote.url << " is shutting down; job " << id
                << " was not finished (with a --results-dir it is kept: rayfarm wait " << id
                << " once the server is back)\n";
      exit_code = kServerError;
      return std::nullopt;
    case StreamEnd::unavailable:
      break;
  }

  auto client = remote.client();
  for (;;) {
    if (interrupted && cancel_on_interrupt) return cancel();
    auto res = client->get("/jobs/" + id, remote.headers());
    if (!res || res->status != 200) {
      bar.end();
      exit_code = report_http_error(res, "job " + id);
      return std::nullopt;
    }
    status = nlohmann::json::parse(res->body, nullptr, false);
    if (status.is_discarded() || !status.is_object()) {
      bar.end();
      std::cerr << "rayfarm: the server sent a status that is not JSON\n";
      exit_code = kServerError;
      return std::nullopt;
    }
    bar.show(status);
    if (is_final(status.value("state", ""))) {
      bar.end();
      return status;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

}  // namespace rayfarm::cli
