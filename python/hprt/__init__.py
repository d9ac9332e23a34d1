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

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING, Any, Callable, Dict, Optional, Sequence, Union

from ._hprt import (
    Bake,
    Camera,
    Captured,
    Composite,
    Decomposition,
    HprtError,
    HprtFileNotFoundError,
    Light,
    Renderer,
    Scene,
    SceneObject,
    bake,
    capture,
    composite,
    decompose,
    load_bake,
    load_map,
    load_scene,
    reference,
    reference_composite,
    report_json,
)
from ._tqdm import TqdmProgress

if TYPE_CHECKING:
    from ._hprt import Backend, Progress

PathArgument = Union[str, "os.PathLike[str]"]


def report(
    scene: Scene,
    output: PathArgument,
    maps: Optional[Sequence[PathArgument]] = None,
    bake: Optional[Bake] = None,
    sequence: Optional[PathArgument] = None,
    path: bool = False,
    width: Optional[int] = None,
    height: Optional[int] = None,
    spp: int = 512,
    bounces: Optional[int] = None,
    seed: int = 0,
    thresholds: Optional[Sequence[float]] = None,
    frames: int = 5,
    positions: int = 24,
    probe_spp: int = 64,
    backend: Backend = "auto",
    progress: Optional[Progress] = None,
    log: Optional[Callable[[str], object]] = None,
) -> Dict[str, Any]:
    """Writes the usual report of ``scene`` into the folder ``output`` (``report.html``,
    ``stats.json``...; the folder is replaced whole when the report is done, nothing is
    written when it fails) and returns its statistics, as ``stats.json`` holds them.

    Which report, as ``hprt report`` chooses: every method against the path-traced truth
    under each of ``maps`` (the scene's map when not given); for a scene with a
    ``[backplate]``, each method's composite against the true composite; with ``sequence``
    (a folder of maps or a sequence file), per frame; with ``path=True``, the model carried
    along the scene's ``[path]`` through its room. ``bake``: the scene's bake (the cached
    one, baked if missing, when not given). ``log(line)`` receives what the command line
    prints; ``progress(stage, done, total)`` the long steps' progress."""
    text = report_json(
        scene, output, maps=maps, bake=bake, sequence=sequence, path=path, width=width,
        height=height, spp=spp, bounces=bounces, seed=seed, thresholds=thresholds,
        frames=frames, positions=positions, probe_spp=probe_spp, backend=backend,
        progress=progress, log=log,
    )
    result: Dict[str, Any] = json.loads(text)
    return result


__all__ = [
    "Bake",
    "Camera",
    "Captured",
    "Composite",
    "Decomposition",
    "HprtError",
    "HprtFileNotFoundError",
    "Light",
    "Renderer",
    "Scene",
    "SceneObject",
    "TqdmProgress",
    "bake",
    "capture",
    "composite",
    "decompose",
    "load_bake",
    "load_map",
    "load_scene",
    "reference",
    "reference_composite",
    "report",
]
