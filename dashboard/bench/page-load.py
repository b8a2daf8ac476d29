#!/usr/bin/env python3
"""Load time of dashboard pages in headless Chromium, through chromedriver (stdlib only).

Usage: dashboard/bench/page-load.py BASE_URL PATH [PATH ...] [--repeat N] [--width 1400]
       [--shots DIR]

Per path: HTML bytes (as sent, uncompressed), and over N loads in a fresh tab each the median
of responseEnd (server and transfer), domContentLoaded and loadEventEnd, in ms from navigation
start (the Navigation Timing entry), and the page's height in pixels. With --shots, a screenshot of
the first load of each path is written to DIR. Needs `chromedriver` and `chromium`
(dashboard/ci/setup-chromium.sh); TESSERA_CHROMEDRIVER / TESSERA_CHROMIUM point elsewhere.
"""

import argparse
import base64
import json
import os
import socket
import statistics
import subprocess
import time
import urllib.request


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


def call(base, method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method,
                                 headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=120) as r:
        return json.loads(r.read())["value"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("base")
    ap.add_argument("paths", nargs="+")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--width", type=int, default=1400)
    ap.add_argument("--shots")
    a = ap.parse_args()
    driver = os.environ.get("TESSERA_CHROMEDRIVER", "chromedriver")
    chromium = os.environ.get("TESSERA_CHROMIUM", "/usr/bin/chromium")
    port = free_port()
    proc = subprocess.Popen([driver, f"--port={port}"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    wd = f"http://127.0.0.1:{port}"
    try:
        for _ in range(100):
            try:
                urllib.request.urlopen(wd + "/status", timeout=1)
                break
            except OSError:
                time.sleep(0.1)
        caps = {"capabilities": {"alwaysMatch": {"goog:chromeOptions": {
            "binary": chromium,
            "args": ["--headless=new", "--no-sandbox", "--disable-gpu",
                     "--disable-dev-shm-usage", f"--window-size={a.width},900"]}}}}
        sid = call(wd, "POST", "/session", caps)["sessionId"]
        s = f"/session/{sid}"
        print("| path | HTML bytes | responseEnd ms | DOMContentLoaded ms | load ms | height px |")
        print("|---|---:|---:|---:|---:|---:|")
        for n, path in enumerate(a.paths):
            with urllib.request.urlopen(a.base + path, timeout=300) as r:
                size = len(r.read())
            rows = []
            for i in range(a.repeat):
                call(wd, "POST", s + "/url", {"url": "about:blank"})
                call(wd, "POST", s + "/url", {"url": a.base + path})
                t = call(wd, "POST", s + "/execute/sync", {"script": (
                    "const e = performance.getEntriesByType('navigation')[0];"
                    "return [e.responseEnd, e.domContentLoadedEventEnd, e.loadEventEnd,"
                    " document.documentElement.scrollHeight];"), "args": []})
                rows.append(t)
                if i == 0 and a.shots:
                    os.makedirs(a.shots, exist_ok=True)
                    png = base64.b64decode(call(wd, "GET", s + "/screenshot"))
                    with open(os.path.join(a.shots, f"page-{n}.png"), "wb") as f:
                        f.write(png)
            med = [statistics.median(r[k] for r in rows) for k in range(3)]
            print(f"| `{path}` | {size:,} | {med[0]:.0f} | {med[1]:.0f} | {med[2]:.0f} | {rows[0][3]:,} |")
        call(wd, "DELETE", s)
    finally:
        proc.terminate()
        proc.wait()


if __name__ == "__main__":
    main()
