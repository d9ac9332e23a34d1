#!/usr/bin/env python3
"""Writes studio.hdr: a synthetic photo studio for testing large area sources.

A dim room (grey walls, darker floor) lit by one large softbox, 40° wide and 28° tall, 35° above
the horizon, of uniform radiance 12, and a narrow strip light (6° x 30°, radiance 6) behind and
to the other side. Equirectangular, 1024 x 512, hprt's mapping (CONVENTIONS.md): texel (i, j)
looks along azimuth phi = 2 pi (i + 0.5) / w measured from -z toward +x, polar angle
theta = pi (j + 0.5) / h from +y. Every texel is the average of 4 x 4 samples, so the sources'
edges are anti-aliased as a camera would record them. Deterministic: no random numbers.

Run from the repository root: python3 scenes/env/make_studio.py
"""
import numpy as np

W, H, S = 1024, 512, 4


def directions():
    i = (np.arange(W * S) + 0.5) / (W * S)
    j = (np.arange(H * S) + 0.5) / (H * S)
    phi = 2 * np.pi * i[None, :]
    theta = np.pi * j[:, None]
    x = np.sin(theta) * np.sin(phi)
    y = np.cos(theta) * np.ones_like(phi)
    z = -np.sin(theta) * np.cos(phi)
    return x, y, z


def rect_light(x, y, z, azimuth_deg, elevation_deg, width_deg, height_deg):
    """Mask of a rectangle facing the origin, spanning the given angles around its centre."""
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    centre = np.array([np.cos(el) * np.sin(az), np.sin(el), -np.cos(el) * np.cos(az)])
    right = np.array([np.cos(az), 0.0, np.sin(az)])
    up = np.cross(right, centre)
    along = x * centre[0] + y * centre[1] + z * centre[2]
    u = (x * right[0] + y * right[1] + z * right[2]) / np.maximum(along, 1e-6)
    v = (x * up[0] + y * up[1] + z * up[2]) / np.maximum(along, 1e-6)
    half_w, half_h = np.tan(np.radians(width_deg) / 2), np.tan(np.radians(height_deg) / 2)
    return (along > 0) & (np.abs(u) <= half_w) & (np.abs(v) <= half_h)


def main():
    x, y, z = directions()
    walls = 0.25 + 0.1 * np.clip(y, 0, 1)
    radiance = np.where(y < 0, 0.08, walls)[..., None] * np.array([1.0, 0.98, 0.95])
    softbox = rect_light(x, y, z, 40.0, 35.0, 40.0, 28.0)
    strip = rect_light(x, y, z, -150.0, 20.0, 6.0, 30.0)
    radiance[softbox] = np.array([12.0, 12.0, 11.5])
    radiance[strip] = np.array([6.0, 6.2, 6.5])
    texels = radiance.reshape(H, S, W, S, 3).mean(axis=(1, 3)).astype(np.float32)
    write_hdr("scenes/env/studio.hdr", texels)


def write_hdr(path, rgb):
    """Radiance RGBE, flat (not run-length encoded) scanlines."""
    m = rgb.max(axis=2)
    exponent = np.where(m > 1e-32, np.floor(np.log2(np.maximum(m, 1e-32))) + 1, 0)
    scale = np.where(m > 1e-32, 256.0 / np.exp2(exponent), 0)
    mantissa = np.clip(rgb * scale[..., None], 0, 255).astype(np.uint8)
    e = np.where(m > 1e-32, exponent + 128, 0).astype(np.uint8)
    data = np.concatenate([mantissa, e[..., None]], axis=2)
    h, w = m.shape
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n")
        f.write(f"-Y {h} +X {w}\n".encode())
        f.write(data.tobytes())


if __name__ == "__main__":
    main()
