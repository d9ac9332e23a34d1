"""Type stubs of the compiled module (python/src/*.rs)."""

import os
from pathlib import Path
from typing import Callable, Literal, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

Image = npt.NDArray[np.float32]
MapArgument = Union[str, "os.PathLike[str]", npt.NDArray[np.float32]]
DecomposeMode = Literal["consistent", "thesis"]
RenderMode = Literal["hybrid", "prt", "lights", "unshadowed", "median-cut", "sh-sun"]
Backend = Literal["auto", "vulkan", "gl"]
Progress = Union[Callable[[str, int, int], object], Literal["tqdm"], bool]
"""``progress(stage, done, total)``, called at most once per percent of each stage (an
exception it raises stops the work and is raised); ``"tqdm"`` or ``True`` for tqdm bars
(``hprt.TqdmProgress``); ``False`` for nothing. Ctrl-C stops a long call whatever it is."""

class HprtError(Exception):
    """An hprt library call failed; the message says what and where."""

class HprtFileNotFoundError(HprtError, FileNotFoundError):
    """A file an hprt call reads is missing."""

class Light:
    """One directional light of a decomposition, or of your own."""

    def __init__(
        self,
        direction: tuple[float, float, float],
        power: tuple[float, float, float],
        radius_deg: float = 0.5,
    ) -> None: ...
    @property
    def direction(self) -> tuple[float, float, float]:
        """Unit direction the light arrives from (+Y up)."""
    @property
    def power(self) -> tuple[float, float, float]:
        """RGB power: the irradiance on a surface facing it."""
    @property
    def radius_deg(self) -> float:
        """Angular radius of the source, degrees."""
    @property
    def cap_radius_deg(self) -> float:
        """Radius of the cap it was taken from, degrees."""
    @property
    def share(self) -> float:
        """Share of the map's total luminous power."""
    @property
    def halo_radius_deg(self) -> float:
        """Radius of the glow around the source, degrees."""
    @property
    def core_fraction(self) -> float:
        """Fraction of the power from the source itself."""
    def sh(self, order: int = 3) -> npt.NDArray[np.float32]:
        """The light's SH projection as a point source, ``(order**2, 3)``."""

class Decomposition:
    """SH coefficients plus lights: ``hprt.decompose``'s, or lighting of your own."""

    def __init__(self, sh: npt.NDArray[np.float32], lights: list[Light] = ...) -> None: ...
    @property
    def sh(self) -> npt.NDArray[np.float32]:
        """``(order**2, 3)`` RGB coefficients, index ``l*(l+1)+m``."""
    @property
    def lights(self) -> list[Light]:
        """The lights, strongest first."""
    @property
    def total_power(self) -> npt.NDArray[np.float32]:
        """The map's total RGB power."""

class Camera:
    """A pinhole camera: position, target, vertical field of view (degrees), up."""

    def __init__(
        self,
        position: tuple[float, float, float],
        target: tuple[float, float, float],
        fov_deg: float = 40.0,
        up: tuple[float, float, float] = (0.0, 1.0, 0.0),
    ) -> None: ...
    @property
    def position(self) -> tuple[float, float, float]: ...
    @property
    def target(self) -> tuple[float, float, float]: ...
    @property
    def fov_deg(self) -> float: ...
    @property
    def up(self) -> tuple[float, float, float]: ...

class SceneObject:
    """One object of a scene: its role and its (Phong) material."""

    @property
    def name(self) -> str: ...
    @property
    def role(self) -> Literal["object", "proxy"]: ...
    @property
    def albedo(self) -> tuple[float, float, float]:
        """Diffuse albedo, or a textured object's texture factor."""
    @property
    def textured(self) -> bool: ...
    @property
    def specular(self) -> tuple[float, float, float]:
        """Phong k_s per channel (zero: diffuse)."""
    @property
    def shininess(self) -> float: ...
    @property
    def metallic(self) -> float | None:
        """glTF's metallic factor of the object's metallic-roughness layer (None without one;
        the albedo is then its base colour)."""
    @property
    def roughness(self) -> float | None:
        """The layer's perceptual roughness (None without a layer)."""
    @property
    def normal_map_scale(self) -> float | None:
        """The scale of the object's tangent-space normal map (None without one)."""
    @property
    def emission(self) -> tuple[float, float, float] | None:
        """The radiance the object emits: glTF's emissive factor times its strength, before
        its emissive texture (None where it emits nothing)."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...

class Scene:
    """A scene file or a model placed in a default scene."""

    @property
    def camera(self) -> Camera:
        """The scene's camera."""
    @property
    def image_size(self) -> tuple[int, int]:
        """The scene camera's (width, height)."""
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> Path: ...
    @property
    def objects(self) -> list[SceneObject]:
        """Its objects, in order, with their materials."""
    @property
    def vertex_count(self) -> int: ...
    @property
    def triangle_count(self) -> int: ...
    @property
    def rotation_deg(self) -> float:
        """The map's rotation renders and references use when given none."""
    @property
    def environment(self) -> Optional[Path]:
        """The map the scene names, if any."""

class Bake:
    """Per-vertex SH transfer of a scene."""

    @property
    def order(self) -> int: ...
    @property
    def samples(self) -> int: ...
    @property
    def bounces(self) -> int: ...
    @property
    def direct(self) -> npt.NDArray[np.float32]:
        """``(vertices, 3, order**2)`` shadowed transfer: a read-only view, no copy."""
    @property
    def indirect(self) -> npt.NDArray[np.float32]:
        """``(vertices, 3, order**2)`` interreflected transfer: a read-only view, no copy."""
    @property
    def transfer(self) -> npt.NDArray[np.float32]:
        """Direct plus interreflected."""
    def save(self, path: Union[str, "os.PathLike[str]"]) -> None:
        """Writes a ``.bake`` file that ``hprt render --bake`` reads."""

