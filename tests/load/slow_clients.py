#!/usr/bin/env python3
"""Slow clients hold connections (half-sent request heads, idle keep-alive, open event
streams) while /healthz must stay fast. Loopback only, bounded in time.
Usage: tests/load/slow_clients.py PORT [CLIENTS]"""
import socket
import sys
import time

port = int(sys.argv[1])
clients = int(sys.argv[2]) if len(sys.argv) > 2 else 48
held = []
for i in range(clients):
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    kind = i % 3
    if kind == 0:
        s.sendall(b"POST /render HTTP/1.1\r\nHost: x\r\n")  # never finishes its head
    elif kind == 1:
        s.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")  # then idles on keep-alive
    else:
        s.sendall(b"GET /samples HTTP/1.1\r\nHost: x\r\nContent-Length: 1000\r\n\r\nab")  # stalls its body
    held.append(s)

times = []
for _ in range(20):
    t0 = time.time()
    c = socket.create_connection(("127.0.0.1", port), timeout=10)
    c.sendall(b"GET /healthz HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n")
    answer = c.recv(100)
    c.close()
    times.append((time.time() - t0) * 1000)
    assert answer.startswith(b"HTTP/1.1 200"), answer
    time.sleep(0.05)
times.sort()
print(f"slow clients: {clients} held connections; /healthz p50 {times[len(times)//2]:.1f} ms, "
      f"max {times[-1]:.1f} ms")
for s in held:
    s.close()
if times[-1] > 1000:
    print("slow clients: FAIL: /healthz took over a second")
    sys.exit(1)
print("slow clients: ok")
