"""The teapot in three of the renderer's modes against the path tracer, notebook style: the
map decomposed (its lights printed), the bake, each mode's image and its relative L1 error to
the path-traced reference at the same size, and a figure of them all.

``python python/examples/compare_modes.py [OUT.png]`` from the repository root (the figure
goes to a temporary folder when no path is given)."""

import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import numpy.typing as npt

import hprt

SCENE = "scenes/teapot.toml"
MAP = "scenes/env/interior.exr"
WIDTH, HEIGHT = 80, 60
Image = npt.NDArray[np.float32]


def relative_l1(image: Image, truth: Image) -> float:
    """Σ|image − truth| / Σ truth over the image's pixels and channels."""
    return float(np.abs(image - truth).sum() / truth.sum())


def display(image: Image) -> Image:
    """Reinhard-tone-mapped and gamma-encoded for the figure."""
    return np.clip((image / (1.0 + image)) ** (1.0 / 2.2), 0.0, 1.0).astype(np.float32)


def main(out: Path) -> dict[str, float]:
    scene = hprt.load_scene(SCENE)
    environment = hprt.load_map(MAP)

    # The map as the hybrid sees it: SH plus lights, turned as the scene turns its map.
    bake = hprt.bake(scene, samples=64, bounces=1, order=4)
    lighting = hprt.decompose(environment, order=bake.order, rotation_deg=scene.rotation_deg)
    for light in lighting.lights:
        x, y, z = light.direction
        print(f"light from ({x:.2f}, {y:.2f}, {z:.2f}): {100 * light.share:.1f}% of the power")

    renderer = hprt.Renderer(scene, bake, width=WIDTH, height=HEIGHT)
    images: dict[str, Image] = {
        "prt": renderer.render(environment, mode="prt"),
        # The decomposition drawn as it is: bit for bit what rendering the map in hybrid gives.
        "hybrid": renderer.render(lighting, background=environment),
        "median-cut": renderer.render(environment, mode="median-cut"),
    }
    truth = hprt.reference(scene, environment, spp=64, bounces=1, width=WIDTH, height=HEIGHT)
    errors = {mode: relative_l1(image, truth) for mode, image in images.items()}
    print(f"relative L1 to the path tracer, teapot {WIDTH}x{HEIGHT}:")
    for mode, error in errors.items():
        print(f"{mode:>12} {error:.4f}")

    figure, axes = plt.subplots(1, len(images) + 2, figsize=(3 * (len(images) + 2), 3.0))
    panels = [("path tracer", truth), *images.items()]
    for axis, (name, image) in zip(axes, panels):
        axis.imshow(display(image))
        axis.set_title(name if name not in errors else f"{name}: {errors[name]:.3f}")
        axis.axis("off")
    bars = axes[-1]
    bars.bar(list(errors), list(errors.values()), color="tab:blue")
    bars.set_ylabel("relative L1")
    bars.tick_params(axis="x", labelrotation=30)
    figure.tight_layout()
    figure.savefig(out, dpi=100, bbox_inches="tight")
    plt.close(figure)
    print(f"wrote {out}")
    return errors


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp()) / "compare_modes.png"
    main(target)
