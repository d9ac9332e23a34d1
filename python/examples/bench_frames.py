"""100 frames of the teapot at 320 × 240 under a map that changes every frame (the interior
turned by 3.6° more each frame, as a new array), each decomposed, rendered in hybrid mode and
read back through ``hprt.Renderer.render``: the same loop as ``bench_frames.rs`` beside it.

``python python/examples/bench_frames.py [--rust BIN]`` from the repository root prints the
median frame and the total; with ``--rust`` (the built ``bench_frames`` example) it runs the
Rust loop too, on the same adapter, and prints the ratio of the totals."""

import argparse
import re
import statistics
import subprocess
import time

import numpy as np

import hprt

FRAMES = 100
WIDTH, HEIGHT = 320, 240


def python_loop() -> tuple[float, float, str]:
    """(median frame, total) in seconds, and the adapter."""
    scene = hprt.load_scene("scenes/teapot.toml")
    environment = hprt.load_map("scenes/env/interior.exr")
    bake = hprt.bake(scene, samples=64, bounces=1)
    renderer = hprt.Renderer(scene, bake, width=WIDTH, height=HEIGHT)
    width = environment.shape[1]
    maps = [
        np.ascontiguousarray(np.roll(environment, f * width // FRAMES, axis=1))
        for f in range(FRAMES)
    ]
    renderer.render(maps[0])  # warm-up: pipelines, first upload
    seconds = []
    start = time.perf_counter()
    for environment in maps:
        t = time.perf_counter()
        renderer.render(environment)
        seconds.append(time.perf_counter() - t)
    total = time.perf_counter() - start
    return statistics.median(seconds), total, renderer.adapter


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rust", help="the built bench_frames example, to run too")
    args = parser.parse_args()
    rust_total = None
    if args.rust:
        out = subprocess.run([args.rust], check=True, capture_output=True, text=True).stdout
        print(out.strip())
        found = re.search(r"total (\d+\.\d+) s", out)
        assert found, out
        rust_total = float(found.group(1))
    median, total, adapter = python_loop()
    print(
        f"python: {FRAMES} frames {WIDTH}x{HEIGHT} on {adapter}: "
        f"median {median * 1e3:.2f} ms, total {total:.3f} s"
    )
    if rust_total is not None:
        print(f"python / rust: {total / rust_total:.3f}")


if __name__ == "__main__":
    main()
