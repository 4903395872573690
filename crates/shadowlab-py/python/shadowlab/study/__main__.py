"""``python -m shadowlab.study STUDY.toml --out DIR [--scheduler ADDRESS]``: runs the study a
TOML file describes (on a local cluster, or on the Dask scheduler at ADDRESS), then writes
``DIR/rows.parquet``, ``DIR/summary.csv``, ``DIR/summary.md`` and ``DIR/summary.svg`` and
prints the summary. The jobs' own results are in ``DIR/jobs``; run it again to resume.

``--bench`` times the study from scratch instead, ``--repeat`` times on one worker and on
``--workers`` workers (each with ``--threads`` threads), and prints the times and the
speed-up of the fastest runs.

Bad input (an unreadable file, an unknown key) is one sentence on stderr and exit code 2.
"""

import argparse
import contextlib
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


def _timed(study: Study, client: Any, n: int) -> Dict[str, float]:
    """One timed run of ``study`` from an empty folder on ``client``'s ``n`` workers: wall
    seconds, the share of it the workers spent in jobs, the CPU cores they obtained."""
    from dask.distributed import get_task_stream

    shutil.rmtree(study.out, ignore_errors=True)
    cpu0 = sum(client.run(_cpu_seconds).values())
    with get_task_stream(client) as stream:
        t0 = time.perf_counter()
        study.run(client, progress=False)
        wall = time.perf_counter() - t0
    cpu = sum(client.run(_cpu_seconds).values()) - cpu0
    spans = [s for t in stream.data for s in t["startstops"] if s["action"] == "compute"]
    busy = sum(s["stop"] - s["start"] for s in spans) / (n * wall)
    return {"seconds": wall, "busy_share": busy, "cores_obtained": cpu / wall}


def _bench(spec: Dict[str, Any], out: Path, workers: int, threads: int, repeat: int) -> Dict[str, Any]:
    """The study's wall time on 1 and on ``workers`` workers, ``repeat`` times each, the
    runs alternating (so that other work on the machine falls on both alike), each from
    an empty folder, the clusters started and their workers' imports done before the
    clock starts. The fastest run of each is the one least disturbed: the speed-up is
    theirs. Each run also states the share of its time the workers spent in jobs and the
    CPU cores they obtained (fewer than the workers on a machine busy with other work)."""
    sizes = sorted({1, workers})
    runs: Dict[int, List[Dict[str, float]]] = {n: [] for n in sizes}
    with contextlib.ExitStack() as stack:
        clients = {n: stack.enter_context(local_client(n, threads)) for n in sizes}
        for c in clients.values():
            c.run(lambda: __import__("shadowlab.study"))
        for r in range(repeat):
            for n in sizes:
                study = Study(**spec, out=out / f"bench-{n}-workers")
                runs[n].append(_timed(study, clients[n], n))
                t = runs[n][-1]
                print(f"run {r + 1}: {n} worker(s) x {threads} thread(s), {len(study.jobs)} jobs: "
                      f"{t['seconds']:.2f} s; workers busy {t['busy_share']:.0%} of the time; "
                      f"CPU obtained {t['cores_obtained']:.2f} cores", flush=True)
    best = {n: min(runs[n], key=lambda t: t["seconds"]) for n in sizes}
    result = {"jobs": len(study.jobs), "threads_per_worker": threads, "runs": runs,
              "best": best, "load_average": os.getloadavg(),
              "speedup": best[1]["seconds"] / best[workers]["seconds"]}
    print(f"fastest: 1 worker {best[1]['seconds']:.2f} s, {workers} workers "
          f"{best[workers]['seconds']:.2f} s; speed-up {result['speedup']:.2f}x")
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
    p.add_argument("--repeat", type=int, default=5, help="--bench: timed runs of each (default 5)")
    p.add_argument("--quiet", action="store_true", help="no progress bar and no summary on stdout")
    a = p.parse_args(argv)
    try:
        spec = load_toml(a.study)
        if a.bench:
            _bench(spec, a.out, a.workers or os.cpu_count() or 1, a.threads, a.repeat)
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
