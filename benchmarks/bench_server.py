"""Load test of the explorer's HTTP server: loopback only, bounded, stops by itself.

Starts the server (``brdfkit.web.make_server("127.0.0.1", 0)``) in a child
process (``--in-process``: in a thread of this one), then ``--clients`` threads (default 16) each keep one HTTP/1.1 connection alive and
send ``--requests`` requests (default 200) round-robin over a small mix of
endpoints (``/api/eval`` single and 64-pair, ``/api/models``, the page,
``/api/shader/ward``). Prints requests/s and the p50/p90/p99/max latency,
and the number of errors (any status other than 200, any exception).
Goal (issue 14): p99 < 50 ms at 16 clients, no error.

The child process is stopped at the end whatever happens; each client joins
within 120 s or is counted as an error. With ``--in-process`` the clients and
the server share one GIL, so the figures are a lower bound for the server.

    python benchmarks/bench_server.py [--clients 16] [--requests 200]
"""

from __future__ import annotations

import argparse
import http.client
import json
import os
import statistics
import subprocess
import sys
import threading
import time
from urllib.parse import quote

from brdfkit.web import start_in_thread


def _paths() -> list[str]:
    pairs = json.dumps([[0.1 * (i % 7), 0.05 * (i % 5), 1.0] for i in range(64)])
    return [
        "/api/eval?model=ward&params=" + quote('{"alpha_x":0.2}') + "&wi=0.3,0,1&wo=-0.2,0.1,1",
        "/api/eval?model=cook-torrance&wi=" + quote(pairs) + "&wo=0,0,1",
        "/api/models",
        "/",
        "/api/shader/ward",
    ]


_CHILD = (
    "import sys; from brdfkit.web import make_server; s = make_server('127.0.0.1', 0); "
    "print(s.server_address[1], flush=True); s.serve_forever()"
)


def _start(in_process: bool):
    """(host, port, stop) of a running server."""
    if in_process:
        srv, thread = start_in_thread("127.0.0.1", 0)

        def stop() -> None:
            srv.shutdown()
            srv.server_close()
            thread.join(5)

        return "127.0.0.1", srv.server_address[1], stop
    child = subprocess.Popen([sys.executable, "-c", _CHILD], stdout=subprocess.PIPE, env=dict(os.environ))
    line = child.stdout.readline()
    if not line.strip().isdigit():
        child.kill()
        raise RuntimeError("the server process did not start")

    def stop() -> None:
        child.terminate()
        try:
            child.wait(5)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait(5)

    return "127.0.0.1", int(line), stop


def run(clients: int, requests: int, in_process: bool = False) -> dict:
    host, port, stop = _start(in_process)
    try:
        return _load(host, port, clients, requests)
    finally:
        stop()


def _load(host: str, port: int, clients: int, requests: int) -> dict:
    paths = _paths()
    lat: list[float] = []
    errors: list[str] = []
    lock = threading.Lock()
    barrier = threading.Barrier(clients + 1)

    def client(k: int) -> None:
        mine, errs = [], []
        conn = http.client.HTTPConnection(host, port, timeout=10)
        barrier.wait()
        for i in range(requests):
            p = paths[(i + k) % len(paths)]
            t0 = time.perf_counter()
            try:
                conn.request("GET", p)
                r = conn.getresponse()
                r.read()
                if r.status != 200:
                    errs.append(f"{r.status} {p[:40]}")
            except Exception as e:  # noqa: BLE001 - counted as an error
                errs.append(repr(e))
                conn.close()
                conn = http.client.HTTPConnection(host, port, timeout=10)
            mine.append(time.perf_counter() - t0)
        conn.close()
        with lock:
            lat.extend(mine)
            errors.extend(errs)

    # warm the caches (model table, shader sources) outside the measurement
    warm = http.client.HTTPConnection(host, port, timeout=30)
    for p in paths:
        warm.request("GET", p)
        warm.getresponse().read()
    warm.close()

    threads = [threading.Thread(target=client, args=(k,), daemon=True) for k in range(clients)]
    for t in threads:
        t.start()
    barrier.wait()
    t0 = time.perf_counter()
    for t in threads:
        t.join(120)  # bounded: a hung client is reported, not waited for
    wall = time.perf_counter() - t0
    hung = sum(t.is_alive() for t in threads)
    lat.sort()
    q = lambda f: lat[min(len(lat) - 1, int(f * len(lat)))] * 1e3  # noqa: E731
    return {
        "clients": clients,
        "requests": len(lat),
        "wall_s": wall,
        "rps": len(lat) / wall if wall > 0 else float("nan"),
        "p50_ms": q(0.50),
        "p90_ms": q(0.90),
        "p99_ms": q(0.99),
        "max_ms": lat[-1] * 1e3 if lat else float("nan"),
        "mean_ms": statistics.fmean(lat) * 1e3 if lat else float("nan"),
        "errors": len(errors) + hung,
        "first_errors": errors[:5],
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=16)
    ap.add_argument("--requests", type=int, default=200, help="requests per client")
    ap.add_argument("--in-process", action="store_true", help="run the server in a thread of this process")
    a = ap.parse_args(argv)
    if not 1 <= a.clients <= 256 or not 1 <= a.requests <= 100_000:
        ap.error("--clients must be in [1, 256] and --requests in [1, 100000]")
    r = run(a.clients, a.requests, a.in_process)
    print(
        f"server {'in this process' if a.in_process else 'in a child process'}, load average "
        f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs"
    )
    print(
        f"{r['clients']} clients, {r['requests']} requests in {r['wall_s']:.2f} s: {r['rps']:.0f} requests/s; "
        f"latency p50 {r['p50_ms']:.2f} ms, p90 {r['p90_ms']:.2f} ms, p99 {r['p99_ms']:.2f} ms, "
        f"max {r['max_ms']:.1f} ms; errors {r['errors']}"
    )
    if r["first_errors"]:
        print("first errors:", "; ".join(r["first_errors"]))
    print(f"goal p99 < 50 ms, no error: {'met' if r['p99_ms'] < 50 and r['errors'] == 0 else 'NOT met'}")
    return 0 if r["errors"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
