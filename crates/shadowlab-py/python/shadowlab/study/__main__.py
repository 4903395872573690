"""``python -m shadowlab.study STUDY.toml --out DIR [--scheduler ADDRESS]``: runs the study a
TOML file describes (on a local cluster, or on the Dask scheduler at ADDRESS), then writes
``DIR/rows.parquet``, ``DIR/summary.csv``, ``DIR/summary.md`` and ``DIR/summary.svg`` and
prints the summary. The jobs' own results are in ``DIR/jobs``; run it again to resume.

``--bench`` runs the study twice from scratch instead, on one worker and on ``--workers``
workers (each with ``--threads`` threads), and prints both times and the speed-up.

Bad input (an unreadable file, an unknown key) is one sentence on stderr and exit code 2.
"""

import argparse
import json
import os
import shutil
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Optional

from .. import ShadowlabError
from . import Study, local_client
from ._summary import markdown, write_summary

#: The keys a study file may hold.
KEYS = {"scenes", "techniques", "sweeps", "params", "lights", "cameras", "size",
        "reference_spp", "reference_pattern", "frames", "images"}


def load_toml(path: Path) -> Dict[str, Any]:
    """The study a TOML file describes, as ``Study``'s keyword arguments."""
    try:
        import tomllib
    except ImportError:  # Python < 3.11
        import tomli as tomllib  # type: ignore[no-redef]
    try:
        spec = tomllib.loads(path.read_text())
    except OSError as e:
        raise ShadowlabError(f"{path}: cannot read the study file ({e.strerror or e})") from None
    except tomllib.TOMLDecodeError as e:
        raise ShadowlabError(f"{path}: not a valid TOML file ({e})") from None
    unknown = sorted(set(spec) - KEYS)
    if unknown:
        raise ShadowlabError(f"{path}: unknown key {unknown[0]!r}; a study takes {', '.join(sorted(KEYS))}")
    for required in ("scenes", "techniques"):
        if required not in spec:
            raise ShadowlabError(f"{path}: the study names no {required} (key {required!r})")
    here = path.resolve().parent
    spec["scenes"] = [_beside(here, s) for s in spec["scenes"]] \
        if isinstance(spec["scenes"], list) else spec["scenes"]
    if "size" in spec:
        spec["size"] = tuple(spec["size"])
    return spec


def _beside(folder: Path, scene: Any) -> Any:
    """A scene file named relative to the study file, by its path from here; built-in
    names and tables as they are."""
    if isinstance(scene, str) and (folder / scene).exists():
        return str(folder / scene)
    if isinstance(scene, dict) and isinstance(scene.get("scene"), str) \
            and (folder / scene["scene"]).exists():
        return {**scene, "scene": str(folder / scene["scene"])}
    return scene


def _cpu_seconds() -> float:
    """The CPU time of this process (a worker's), user and system."""
    import resource

    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _bench(spec: Dict[str, Any], out: Path, workers: int, threads: int) -> Dict[str, Any]:
    """The study's wall time on 1 and on ``workers`` workers, each from an empty folder, the
    clusters started (and their workers' imports done) before the clock starts; with the
    share of the time the workers spent in jobs and the CPU cores they obtained (on a
    machine shared with other work, fewer than the workers)."""
    from dask.distributed import get_task_stream

    times, busy, cores = {}, {}, {}
    for n in sorted({1, workers}):
        folder = out / f"bench-{n}-workers"
        shutil.rmtree(folder, ignore_errors=True)
        study = Study(**spec, out=folder)
        with local_client(n, threads) as client:
            client.run(lambda: __import__("shadowlab.study"))
            cpu0 = sum(client.run(_cpu_seconds).values())
            with get_task_stream(client) as stream:
                t0 = time.perf_counter()
                rows = study.run(client, progress=False)
                times[n] = time.perf_counter() - t0
            cpu = sum(client.run(_cpu_seconds).values()) - cpu0
        spans = [s for t in stream.data for s in t["startstops"] if s["action"] == "compute"]
        busy[n] = sum(s["stop"] - s["start"] for s in spans) / (n * times[n])
        cores[n] = cpu / times[n]
        print(f"{n} worker(s) x {threads} thread(s): {len(study.jobs)} jobs, {len(rows)} rows, "
              f"{times[n]:.2f} s; workers busy {busy[n]:.0%} of the time; "
              f"CPU obtained {cores[n]:.2f} cores")
    result = {"jobs": len(study.jobs), "threads_per_worker": threads,
              "seconds": {str(k): v for k, v in times.items()},
              "busy_share": {str(k): v for k, v in busy.items()},
              "cores_obtained": {str(k): v for k, v in cores.items()},
              "load_average": os.getloadavg()[0],
              "speedup": times[1] / times[workers]}
    print(f"speed-up with {workers} workers: {result['speedup']:.2f}x")
    (out / "bench.json").write_text(json.dumps(result, indent=2) + "\n")
    return result


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="python -m shadowlab.study", description=__doc__.split("\n\n")[0])
    p.add_argument("study", type=Path, help="the study's TOML file")
    p.add_argument("--out", type=Path, required=True, help="results folder")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    p.add_argument("--workers", type=int, help="local workers (default: one per CPU)")
    p.add_argument("--threads", type=int, default=1, help="threads per local worker (default 1)")
    p.add_argument("--bench", action="store_true", help="time the study on 1 and on --workers workers")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary on stdout")
    a = p.parse_args(argv)
    try:
        spec = load_toml(a.study)
        if a.bench:
            _bench(spec, a.out, a.workers or os.cpu_count() or 1, a.threads)
            return 0
        study = Study(**spec, out=a.out)
        if a.scheduler:
            from dask.distributed import Client

            with Client(a.scheduler) as client:
                rows = study.run(client, progress=not a.quiet)
        else:
            rows = study.run(workers=a.workers, threads=a.threads, progress=not a.quiet)
        summary = write_summary(rows, a.out)
    except ShadowlabError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if not a.quiet:
        print(markdown(summary, rows), end="")
        print(f"rows: {a.out / 'rows.parquet'}; summary: {a.out / 'summary.md'}, {a.out / 'summary.svg'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
