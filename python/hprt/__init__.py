"""hprt: hybrid precomputed radiance transfer and shadow-mapped lights under HDR maps.

Maps and images are ``(H, W, 3) float32`` numpy arrays of linear radiance (equirectangular
maps, +Y up; the conventions are hprt's CONVENTIONS.md). The functions are the library under
the ``hprt`` command line, with the same numbers::

    import hprt
    scene = hprt.load_scene("scenes/teapot.toml")
    bake = hprt.bake(scene, samples=256)
    renderer = hprt.Renderer(scene, bake, width=320, height=240)
    image = renderer.render("scenes/env/interior.exr", mode="hybrid")
    truth = hprt.reference(scene, "scenes/env/interior.exr", spp=64, width=320, height=240)
"""

from ._hprt import (
    Bake,
    Camera,
    Captured,
    Composite,
    Decomposition,
    HprtError,
    Light,
    Renderer,
    Scene,
    SceneObject,
    bake,
    capture,
    decompose,
    load_bake,
    load_map,
    load_scene,
    reference,
    reference_composite,
)
from ._tqdm import TqdmProgress

__all__ = [
    "Bake",
    "Camera",
    "Captured",
    "Composite",
    "Decomposition",
    "HprtError",
    "Light",
    "Renderer",
    "Scene",
    "SceneObject",
    "TqdmProgress",
    "bake",
    "capture",
    "decompose",
    "load_bake",
    "load_map",
    "load_scene",
    "reference",
    "reference_composite",
]
