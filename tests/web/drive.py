#!/usr/bin/env python3
"""Opens an exported web viewer in headless Chromium over WebDriver and prints what the page
did, as JSON: its state and message, the backend that drew, the time from loading the page to
its first frame, the first frame's linear radiance, and the decompositions counted as the map
turns. Used by tests/web.rs; standard library only.

    drive.py SITE_DIR --backend webgpu|webgl2|none [--query Q] [--turns N]

`none` starts Chromium with neither WebGPU nor WebGL, as a browser without them.
"""

import argparse
import functools
import http.server
import json
import mimetypes
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request

CHROMIUM = os.environ.get("HPRT_CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("HPRT_CHROMEDRIVER", "/usr/bin/chromedriver")
# Quiet on a closed network: no updates, syncing or first-run work reaching out.
COMMON = [
    "--headless=new",
    "--no-sandbox",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-dev-shm-usage",
]
# WebGPU on SwiftShader, drawing to a canvas (each of the last three is needed for that).
FLAGS = {
    "webgpu": [
        "--enable-unsafe-webgpu",
        "--enable-features=Vulkan",
        "--use-vulkan=swiftshader",
        "--use-angle=swiftshader",
    ],
    "webgl2": [],
    "none": ["--disable-3d-apis", "--disable-features=WebGPU"],
}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def serve(site):
    mimetypes.add_type("application/wasm", ".wasm")
    handler = functools.partial(Quiet, directory=site)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


class Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, *args):
        pass


class Driver:
    def __init__(self, port):
        self.base = f"http://127.0.0.1:{port}"
        self.session = None

    def call(self, method, path, body=None, timeout=300):
        data = None if body is None else json.dumps(body).encode()
        request = urllib.request.Request(self.base + path, data=data, method=method)
        request.add_header("Content-Type", "application/json")
        try:
            with urllib.request.urlopen(request, timeout=timeout) as response:
                return json.load(response)["value"]
        except urllib.error.HTTPError as e:
            raise RuntimeError(f"WebDriver {method} {path}: {e.read().decode()[:2000]}")

    def wait_ready(self, seconds=30):
        deadline = time.time() + seconds
        while time.time() < deadline:
            try:
                if self.call("GET", "/status", timeout=2).get("ready"):
                    return
            except (OSError, RuntimeError):
                pass
            time.sleep(0.1)
        raise RuntimeError("chromedriver did not start")

    def start(self, args, profile):
        capabilities = {
            "browserName": "chrome",
            "goog:chromeOptions": {"binary": CHROMIUM, "args": args + [f"--user-data-dir={profile}"]},
        }
        value = self.call("POST", "/session", {"capabilities": {"alwaysMatch": capabilities}})
        self.session = f"/session/{value['sessionId']}"
        self.call("POST", self.session + "/timeouts", {"script": 240000, "pageLoad": 240000})

    def run(self, script, *args):
        return self.call("POST", self.session + "/execute/sync", {"script": script, "args": list(args)})

    def run_async(self, script, *args):
        return self.call("POST", self.session + "/execute/async", {"script": script, "args": list(args)})


STATE = "return window.hprt ? {state: hprt.state, message: hprt.message || null, " \
    "backend: hprt.backend || null, firstFrameMs: hprt.firstFrameMs || null, " \
    "maps: hprt.maps || null} : {state: 'absent'}"
READ = "const done = arguments[arguments.length - 1];" \
    "hprt.readFrame().then(f => done({frame: f, size: hprt.size}), e => done({error: String(e)}));"


def drive(driver, url, turns):
    started = time.time()
    driver.call("POST", driver.session + "/url", {"url": url})
    while True:
        state = driver.run(STATE)
        if state["state"] not in ("loading", "absent") or time.time() - started > 240:
            break
        time.sleep(0.05)
    result = dict(state)
    result["secondsToSettle"] = time.time() - started
    if state["state"] != "ready":
        result["text"] = driver.run("return document.getElementById('message').textContent")
        return result
    frame = driver.run_async(READ)
    result.update(frame)
    if turns:
        counts = [driver.run("return hprt.turn(arguments[0])", 10.0 * (i + 1)) for i in range(turns)]
        result["decompositions"] = counts
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("site")
    parser.add_argument("--backend", choices=sorted(FLAGS), required=True)
    parser.add_argument("--query", default="")
    parser.add_argument("--turns", type=int, default=0)
    options = parser.parse_args()
    server = serve(options.site)
    port = free_port()
    chromedriver = subprocess.Popen(
        [CHROMEDRIVER, f"--port={port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    driver = Driver(port)
    try:
        driver.wait_ready()
        with tempfile.TemporaryDirectory() as profile:
            driver.start(COMMON + FLAGS[options.backend], profile)
            query = options.query or ("" if options.backend == "none" else f"backend={options.backend}")
            url = f"http://127.0.0.1:{server.server_address[1]}/index.html?{query}"
            try:
                result = drive(driver, url, options.turns)
            finally:
                driver.call("DELETE", driver.session)
    finally:
        chromedriver.terminate()
        chromedriver.wait(timeout=30)
        server.shutdown()
    json.dump(result, sys.stdout)


if __name__ == "__main__":
    main()
