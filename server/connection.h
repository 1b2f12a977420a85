// rayfarmd's HTTP connections: cpp-httplib's server with its connection loop replaced, because
// 0.11.4's reads a request line and headers of any length for as long as a client trickles
// them, and keeps a connection open after a request whose body it never read (the body is
// then parsed as further requests). Here the request head is bounded in bytes and in time, a
// handler that refuses a request before its body marks the connection to close after the
// answer (with a short lingering close so the answer is not lost to a reset), and idle
// keep-alive connections end as soon as the server stops.
#pragma once

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstddef>
#include <string_view>

namespace rayfarm::server {

struct ConnectionLimits {
  std::size_t max_head_bytes = 64 * 1024;        // request line and headers together
  std::chrono::milliseconds head_timeout{10000};  // to receive them, from the first byte
  // The body then arrives at this many bytes a second at least, after a grace of
  // head_timeout: a client that trickles a body (a byte every few seconds keeps each read
  // under the read timeout) cannot hold a connection thread for long, and 64 of them cannot
  // silence the server. A slow but real upload (a 16 MB scene over 1 Mbit/s) still fits.
  std::size_t min_body_rate = 8 * 1024;
};

class GuardedServer : public httplib::Server {
 public:
  explicit GuardedServer(ConnectionLimits limits) : limits_(limits) {}

  // For handlers on the connection's thread. The request head has been read: the head limits
  // no longer apply (the body has its own, the payload limit). Call it from the pre-routing
  // and expect-100 handlers: a request that never reaches them (one the library refused
  // itself) ends its connection.
  static void head_complete();
  // Whether head_complete() was called for the request being answered: false where the
  // library refused the request line or a header itself (a malformed line, or one over its
  // 8 KiB).
  static bool head_read();
  // Whether the request being answered has a header line `name` (any case) with an empty
  // value, which the library drops: read from the head as it arrived.
  static bool empty_header(std::string_view name);
  // Whether a header line of the request being answered begins with white space: obsolete
  // line folding (RFC 9112 §5.2), which a server must refuse or unfold.
  static bool folded_header();
  // Whether the body of the request being answered stopped before its Content-Length: it
  // fell behind min_body_rate, or the client stopped sending. The connection ends after the
  // answer, as after any request whose body was not read to its end.
  static bool body_cut_short();
  // This answer is sent without reading the request's body: the connection ends after it.
  static void close_after(const httplib::Request& req);
  // Whether the client of the request being answered has closed its connection (its end of
  // file is waiting; a pipelined next request is not that): no one will read the answer. A
  // look, no wait; false off a connection's thread.
  static bool client_gone();

  // After binding: the library listens with a backlog of 5, so a burst of new connections
  // (a lab class submitting at once) meets dropped SYNs and 1 s retries. Listening again on
  // the bound socket raises it (Linux takes a new backlog this way).
  void widen_backlog() {
    if (svr_sock_ != INVALID_SOCKET) ::listen(svr_sock_, SOMAXCONN);
  }

  // Connections a thread is serving, from taking them until they are closed.
  int open_connections() const { return open_.load(); }

 private:
  bool process_and_close_socket(socket_t sock) override;

  ConnectionLimits limits_;
  std::atomic<int> open_{0};
};

}  // namespace rayfarm::server
