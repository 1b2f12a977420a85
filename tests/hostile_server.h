// A server that answers every request with what a test scripts for it, byte for byte: for
// the clients' defences against answers that never end or announce more than they should.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace rayfarm::test {

class HostileServer {
 public:
  // The connection's socket, and the request line ("GET /jobs/x HTTP/1.1"). Send with send()
  // below: it stops (false) when the client has gone or the server is stopping.
  using Handler = std::function<void(HostileServer&, int fd, const std::string& request_line)>;

  explicit HostileServer(Handler handler) : handler_(std::move(handler)) {
    listen_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    if (listen_ < 0 || ::bind(listen_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
        ::listen(listen_, 16) != 0 ||
        ::getsockname(listen_, reinterpret_cast<sockaddr*>(&a), &len) != 0)
      return;
    url_ = "http://127.0.0.1:" + std::to_string(ntohs(a.sin_port));
    acceptor_ = std::thread([this] { accept_loop(); });
  }

  ~HostileServer() {
    stopping_ = true;
    ::shutdown(listen_, SHUT_RDWR);
    if (acceptor_.joinable()) acceptor_.join();
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::thread& t : connections_) t.join();
    ::close(listen_);
  }

  const std::string& url() const { return url_; }  // empty if the socket could not be set up

  bool send(int fd, const std::string& bytes) {
    for (std::size_t at = 0; at < bytes.size();) {
      if (stopping_) return false;
      const ssize_t n = ::send(fd, bytes.data() + at, bytes.size() - at, MSG_NOSIGNAL);
      if (n <= 0) return false;
      at += static_cast<std::size_t>(n);
    }
    return true;
  }

 private:
  void accept_loop() {
    for (;;) {
      const int fd = ::accept(listen_, nullptr, nullptr);
      if (fd < 0) return;  // shut down
      // A client that stops reading cannot hold a sender (or the destructor) for long.
      const timeval second{1, 0};
      ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &second, sizeof second);
      ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &second, sizeof second);
      std::lock_guard<std::mutex> lock(mutex_);
      connections_.emplace_back([this, fd] {
        // The request's head; a body (a POST's) is not read.
        std::string head;
        char c;
        while (head.find("\r\n\r\n") == std::string::npos && ::recv(fd, &c, 1, 0) == 1) head += c;
        handler_(*this, fd, head.substr(0, head.find("\r\n")));
        ::shutdown(fd, SHUT_RDWR);
        ::close(fd);
      });
    }
  }

  Handler handler_;
  int listen_ = -1;
  std::string url_;
  std::atomic<bool> stopping_{false};
  std::thread acceptor_;
  std::mutex mutex_;
  std::vector<std::thread> connections_;
};

}  // namespace rayfarm::test
