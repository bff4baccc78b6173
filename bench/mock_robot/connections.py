#!/usr/bin/env python3
"""Memory of `pepper_app mock-robot` over many connections (issue 23: "no memory growth over
100,000 connections (measure RSS)").

Starts `pepper_app mock-robot` on a free loopback port, opens and closes N TCP connections (every
other one sends a truncated message header before closing, as a client that dies mid-message),
prints the server's resident memory (VmRSS) every 20,000 connections and at the end, then runs
`pepper_app doctor` against it to show that a well-behaved client is still served.

Usage: bench/mock_robot/connections.py [--app build/pepper_app/pepper_app] [--count 100000]
Exit status 1 when the server died or doctor failed; the RSS figures are for the reader (the
suite's QiLoopback test asserts a bound over 10,000 cycles).
"""
import argparse
import socket
import subprocess
import sys
import time


def rss_kib(pid):
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise RuntimeError("no VmRSS")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--app", default="build/pepper_app/pepper_app")
    ap.add_argument("--count", type=int, default=100000)
    a = ap.parse_args()
    port = free_port()
    url = f"tcp://127.0.0.1:{port}"
    server = subprocess.Popen([a.app, "mock-robot", "--listen", url],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.time() + 10
        while True:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=1).close()
                break
            except OSError:
                if time.time() > deadline or server.poll() is not None:
                    print("mock-robot did not start", file=sys.stderr)
                    return 1
                time.sleep(0.1)
        time.sleep(0.5)
        before = rss_kib(server.pid)
        t0 = time.time()
        for i in range(1, a.count + 1):
            s = socket.create_connection(("127.0.0.1", port))
            if i % 2:
                s.send(b"\x42\xde\xad\xad" + b"\x00" * 24)  # a header cut short, then gone
            s.close()
            if i % 20000 == 0:
                print(f"{i} connections: RSS {rss_kib(server.pid)} KiB "
                      f"({rss_kib(server.pid) - before:+d} KiB)", flush=True)
        time.sleep(1.0)
        after = rss_kib(server.pid)
        print(f"{a.count} connections in {time.time() - t0:.1f} s: RSS {before} -> {after} KiB "
              f"({after - before:+d} KiB)")
        if server.poll() is not None:
            print("mock-robot died", file=sys.stderr)
            return 1
        d = subprocess.run([a.app, "doctor", "--robot", url], capture_output=True, text=True,
                           timeout=120)
        print(f"doctor afterwards: exit {d.returncode}; {d.stdout.splitlines()[0] if d.stdout else ''}")
        return 0 if d.returncode == 0 else 1
    finally:
        server.terminate()
        server.wait()


if __name__ == "__main__":
    sys.exit(main())
