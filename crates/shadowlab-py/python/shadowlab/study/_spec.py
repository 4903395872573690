"""What a study runs: its jobs (one per scene × light × camera), and the lights and cameras
they are described with (plain strings and dicts, so that a job travels to any worker)."""

import hashlib
import json
import os
import re
from dataclasses import asdict, dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

from .. import Camera, Light, ShadowlabError

LightSpec = Union[None, str, Mapping[str, Any]]
CameraSpec = Union[None, Mapping[str, Any]]


def _numbers(text: str, n: int, what: str) -> List[float]:
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != n:
        raise ShadowlabError(f"{what} {text!r} is not {n} numbers separated by commas")
    return values


def make_light(spec: LightSpec) -> Optional[Light]:
    """A light from its description: ``None`` (the scene's own), a string in the command
    line's ``--light`` syntax (``directional:DX,DY,DZ``, ``point:X,Y,Z``,
    ``spot:X,Y,Z:TX,TY,TZ:FOV``, ``rect:C:U:V``, ``disk:C:N:R``, ``sphere:C:R``), or a dict
    ``{"light": STRING, "size": S, "samples": N}`` (``size`` as ``--light-size``)."""
    if spec is None:
        return None
    if isinstance(spec, Mapping):
        unknown = set(spec) - {"light", "size", "samples"}
        if unknown or "light" not in spec:
            raise ShadowlabError(
                f"light {dict(spec)!r} must be a table of light (required), size and samples"
            )
        samples = int(spec.get("samples", 256))
        text = str(spec["light"])
        kind = text.split(":", 1)[0]
        if kind in ("rect", "disk", "sphere"):
            if "size" in spec:
                raise ShadowlabError(f"light {text!r} already has an area; it takes no size")
            return _parse_light(text, samples)
        light = _parse_light(text, samples)
        return light.sized(float(spec["size"]), samples) if "size" in spec else light
    return _parse_light(str(spec), 256)


def _parse_light(text: str, samples: int) -> Light:
    kind, _, rest = text.partition(":")
    parts = rest.split(":") if rest else []
    v3 = lambda i, what: _numbers(parts[i], 3, f"light {text!r} {what}")  # noqa: E731
    number = lambda i, what: _numbers(parts[i], 1, f"light {text!r} {what}")[0]  # noqa: E731
    shapes = {
        ("directional", 1): lambda: Light.directional(v3(0, "direction")),
        ("point", 1): lambda: Light.point(v3(0, "position")),
        ("spot", 3): lambda: Light.spot(v3(0, "position"), v3(1, "target"), number(2, "angle")),
        ("rect", 3): lambda: Light.rect(v3(0, "centre"), v3(1, "edge"), v3(2, "edge"), samples),
        ("disk", 3): lambda: Light.disk(v3(0, "centre"), v3(1, "normal"), number(2, "radius"), samples),
        ("sphere", 2): lambda: Light.sphere(v3(0, "centre"), number(1, "radius"), samples),
    }
    make = shapes.get((kind, len(parts)))
    if make is None:
        raise ShadowlabError(
            f"light {text!r} is not directional:DX,DY,DZ, point:X,Y,Z, spot:X,Y,Z:TX,TY,TZ:FOV, "
            "rect:C:U:V, disk:C:N:R or sphere:C:R"
        )
    return make()


def make_camera(spec: CameraSpec, default: Camera, size: Optional[Tuple[int, int]]) -> Camera:
    """A camera from its description (``None``: the scene's own; a dict of ``eye``,
    ``target`` and ``fov_y_deg``, or ``projection = "orthographic"`` with ``ymag`` and
    ``xmag``), at ``size`` when given."""
    if spec is None:
        cam = default
    else:
        allowed = {"eye", "target", "fov_y_deg", "projection", "xmag", "ymag"}
        unknown = set(spec) - allowed
        if unknown or "eye" not in spec or "target" not in spec:
            raise ShadowlabError(
                f"camera {dict(spec)!r} must be a table of eye, target and fov_y_deg "
                "(or projection = \"orthographic\" with ymag and xmag)"
            )
        w, h = size if size else (default.width, default.height)
        if spec.get("projection", "perspective") == "orthographic":
            cam = Camera.orthographic(spec["eye"], spec["target"], float(spec["ymag"]),
                                      spec.get("xmag"), w, h)
        else:
            cam = Camera(spec["eye"], spec["target"], float(spec.get("fov_y_deg", 45.0)), w, h)
    return cam.with_size(*size) if size else cam


