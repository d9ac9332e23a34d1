"""Times Embree 4 on the bake's own rays, for comparison with `hprt bench bake`.

    hprt bench bake scenes/dragon.toml --samples 64 --bounces 0 --dump-rays rays.bin
    python3 scenes/scripts/embree_rays.py rays.bin [--threads 2] [--repeat 3]

Reads the rays file `hprt bench bake --dump-rays` writes (layout in the README), builds an
Embree scene of its triangles and casts every ray as a single-ray query (`rtcIntersect1` /
`rtcOccluded1` through embreex's `run`), split across threads (embreex releases the GIL),
closest hit and then occlusion; prints the median rays per second of each. Needs Python 3
with numpy and embreex 4.4 (`pip install embreex==4.4.0`).
"""

import argparse
import statistics
import struct
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh


def read_rays(path):
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"HPRTRAYS":
        raise SystemExit(f"{path}: not a rays file of hprt bench bake --dump-rays")
    version, per_fan, fans, triangles = struct.unpack_from("<IIQQ", data, 8)
    if version != 1:
        raise SystemExit(f"{path}: version {version}, this script reads version 1")
    rays = per_fan * fans
    floats = np.frombuffer(data, dtype="<f4", offset=32, count=rays * 6 + triangles * 9)
    ray_data = floats[: rays * 6].reshape(rays, 6)
    corners = floats[rays * 6 :].reshape(triangles, 3, 3)
    return (
        np.ascontiguousarray(ray_data[:, :3]),
        np.ascontiguousarray(ray_data[:, 3:]),
        np.ascontiguousarray(corners),
    )


def rays_per_second(scene, origins, directions, query, threads):
    parts = np.array_split(np.arange(len(origins)), threads)

    def cast(part):
        scene.run(origins[part], directions[part], query=query)

    start = time.perf_counter()
    with ThreadPoolExecutor(threads) as pool:
        list(pool.map(cast, parts))
    return len(origins) / (time.perf_counter() - start)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("rays")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    origins, directions, corners = read_rays(args.rays)
    scene = rtcore_scene.EmbreeScene()
    TriangleMesh(scene, corners)
    # The first query commits the scene (builds its BVH): not timed.
    scene.run(origins[:1], directions[:1], query="INTERSECT")
    print(
        f"{len(origins)} rays, {len(corners)} triangles, {args.threads} threads, "
        f"median of {args.repeat}"
    )
    for query, name in [("INTERSECT", "closest hit"), ("OCCLUDED", "occlusion")]:
        rates = [
            rays_per_second(scene, origins, directions, query, args.threads)
            for _ in range(args.repeat)
        ]
        print(f"embree {name}: {statistics.median(rates) / 1e6:.2f} M rays/s")


if __name__ == "__main__":
    main()
