#include "socket_peer.h"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>

namespace rayfarm::farm {

bool socket_closed_by_peer(int fd) {
  if (fd < 0) return false;
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, 0) <= 0) return false;
  if (p.revents & (POLLERR | POLLHUP)) return true;
  // Readable: either data waits (still open) or the stream has ended. Peek one byte to tell.
  char byte;
  const ssize_t n = ::recv(fd, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
  return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

}  // namespace rayfarm::farm
