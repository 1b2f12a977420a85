// Whether the other end of a connected socket has closed it, asked without blocking and
// without consuming input. Shared by rayfarmd's HTTP connections (a waiting client that hung
// up) and the farm's pooled Redis connections (one Redis closed while it was idle).
#pragma once

namespace rayfarm::farm {

// True once the peer has closed (end of stream) or the socket is in error; false while it is
// open, whether or not input is waiting.
bool socket_closed_by_peer(int fd);

}  // namespace rayfarm::farm
