"""Studies bigger than one frame: techniques over many scenes, lights, cameras and parameter
values, run as independent jobs on a Dask cluster (``pip install "shadowlab[study]"``).

A :class:`Study` expands to one job per scene × light × camera; each job loads its scene once
and measures every technique and every value of every sweep over one camera pass and one
ray-traced reference (``Scene.compare``), then writes its rows as one Parquet file in
``OUT/jobs``. ``Study.run`` sends the jobs that have no file yet to a Dask client (a local
cluster of single-threaded worker processes unless one is given) and returns every row as a
pandas DataFrame: one per scene, light, camera, technique, parameter set and frame.

A job that fails (a scene that does not load, a bad parameter) is one row whose ``error``
says why; the study goes on. A study that stops resumes where it left off: run it again
and only the jobs without a file run. A worker lost mid-job loses nothing: the scheduler
runs the job again elsewhere, and a job writes the same rows wherever it runs, through a
temporary file renamed into place.

``python -m shadowlab.study STUDY.toml --out DIR [--scheduler ADDRESS]`` runs a study
described in TOML and writes its summary (see ``shadowlab.study.__main__``).
"""

import os
import sys
import time
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator, List, Mapping, Optional, Sequence, Tuple

from .. import ShadowlabError
from ._job import COLUMNS, DTYPES, result_path, run_job
from ._spec import Job, expand
from ._summary import summarize, write_summary

__all__ = ["COLUMNS", "Job", "Study", "local_client", "summarize", "write_summary"]


@contextmanager
def local_client(workers: Optional[int] = None, threads: int = 1) -> Iterator[Any]:
    """A Dask client on a local cluster of ``workers`` processes (default: one per CPU), each
    running one job at a time on ``threads`` threads."""
    import dask
    from dask.distributed import Client, LocalCluster

    n = workers or os.cpu_count() or 1
    env = {"RAYON_NUM_THREADS": str(threads)}
    # A job lasts seconds: a worker is handed its next job when it finishes one (no queue
    # of two on one worker while another idles at the end of the study).
    with dask.config.set({"distributed.scheduler.worker-saturation": 1.0}), \
            LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                         dashboard_address=":0", env=env) as cluster, Client(cluster) as client:
        client.wait_for_workers(n)
        yield client


class Study:
    """Techniques over scenes × lights × cameras, with parameter sweeps.

    - ``scenes``: built-in scene names or scene files (as ``--scene``), or dicts
      ``{"scene": NAME, "params": {...}}`` for a built-in scene's parameters;
    - ``techniques``: technique names; ``params``: ``{technique: {key: value}}``;
    - ``sweeps``: ``{"technique.key": [values]}``, one result per value (as ``--sweep``);
    - ``lights``: ``{name: light}`` or a list, each a ``--light`` string
      (``"directional:-0.4,1,0.3"``) or ``{"light": STRING, "size": S, "samples": N}``;
      default: each scene's own light;
    - ``cameras``: ``{name: {"eye": [...], "target": [...], "fov_y_deg": F}}`` or a list;
      default: each scene's own camera;
    - ``size``: ``(width, height)`` of every image; ``reference_spp``, ``reference_pattern``:
      the reference's samples per pixel and their pattern; ``frames``: frames along each
      scene's camera path, each measured against its own reference;
    - ``out``: the results folder; ``images``: also write each run's shadow term and the
      reference's as PNG files in ``OUT/images/JOB``;
    - ``before_job``: a function the worker calls with each job before running it.
    """

    def __init__(
        self,
        scenes: Sequence[Any],
        techniques: Sequence[str],
        sweeps: Optional[Mapping[str, Sequence[Any]]] = None,
        *,
        params: Optional[Mapping[str, Mapping[str, Any]]] = None,
        lights: Any = None,
        cameras: Any = None,
        size: Optional[Tuple[int, int]] = None,
        reference_spp: int = 1,
        reference_pattern: str = "grid",
        frames: int = 1,
        out: "str | os.PathLike[str]" = "shadowlab-study",
        images: bool = False,
        before_job: Optional[Callable[[Job], None]] = None,
    ) -> None:
        self.jobs: List[Job] = expand(
            scenes, techniques, sweeps, params, lights, cameras, size, reference_spp,
            reference_pattern, frames, images,
        )
        self.out = Path(out)
        self.before_job = before_job

    def missing(self) -> List[Job]:
        """The jobs whose results are not written yet."""
        return [j for j in self.jobs if not result_path(self.out, j).exists()]

    def run(self, client: Any = None, *, workers: Optional[int] = None, threads: int = 1,
            progress: bool = True) -> Any:
        """Runs the missing jobs on ``client`` (default: a local cluster of ``workers``
        processes with ``threads`` threads each) and returns every job's rows."""
        todo = self.missing()
        if todo:
            if client is None:
                with local_client(workers, threads) as c:
                    self._run_on(c, todo, progress)
            else:
                self._run_on(client, todo, progress)
        return self.results()

    def _run_on(self, client: Any, todo: List[Job], progress: bool) -> None:
        from dask.distributed import as_completed

        (self.out / "jobs").mkdir(parents=True, exist_ok=True)
        futures = client.map(
            run_job, todo, out=str(self.out.resolve()), before=self.before_job,
            key=[f"shadowlab-study-{j.key}" for j in todo],
        )
        t0, done, lost = time.perf_counter(), 0, []
        for f in as_completed(futures):
            try:
                f.result()
            except Exception as e:  # the job could not run at all (e.g. lost workers)
                lost.append(f"{f.key}: {' '.join(str(e).split())}")
            done += 1
            if progress:
                _bar(done, len(todo), len(self.jobs) - len(todo), len(lost), time.perf_counter() - t0)
        if progress:
            sys.stderr.write("\n")
        if lost:
            raise ShadowlabError(
                f"{len(lost)} of {len(todo)} jobs could not run; run the study again to retry "
                f"them (first: {lost[0]})"
            )

    def results(self) -> Any:
        """Every written job's rows, in job order (jobs without a file have none)."""
        import pandas as pd

        frames = [pd.read_parquet(p) for p in (result_path(self.out, j) for j in self.jobs)
                  if p.exists()]
        if not frames:
            return pd.DataFrame(columns=COLUMNS).astype(DTYPES)
        return pd.concat(frames, ignore_index=True)


def _bar(done: int, total: int, skipped: int, lost: int, seconds: float) -> None:
    width = 30
    filled = width * done // max(total, 1)
    extra = f", {skipped} already written" if skipped else ""
    extra += f", {lost} could not run" if lost else ""
    sys.stderr.write(f"\rstudy [{'#' * filled}{'.' * (width - filled)}] {done}/{total} jobs"
                     f"{extra} {seconds:6.1f} s")
    sys.stderr.flush()
