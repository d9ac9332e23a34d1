"""Makes city_square.png: a 640x480 photograph of the city square in ../env/city.exr (Greg
Zaal, HDRI Haven, CC0), seen through the pinhole camera of ../teapot_photo.toml.

The panorama is itself stitched from photographs; this reprojects it through that scene's
camera (pixel centres, CONVENTIONS.md's mapping and the scene's rotation_deg, bilinear),
keeps the map's radiance units (exposure 1: the teapot is lit in the same units), clips
at 1 and encodes sRGB in 8 bits, as a camera's JPEG or PNG would. So the photograph's camera
matches the scene's exactly, by construction.

Python 3 with numpy and OpenEXR (pip install numpy OpenEXR); deterministic.
"""
import math
import struct
import zlib
from pathlib import Path

import Imath
import numpy as np
import OpenEXR

HERE = Path(__file__).resolve().parent
# The camera and rotation of ../teapot_photo.toml.
POSITION = np.array([6.5, 4.0, 11.0])
TARGET = np.array([0.3, 1.0, 0.0])
UP = np.array([0.0, 1.0, 0.0])
FOV_Y_DEG = 38.0
WIDTH, HEIGHT = 640, 480
ROTATION_DEG = 150.0


def read_exr(path):
    f = OpenEXR.InputFile(str(path))
    window = f.header()["dataWindow"]
    w, h = window.max.x + 1, window.max.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    channels = [np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in "RGB"]
    return np.maximum(np.stack(channels, -1).astype(np.float64), 0.0)


def directions():
    forward = (TARGET - POSITION) / np.linalg.norm(TARGET - POSITION)
    right = np.cross(forward, UP)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    tan_half = math.tan(math.radians(FOV_Y_DEG) / 2)
    i, j = np.meshgrid(np.arange(WIDTH), np.arange(HEIGHT))
    x = (2 * (i + 0.5) / WIDTH - 1) * tan_half * WIDTH / HEIGHT
    y = (1 - 2 * (j + 0.5) / HEIGHT) * tan_half
    d = forward + x[..., None] * right + y[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def lookup(env, d):
    """The map turned by ROTATION_DEG about +Y, looked up bilinearly at directions d."""
    a = math.radians(ROTATION_DEG)
    c, s = math.cos(a), math.sin(a)
    x = d[..., 0] * c - d[..., 2] * s
    z = d[..., 0] * s + d[..., 2] * c
    y = d[..., 1]
    h, w, _ = env.shape
    u = (np.arctan2(x, -z) / (2 * math.pi)) % 1.0
    v = np.arccos(np.clip(y, -1, 1)) / math.pi
    fx, fy = u * w - 0.5, np.clip(v * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(fx).astype(int), np.floor(fy).astype(int)
    tx, ty = (fx - x0)[..., None], (fy - y0)[..., None]
    x1, y1 = (x0 + 1) % w, np.minimum(y0 + 1, h - 1)
    x0 %= w
    top = env[y0, x0] * (1 - tx) + env[y0, x1] * tx
    bottom = env[y1, x0] * (1 - tx) + env[y1, x1] * tx
    return top * (1 - ty) + bottom * ty


def srgb8(linear):
    c = np.clip(linear, 0, 1)
    encoded = np.where(c <= 0.0031308, 12.92 * c, 1.055 * c ** (1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def write_png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data))

    header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")
    )


if __name__ == "__main__":
    env = read_exr(HERE.parent / "env" / "city.exr")
    photo = lookup(env, directions())
    clipped = np.mean(photo.max(-1) > 1)
    write_png(HERE / "city_square.png", srgb8(photo))
    print(f"wrote city_square.png ({100 * clipped:.1f}% of pixels clipped)")
