// The connection loop and socket stream of GuardedServer.
#include "connection.h"

#include "socket_peer.h"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

namespace rayfarm::server {
namespace {

using Clock = std::chrono::steady_clock;

struct ConnectionState {
  int fd = -1;
  bool head_complete = false;
  bool close_after = false;
  bool body_failed = false;  // a read of the body timed out, failed or met the end
  std::string head;          // the request line and headers as they arrived
  Clock::time_point head_deadline{};
  Clock::time_point body_start{};  // when the head was complete
  std::size_t body_bytes = 0;      // read since
};

bool same_name(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) ==
                  std::tolower(static_cast<unsigned char>(y));
         });
}

// Calls f(name, value) for each header line of a request head as it arrived (the value with
// the white space around it).
template <class F>
void each_header(std::string_view head, F&& f) {
  for (std::size_t at = head.find('\n'); at != std::string_view::npos;) {
    const std::size_t end = head.find('\n', at + 1);
    const std::string_view line =
        head.substr(at + 1, end == std::string_view::npos ? end : end - at - 1);
    at = end;
    if (const std::size_t colon = line.find(':'); colon != std::string_view::npos)
      f(line.substr(0, colon), line.substr(colon + 1));
  }
}

// The value of the head's Content-Length line; 0 when there is none or it is not one number
// (such a request is refused before its body is read, and its connection closed).
std::size_t declared_length(std::string_view head) {
  std::size_t length = 0;
  each_header(head, [&](std::string_view name, std::string_view value) {
    if (!same_name(name, "Content-Length")) return;
    std::size_t n = 0;
    bool digits = false;
    for (char c : value) {
      if (c >= '0' && c <= '9' && n < (std::size_t{1} << 60)) {
        n = n * 10 + static_cast<std::size_t>(c - '0');
        digits = true;
      } else if (c != ' ' && c != '\t' && c != '\r') {
        return;
      }
    }
    if (digits) length = n;
  });
  return length;
}

thread_local ConnectionState* current = nullptr;

int poll_for(int fd, short events, int timeout_ms) {
  pollfd p{fd, events, 0};
  for (;;) {
    int r = ::poll(&p, 1, timeout_ms);
    if (r >= 0 || errno != EINTR) return r;
  }
}

int ms_until(Clock::time_point t) {
  auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(t - Clock::now()).count();
  return static_cast<int>(std::clamp<long long>(ms, 0, 1 << 30));
}

void address_of(int fd, bool peer, std::string& ip, int& port) {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  int r = peer ? ::getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len)
               : ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  if (r != 0) return;
  char host[NI_MAXHOST], serv[NI_MAXSERV];
  if (::getnameinfo(reinterpret_cast<sockaddr*>(&addr), len, host, sizeof host, serv, sizeof serv,
                    NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
    ip = host;
    port = std::atoi(serv);
  }
}

// A connected socket with a small read buffer (the library reads the head a byte at a time).
// While the head of a request is incomplete, reads stop at its byte and time limits.
class SocketStream final : public httplib::Stream {
 public:
  SocketStream(int fd, ConnectionState& state, const ConnectionLimits& limits, int read_timeout_ms,
               int write_timeout_ms)
      : fd_(fd),
        state_(state),
        limits_(limits),
        read_timeout_ms_(read_timeout_ms),
        write_timeout_ms_(write_timeout_ms) {}

  bool buffered() const { return pos_ < len_; }

  bool is_readable() const override {
    return buffered() || poll_for(fd_, POLLIN, read_timeout_ms_) > 0;
  }

  // Writable and the peer still there (a departed event-stream client is noticed here).
  bool is_writable() const override {
    return poll_for(fd_, POLLOUT, write_timeout_ms_) > 0 && !farm::socket_closed_by_peer(fd_);
  }

  ssize_t read(char* ptr, size_t size) override {
    if (size == 0) return 0;
    if (!buffered()) {
      int timeout = read_timeout_ms_;
      if (!state_.head_complete) {
        if (state_.head.size() >= limits_.max_head_bytes) return -1;
        timeout = std::min(timeout, ms_until(state_.head_deadline));
        if (timeout == 0) return -1;
      } else {
        // The next byte of the body is due by the grace plus what the bytes so far earned.
        const auto earned = std::chrono::milliseconds(
            static_cast<long long>(1000.0 * static_cast<double>(state_.body_bytes) /
                                   static_cast<double>(std::max<std::size_t>(1, limits_.min_body_rate))));
        timeout = std::min(timeout, ms_until(state_.body_start + limits_.head_timeout + earned));
      }
      ssize_t n = -1;
      if (timeout > 0 && poll_for(fd_, POLLIN, timeout) > 0) {
        do n = ::recv(fd_, buf_, sizeof buf_, 0);
        while (n < 0 && errno == EINTR);
      }
      if (n <= 0) {
        if (state_.head_complete) state_.body_failed = true;
        return n;
      }
      pos_ = 0;
      len_ = static_cast<size_t>(n);
    }
    size_t n = std::min(size, len_ - pos_);
    std::memcpy(ptr, buf_ + pos_, n);
    pos_ += n;
    if (!state_.head_complete) state_.head.append(ptr, n);
    else state_.body_bytes += n;
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, size_t size) override {
    if (poll_for(fd_, POLLOUT, write_timeout_ms_) <= 0) return -1;
    ssize_t n;
    do n = ::send(fd_, ptr, size, MSG_NOSIGNAL);
    while (n < 0 && errno == EINTR);
    return n;
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    address_of(fd_, true, ip, port);
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    address_of(fd_, false, ip, port);
  }
  socket_t socket() const override { return fd_; }