class Renderer:
    """The real-time renderer of one scene and bake, reused across frames."""

    def __init__(
        self,
        scene: Scene,
        bake: Bake,
        backend: Backend = "auto",
        width: Optional[int] = None,
        height: Optional[int] = None,
    ) -> None: ...
    @property
    def adapter(self) -> str:
        """The graphics adapter it draws with."""
    def render(
        self,
        lighting: Union[MapArgument, Decomposition],
        mode: RenderMode = "hybrid",
        rotation_deg: Optional[float] = None,
        decompose_mode: DecomposeMode = "consistent",
        camera: Optional[Camera] = None,
        background: Optional[MapArgument] = None,
    ) -> Image:
        """The linear radiance image, ``(height, width, 3) float32``: lit by a map, or by a
        Decomposition drawn over ``background`` (black when not given)."""

def load_map(path: Union[str, "os.PathLike[str]"]) -> Image:
    """An environment map file as an ``(H, W, 3) float32`` equirectangular array."""

def decompose(
    map: MapArgument,
    mode: DecomposeMode = "consistent",
    threshold: Optional[float] = None,
    order: Optional[int] = None,
    rotation_deg: float = 0.0,
) -> Decomposition:
    """The map as SH plus lights, as ``hprt decompose`` gives it."""

def load_scene(path: Union[str, "os.PathLike[str]"]) -> Scene:
    """Loads a scene file (TOML) or a model (glTF, OBJ, PLY, BPT)."""

def bake(
    scene: Scene,
    samples: Optional[int] = None,
    bounces: Optional[int] = None,
    order: Optional[int] = None,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    progress: Optional[Progress] = None,
    cache: bool = False,
) -> Bake:
    """Bakes the scene; its ``[bake]`` settings where an argument is not given. With
    ``cache``, reads the bake from (or writes it to) the cache the command line shares."""

def load_bake(scene: Scene, path: Union[str, "os.PathLike[str]"]) -> Bake:
    """Loads a ``.bake`` file of ``scene``."""

def reference(
    scene: Scene,
    map: MapArgument,
    spp: int = 64,
    bounces: int = 4,
    seed: int = 0,
    rotation_deg: Optional[float] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    camera: Optional[Camera] = None,
    progress: Optional[Progress] = None,
) -> Image:
    """The path-traced image, ``(height, width, 3) float32``; the map turned by the scene's
    rotation when ``rotation_deg`` is not given."""

class Composite:
    """A composite into the scene's backplate and its layers."""

    @property
    def image(self) -> Image: ...
    @property
    def objects(self) -> Image:
        """The objects' radiance on object pixels, zero elsewhere."""
    @property
    def ratio(self) -> Image:
        """The shadow ratio on proxy pixels, one elsewhere."""
    @property
    def kinds(self) -> npt.NDArray[np.uint8]:
        """Per pixel: 0 object, 1 proxy, 2 backplate."""
    @property
    def changed(self) -> npt.NDArray[np.bool_]:
        """Proxy pixels the objects change by more than 2%."""

def reference_composite(
    scene: Scene,
    map: MapArgument,
    spp: int = 64,
    bounces: int = 4,
    seed: int = 0,
    rotation_deg: Optional[float] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    camera: Optional[Camera] = None,
    progress: Optional[Progress] = None,
) -> Composite:
    """The path-traced true composite of a scene with a ``[backplate]``."""

class Captured:
    """A map captured from photographs."""

    @property
    def map(self) -> Image:
        """``(width / 2, width, 3) float32``, linear, in the camera's units."""
    @property
    def response(self) -> npt.NDArray[np.float32]:
        """The inverse response used, ``(256, 3)``."""
    @property
    def spread(self) -> Optional[float]:
        """The median texel's readings across exposures (RMS log), or None if unknown."""
    @property
    def covered(self) -> float:
        """Share of the sphere some exposure resolved."""
    @property
    def warnings(self) -> list[str]: ...

def capture(
    description: Union[str, "os.PathLike[str]", Sequence[Union[str, "os.PathLike[str]"]]],
    width: int = 1024,
    response: Optional[npt.NDArray[np.float32]] = None,
    fov_deg: Optional[float] = None,
    reflectance: tuple[float, float, float] = (1.0, 1.0, 1.0),
    outline: Optional[tuple[float, float, float]] = None,
) -> Captured:
    """The map the photographs see (as ``hprt capture``): those a capture description names,
    or a list of a mirror ball's bracketed photographs from one tripod position (``fov_deg``
    the camera's vertical field of view; ``outline`` the ball's centre x, y and radius in
    pixels, found when not given; exposures from EXIF)."""

CompositeForm = Literal["differential", "occlusion"]

def composite(
    renderer: Renderer,
    lighting: Union[MapArgument, Decomposition],
    mode: RenderMode = "hybrid",
    form: CompositeForm = "differential",
    rotation_deg: Optional[float] = None,
    decompose_mode: DecomposeMode = "consistent",
    camera: Optional[Camera] = None,
    progress: Optional[Progress] = None,
) -> Composite:
    """The GPU methods' composite of the frame ``renderer`` draws into the scene's
    ``[backplate]`` (``hprt render``'s for such a scene), with its layers."""

def report_json(
    scene: Scene,
    output: Union[str, "os.PathLike[str]"],
    maps: Optional[Sequence[Union[str, "os.PathLike[str]"]]] = None,
    bake: Optional[Bake] = None,
    sequence: Optional[Union[str, "os.PathLike[str]"]] = None,
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
) -> str:
    """``report``'s statistics as JSON text (use ``hprt.report``)."""
