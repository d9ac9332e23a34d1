#!/usr/bin/env python3
"""The bundled dragon with every triangle split in four at its edge midpoints (810,080
triangles): a stand-in for the 871k-triangle dragon in bake benchmarks. Writes OUT/dragon4x.ply
and OUT/dragon4x.toml (the dragon scene with this mesh). Python 3, standard library only;
deterministic.

    python3 scenes/scripts/subdivide_dragon.py OUT
    /usr/bin/time hprt bake OUT/dragon4x.toml --samples 256 --bounces 1 -o OUT/dragon4x.bake
"""
import gzip
import pathlib
import struct
import sys

SCENES = pathlib.Path(__file__).resolve().parent.parent


def read_ascii_ply(path):
    lines = gzip.open(path, "rt").read().split("\n")
    i, vertex_count, face_count = 0, 0, 0
    while lines[i].strip() != "end_header":
        words = lines[i].split()
        if words[:2] == ["element", "vertex"]:
            vertex_count = int(words[2])
        if words[:2] == ["element", "face"]:
            face_count = int(words[2])
        i += 1
    i += 1
    vertices = [tuple(map(float, lines[i + k].split()[:3])) for k in range(vertex_count)]
    faces = [tuple(map(int, lines[i + vertex_count + k].split()[1:4])) for k in range(face_count)]
    return vertices, faces


def subdivide(vertices, faces):
    midpoints = {}

    def midpoint(a, b):
        key = (min(a, b), max(a, b))
        if key not in midpoints:
            midpoints[key] = len(vertices)
            vertices.append(tuple((x + y) / 2 for x, y in zip(vertices[a], vertices[b])))
        return midpoints[key]

    out = []
    for a, b, c in faces:
        ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return vertices, out


def main():
    out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    out.mkdir(parents=True, exist_ok=True)
    vertices, faces = subdivide(*read_ascii_ply(SCENES / "meshes" / "dragon_vrip_res2.ply.gz"))
    with open(out / "dragon4x.ply", "wb") as f:
        f.write(
            f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n".encode()
        )
        for v in vertices:
            f.write(struct.pack("<3f", *v))
        for t in faces:
            f.write(struct.pack("<B3i", 3, *t))
    scene = (SCENES / "dragon.toml").read_text()
    scene = scene.replace('"meshes/dragon_vrip_res2.ply.gz"', f'"{(out / "dragon4x.ply").resolve()}"')
    scene = scene.replace('"env/', f'"{SCENES / "env"}/')
    (out / "dragon4x.toml").write_text(scene)
    print(f"{len(vertices)} vertices, {len(faces)} triangles")


if __name__ == "__main__":
    main()
