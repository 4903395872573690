"""Type hints of shadowlab's native module."""

from os import PathLike
from typing import Any, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Vec3 = Union[Sequence[float], npt.NDArray[np.floating[Any]]]
Params = Mapping[str, Any]

class ShadowlabError(ValueError):
    """Bad input: one sentence naming the scene, array, parameter, camera or light at fault."""

class Camera:
    """A camera looking from ``eye`` at ``target`` (+Y up): a perspective pinhole, or
    parallel rays when made by ``Camera.orthographic``."""

    def __init__(
        self,
        eye: Vec3,
        target: Vec3,
        fov_y_deg: float = 45.0,
        width: int = 1024,
        height: int = 768,
    ) -> None: ...
    @staticmethod
    def orthographic(
        eye: Vec3,
        target: Vec3,
        ymag: float,
        xmag: Optional[float] = None,
        width: int = 1024,
        height: int = 768,
    ) -> Camera:
        """An orthographic camera viewing the rectangle ``2·xmag × 2·ymag`` (world units);
        ``xmag`` defaults to ``ymag`` times the image's aspect."""
    @property
    def projection(self) -> str:
        """``"perspective"`` or ``"orthographic"``."""
    @property
    def xmag(self) -> Optional[float]:
        """An orthographic camera's half width; ``None`` for a perspective one."""
    @property
    def ymag(self) -> Optional[float]:
        """An orthographic camera's half height; ``None`` for a perspective one."""
    @property
    def eye(self) -> list[float]: ...
    @property
    def target(self) -> list[float]: ...
    @property
    def fov_y_deg(self) -> float: ...
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    def with_size(self, width: int, height: int) -> Camera:
        """The same camera with another image size."""

class Light:
    """A light source: punctual (``directional``, ``point``, ``spot``) or an area light
    (``rect``, ``disk``, ``sphere``, or a punctual light ``sized``). An area light carries
    its light samples per point (``samples``, 256 unless given): the soft-shadow reference
    (``raytrace``) and the soft techniques (``pcss``, ``afsm-soft``, the filtered soft
    variants) see its area; map-based hard techniques see its centre as a punctual light."""

    @staticmethod
    def directional(to_light: Vec3) -> Light:
        """Parallel light; ``to_light`` points from the scene towards the light."""
    @staticmethod
    def point(position: Vec3) -> Light:
        """Light in every direction from ``position``."""
    @staticmethod
    def spot(position: Vec3, target: Vec3, fov_deg: float) -> Light:
        """A cone of light from ``position`` towards ``target``, ``fov_deg`` wide."""
    @staticmethod
    def rect(centre: Vec3, edge_u: Vec3, edge_v: Vec3, samples: int = 256) -> Light:
        """A parallelogram ``centre + s·edge_u + t·edge_v``, ``s, t`` in ``[-1/2, 1/2]``."""
    @staticmethod
    def disk(centre: Vec3, normal: Vec3, radius: float, samples: int = 256) -> Light:
        """A disk of ``radius`` about ``centre`` facing along ``normal``."""
    @staticmethod
    def sphere(centre: Vec3, radius: float, samples: int = 256) -> Light:
        """A spherical light of ``radius`` about ``centre``."""
    def sized(self, size: float, samples: int = 256) -> Light:
        """This punctual light given a size, as ``--light-size``: a point light a sphere of
        radius ``size``, a spot light a disk facing its target, a directional light a sun
        of angular diameter ``size`` degrees."""
    @property
    def kind(self) -> str:
        """``"directional"``, ``"point"`` or ``"spot"``; an area light's shape (``"rect"``,
        ``"disk"``, ``"sphere"``, ``"distant"``)."""
    @property
    def is_area(self) -> bool:
        """True for an area light."""
    @property
    def samples(self) -> int:
        """Light samples per point under an area light."""
    def to_dict(self) -> dict[str, Any]:
        """The light as ``metrics.json`` records it."""