 private:
  int fd_;
  ConnectionState& state_;
  const ConnectionLimits& limits_;
  int read_timeout_ms_;
  int write_timeout_ms_;
  char buf_[4096];
  size_t pos_ = 0, len_ = 0;
};

// Sends FIN after the answer, then reads and drops what the client still sends, briefly, so
// that closing with unread data (which sends a reset) cannot destroy the answer in flight.
void lingering_close(int fd) {
  ::shutdown(fd, SHUT_WR);
  const auto deadline = Clock::now() + std::chrono::milliseconds(500);
  std::size_t dropped = 0;
  char buf[16384];
  while (dropped < (1u << 20) && poll_for(fd, POLLIN, ms_until(deadline)) > 0) {
    ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    dropped += static_cast<size_t>(n);
  }
}

}  // namespace

void GuardedServer::head_complete() {
  if (current && !current->head_complete) {
    current->head_complete = true;
    current->body_start = Clock::now();
  }
}

bool GuardedServer::head_read() { return current && current->head_complete; }

bool GuardedServer::empty_header(std::string_view name) {
  bool empty = false;
  if (current)
    each_header(current->head, [&](std::string_view n, std::string_view value) {
      empty = empty ||
              (same_name(n, name) && value.find_first_not_of(" \t\r") == std::string_view::npos);
    });
  return empty;
}

bool GuardedServer::folded_header() {
  if (!current) return false;
  const std::string_view head = current->head;
  // Each line after the request line, up to the blank line that ends the head.
  for (std::size_t at = head.find('\n'); at != std::string_view::npos && at + 1 < head.size();
       at = head.find('\n', at + 1)) {
    const char first = head[at + 1];
    if (first == '\r' || first == '\n') break;
    if (first == ' ' || first == '\t') return true;
  }
  return false;
}

bool GuardedServer::body_cut_short() { return current && current->body_failed; }

bool GuardedServer::client_gone() { return current && farm::socket_closed_by_peer(current->fd); }

void GuardedServer::close_after(const httplib::Request& req) {
  if (current) current->close_after = true;
  // Said by the library, once, as for a request that asked to close (and so without the
  // Keep-Alive header it would add otherwise); a header of the answer would be a second.
  auto& headers = const_cast<httplib::Request&>(req).headers;
  headers.erase("Connection");
  headers.emplace("Connection", "close");
}

bool GuardedServer::process_and_close_socket(socket_t sock) {
  open_.fetch_add(1);
  ConnectionState state;
  current = &state;
  auto ms = [](time_t sec, time_t usec) { return static_cast<int>(sec * 1000 + usec / 1000); };
  SocketStream strm(sock, state, limits_, ms(read_timeout_sec_, read_timeout_usec_),
                    ms(write_timeout_sec_, write_timeout_usec_));
  // The next request: already buffered, or arriving within the keep-alive timeout. Polled in
  // short steps so that stop() does not wait for idle connections.
  auto next_request = [&] {
    if (strm.buffered()) return true;
    const auto deadline = Clock::now() + std::chrono::seconds(keep_alive_timeout_sec_);
    while (svr_sock_ != INVALID_SOCKET) {
      int r = poll_for(sock, POLLIN, std::min(50, ms_until(deadline)));
      if (r != 0) return r > 0;
      if (Clock::now() >= deadline) return false;
    }
    return false;
  };
  bool ret = false;
  for (size_t left = keep_alive_max_count_; left > 0 && svr_sock_ != INVALID_SOCKET; --left) {
    if (!next_request()) break;
    state = ConnectionState{};
    state.fd = sock;
    state.head_deadline = Clock::now() + limits_.head_timeout;
    bool connection_closed = false;
    ret = process_request(strm, left == 1, connection_closed, nullptr);
    // A head the library refused itself (bad request line, headers, range) never reached
    // the handlers; whatever follows it is not trusted either. Nor is what follows a body
    // not read to its end (cut short, or refused part way: a multipart body that does not
    // parse): its rest would be read as the next request.
    if (!ret || connection_closed || state.close_after || !state.head_complete) break;
    if (state.body_failed || state.body_bytes < declared_length(state.head)) {
      state.close_after = true;
      break;
    }
  }
  current = nullptr;
  if (state.close_after) lingering_close(sock);
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  open_.fetch_sub(1);
  return ret;
}

}  // namespace rayfarm::server