def _named(items: Any, what: str, default_name: str) -> Dict[str, Any]:
    """Named descriptions from a mapping, a list (named by position) or ``None`` (one,
    ``default_name``, meaning the scene's own)."""
    if items is None:
        return {default_name: None}
    if isinstance(items, Mapping):
        out = dict(items)
    elif isinstance(items, (list, tuple)):
        out = {(s if isinstance(s, str) else f"{what}{i}"): s for i, s in enumerate(items)}
    else:
        raise ShadowlabError(f"{what}s must be a list or a table of {what}s")
    if not out:
        raise ShadowlabError(f"{what}s names no {what}")
    return out


def slug(text: str) -> str:
    """A file-name-safe form of ``text``."""
    return re.sub(r"[^A-Za-z0-9.-]+", "_", text).strip("_")[:48] or "x"


@dataclass(frozen=True)
class Job:
    """One scene under one light through one camera: every technique and parameter value
    over one camera pass and one reference. Plain data, so it travels to any worker; its
    ``key`` names its result file and is the same wherever and whenever it is computed."""

    scene: str
    scene_params: Dict[str, Any]
    light_name: str
    light: LightSpec
    camera_name: str
    camera: CameraSpec
    techniques: List[str]
    params: Dict[str, Dict[str, Any]]
    sweeps: Dict[str, List[Any]]
    size: Optional[Tuple[int, int]]
    reference_spp: int
    reference_pattern: str
    frames: int
    images: bool = field(default=False, compare=False)

    @property
    def key(self) -> str:
        """``scene-light-camera-HASH``, the hash over everything the result depends on."""
        body = asdict(self)
        body.pop("images")
        digest = hashlib.sha256(json.dumps(body, sort_keys=True, default=str).encode())
        return f"{slug(self.scene.rsplit('/', 1)[-1])}-{slug(self.light_name)}-" \
               f"{slug(self.camera_name)}-{digest.hexdigest()[:12]}"


def expand(
    scenes: Sequence[Any],
    techniques: Sequence[str],
    sweeps: Optional[Mapping[str, Sequence[Any]]],
    params: Optional[Mapping[str, Mapping[str, Any]]],
    lights: Any,
    cameras: Any,
    size: Optional[Tuple[int, int]],
    reference_spp: int,
    reference_pattern: str,
    frames: int,
    images: bool,
) -> List[Job]:
    """The jobs of a study, scene by scene, light by light, camera by camera."""
    if isinstance(scenes, str) or not scenes:
        raise ShadowlabError("scenes must be a non-empty list of scene names or files")
    if isinstance(techniques, str) or not techniques:
        raise ShadowlabError("techniques must be a non-empty list of technique names")
    if size is not None:
        if len(size) != 2 or not all(isinstance(v, int) and v > 0 for v in size):
            raise ShadowlabError(f"size {size!r} must be two positive integers (width, height)")
        size = (int(size[0]), int(size[1]))
    light_specs = _named(lights, "light", "scene")
    camera_specs = _named(cameras, "camera", "scene")
    jobs = []
    for s in scenes:
        spec, sparams = (s, {}) if isinstance(s, str) else (s["scene"], dict(s.get("params", {})))
        if os.path.exists(spec):  # a file: by its absolute path, for workers elsewhere
            spec = os.path.abspath(spec)
        for ln, l in light_specs.items():
            for cn, c in camera_specs.items():
                jobs.append(Job(
                    scene=str(spec), scene_params=sparams, light_name=str(ln), light=l,
                    camera_name=str(cn), camera=c, techniques=list(techniques),
                    params={k: dict(v) for k, v in (params or {}).items()},
                    sweeps={k: list(v) for k, v in (sweeps or {}).items()},
                    size=size, reference_spp=int(reference_spp),
                    reference_pattern=str(reference_pattern), frames=int(frames),
                    images=bool(images),
                ))
    keys = [j.key for j in jobs]
    if len(set(keys)) != len(keys):
        raise ShadowlabError("two jobs of the study are the same: list each scene, light and camera once")
    return jobs