class Scene:
    """World-space triangles with their materials, and the camera and light they came with."""

    @staticmethod
    def load(
        spec: str,
        params: Optional[Mapping[str, Any]] = None,
        *,
        up: str = "y",
        obj_kd_alpha: bool = True,
    ) -> Scene:
        """A built-in scene name or a ``.toml``/``.obj``/``.ply``/``.gltf``/``.glb`` file.

        ``up`` is a mesh file's up axis (``"x"``, ``"y"``, ``"z"``, ``"-x"``, ``"-y"``,
        ``"-z"``); ``obj_kd_alpha=False`` keeps OBJ materials without ``map_d`` whole."""
    @staticmethod
    def from_arrays(
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        *,
        name: str = "arrays",
        color: Optional[Vec3] = None,
        transmittance: Optional[Vec3] = None,
        ground: bool = False,
    ) -> Scene:
        """One mesh: vertices ``(n, 3)`` float32, faces ``(m, 3)`` integer indices."""
    def add_mesh(
        self,
        vertices: npt.ArrayLike,
        faces: npt.ArrayLike,
        *,
        color: Optional[Vec3] = None,
        transmittance: Optional[Vec3] = None,
    ) -> int:
        """Adds a mesh; returns its mesh number."""
    def set_mesh_vertices(self, mesh: int, vertices: npt.ArrayLike) -> None:
        """Moves a mesh added from arrays to new vertex positions (same faces)."""
    @property
    def name(self) -> str: ...
    @property
    def triangles(self) -> int: ...
    @property
    def revision(self) -> int:
        """Bumped on every geometry edit."""
    @property
    def bounds(self) -> Tuple[list[float], list[float]]: ...
    @property
    def camera(self) -> Camera:
        """The camera a frame uses when none is given."""
    @property
    def light(self) -> Light:
        """The light a frame uses when none is given."""
    def render(
        self,
        technique: str = "afsm",
        camera: Optional[Camera] = None,
        light: Optional[Light] = None,
        params: Optional[Params] = None,
    ) -> npt.NDArray[np.float32]:
        """The shadow term of one frame, ``(H, W, 3)`` float32 (1 = lit). Releases the GIL."""
    def render_lights(
        self,
        technique: str,
        lights: Sequence[Light],
        camera: Optional[Camera] = None,
        params: Optional[Params] = None,
    ) -> list[npt.NDArray[np.float32]]:
        """One ``(H, W, 3)`` shadow term per light of one frame."""
    def visibility(
        self,
        points: npt.ArrayLike,
        normals: npt.ArrayLike,
        light: Optional[Light] = None,
        technique: str = "raytrace",
        params: Optional[Params] = None,
        triangles: Optional[Sequence[int]] = None,
    ) -> npt.NDArray[np.float32]:
        """The shadow term of each point, ``(n, 3)`` float32."""
    def compare(
        self,
        techniques: Optional[Sequence[str]] = None,
        camera: Optional[Camera] = None,
        light: Optional[Light] = None,
        params: Optional[Mapping[str, Params]] = None,
        reference_spp: int = 1,
        reference_pattern: str = "grid",
        sweeps: Optional[Mapping[str, Sequence[Any]]] = None,
        frames: int = 1,
    ) -> dict[str, Any]:
        """Techniques against the ray-traced reference: a dict shaped like ``metrics.json``.
        ``sweeps`` (``{"technique.key": [values]}``) gives one result per value over one
        camera pass and reference; ``frames > 1`` renders the scene's camera path, each
        frame against its own reference (``results[i]["frames"]``)."""

def techniques() -> list[str]:
    """Every technique name."""

def read_exr(path: Union[str, PathLike[str]]) -> npt.NDArray[np.float32]:
    """A ``--visibility`` EXR as ``(H, W, 4)`` float32: RGB shadow term, A coverage."""
