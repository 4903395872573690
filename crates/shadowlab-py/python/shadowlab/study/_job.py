"""One job on a worker: load the scene, compare every technique and parameter value over
one camera pass and one reference, and write the rows as one Parquet file (written to a
temporary name and renamed, so a file that exists is whole)."""

import json
import os
import struct
import uuid
import zlib
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

import numpy as np

from .. import Scene
from ._spec import Job, make_camera, make_light, slug

#: The columns of a study's rows, in order.
COLUMNS = [
    "job", "scene", "scene_name", "light", "camera", "technique", "label", "params",
    "sweep_key", "sweep_value", "frame", "mismatch_rate", "mean_abs_error",
    "mean_abs_error_rgb", "time_ms", "memory_bytes", "reference_spp", "reference_std_error",
    "backend", "adapter", "width", "height", "triangles", "covered_pixels", "camera_pass_ms",
    "reference_ms", "threads", "shadowlab_version", "error",
]

_FLOATS = {"mismatch_rate", "mean_abs_error", "mean_abs_error_rgb", "time_ms",
           "reference_std_error", "camera_pass_ms", "reference_ms"}
_INTS = {"frame", "memory_bytes", "reference_spp", "width", "height", "triangles",
         "covered_pixels", "threads"}

#: Each column's type, the same in every job's file (an error row's empty columns too).
DTYPES = {c: "float64" if c in _FLOATS else "Int64" if c in _INTS else "string" for c in COLUMNS}


def result_path(out: Path, job: Job) -> Path:
    """Where a job's rows go."""
    return Path(out) / "jobs" / f"{job.key}.parquet"


def _error_sentence(e: BaseException) -> str:
    text = " ".join(str(e).split()) or type(e).__name__
    return text if isinstance(e, ValueError) else f"{type(e).__name__}: {text}"


def _base(job: Job) -> Dict[str, Any]:
    row: Dict[str, Any] = {c: None for c in COLUMNS}
    row.update(job=job.key, scene=job.scene, light=job.light_name, camera=job.camera_name)
    return row


def rows_of(job: Job, m: Dict[str, Any]) -> List[Dict[str, Any]]:
    """The rows of one comparison: one per run and frame."""
    rows = []
    common = _base(job)
    common.update(
        scene_name=m["scene"], width=m["width"], height=m["height"], triangles=m["triangles"],
        covered_pixels=m["covered_pixels"], camera_pass_ms=m["camera_pass_ms"],
        reference_ms=m["reference"]["time_ms"], threads=m["threads"],
        shadowlab_version=m["shadowlab_version"],
    )
    for r in m["results"]:
        run = dict(common)
        sweep = r.get("sweep") or {}
        run.update(
            technique=r["technique"], label=r["label"],
            params=json.dumps(r["params"], sort_keys=True),
            sweep_key=sweep.get("key"), sweep_value=sweep.get("value"),
            reference_spp=r["reference_spp"], reference_std_error=r.get("reference_std_error"),
            backend=r.get("backend", "cpu"), adapter=r.get("adapter"),
        )
        frames = r.get("frames") or [dict(
            frame=0, time_ms=r["time_ms"], memory_bytes=r["memory_bytes"],
            mismatch_rate=r["mismatch_rate"], mean_abs_error=r["mean_abs_error"],
            mean_abs_error_rgb=r["mean_abs_error_rgb"],
        )]
        for f in frames:
            row = dict(run)
            row.update(
                frame=f["frame"], time_ms=f["time_ms"], memory_bytes=f["memory_bytes"],
                mismatch_rate=f["mismatch_rate"], mean_abs_error=f["mean_abs_error"],
                mean_abs_error_rgb=f.get("mean_abs_error_rgb"),
            )
            rows.append(row)
    return rows


def _png(path: Path, img: np.ndarray) -> None:
    """An ``(H, W, 3)`` float image in [0, 1] as an 8-bit PNG."""
    rgb = (np.clip(img, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(h))

    def chunk(kind: bytes, data: bytes) -> bytes:
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    head = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    data = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", head) + chunk(b"IDAT", zlib.compress(raw, 6))
    _atomic_write(path, lambda p: p.write_bytes(data + chunk(b"IEND", b"")))


def _atomic_write(path: Path, write: Callable[[Path], Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def _images(out: Path, job: Job, scene: Scene, camera: Any, light: Any, m: Dict[str, Any]) -> None:
    """The shadow term of the reference and of every run, one PNG each."""
    folder = Path(out) / "images" / job.key
    ref = scene.render("raytrace", camera, light)
    _png(folder / "reference.png", ref)
    for r in m["results"]:
        params = dict(job.params.get(r["technique"], {}))
        if r.get("sweep"):
            params[r["sweep"]["key"]] = r["sweep"]["value"]
        img = scene.render(r["technique"], camera, light, params)
        _png(folder / f"{slug(r['label'])}.png", img)


def run_job(job: Job, out: str, before: Optional[Callable[[Job], None]] = None) -> str:
    """Runs ``job`` and writes its rows (or its one error row) to its Parquet file; returns
    the file's path. Idempotent: a rerun (a worker lost mid-job) writes the same rows."""
    import pandas as pd

    if before is not None:
        before(job)
    path = result_path(Path(out), job)
    try:
        scene = Scene.load(job.scene, job.scene_params or None)
        camera = make_camera(job.camera, scene.camera, job.size)
        light = make_light(job.light)
        m = scene.compare(
            job.techniques, camera, light, job.params or None, job.reference_spp,
            job.reference_pattern, job.sweeps or None, job.frames,
        )
        rows = rows_of(job, m)
        if job.images and job.frames == 1:
            _images(Path(out), job, scene, camera, light, m)
    except Exception as e:  # one error row per failed job, never the end of the study
        row = _base(job)
        row["error"] = _error_sentence(e)
        rows = [row]
    frame = pd.DataFrame(rows, columns=COLUMNS).astype(DTYPES)
    _atomic_write(path, lambda p: frame.to_parquet(p, index=False))
    return str(path)
