"""shadowlab.study on a local Dask cluster: the command line's numbers row for row, a worker
killed mid-study, a study resumed, a scene that does not load."""

import json
import os
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("dask.distributed")
pytest.importorskip("pandas")
pytest.importorskip("pyarrow")

import pandas as pd  # noqa: E402

import shadowlab as sl  # noqa: E402
from shadowlab.study import Study, local_client  # noqa: E402
from shadowlab.study._job import result_path  # noqa: E402

REPO = Path(__file__).resolve().parents[3]
CLI = Path(os.environ.get("SHADOWLAB_CLI", REPO / "target" / "release" / "shadowlab"))

SCENES = ["cage", "fence-leak", "bunny"]
TECHNIQUES = ["sm", "pcf", "afsm"]
SWEEP = {"sm.resolution": [256, 512]}
SIZE = (64, 48)


@pytest.fixture(scope="module")
def client():
    """A local cluster of two single-threaded worker processes, shared by the tests."""
    with local_client(workers=2, threads=1) as c:
        yield c


def cli_metrics(tmp_path, scene, extra=()):
    assert CLI.is_file(), f"build the command line first (cargo build --release); looked for {CLI}"
    out = tmp_path / f"cli-{scene}"
    args = [str(CLI), "--quiet", "compare", "--scene", scene, "--techniques", ",".join(TECHNIQUES),
            "--sweep", "sm.resolution=256,512", "--reference-spp", "1",
            "--width", str(SIZE[0]), "--height", str(SIZE[1]), "--out", str(out), *extra]
    subprocess.run(args, check=True, capture_output=True)
    return json.loads((out / "metrics.json").read_text())


def test_a_study_gives_the_command_lines_numbers_row_for_row(tmp_path, client):
    study = Study(SCENES, TECHNIQUES, SWEEP, size=SIZE, out=tmp_path / "study")
    assert len(study.jobs) == 3
    rows = study.run(client, progress=False)
    assert rows["error"].isna().all()
    assert len(rows) == 3 * 4  # scenes × (sm at two resolutions, pcf, afsm)
    for scene in SCENES:
        m = cli_metrics(tmp_path, scene)
        ours = rows[rows["scene"] == scene]
        assert list(ours["label"]) == [r["label"] for r in m["results"]]
        for row, r in zip(ours.itertuples(), m["results"]):
            # The same scene, frame, techniques and reference through the same library:
            # equal to the last bit (results do not depend on the thread count).
            assert row.mismatch_rate == r["mismatch_rate"], (scene, row.label)
            assert row.mean_abs_error == r["mean_abs_error"], (scene, row.label)
            assert row.mean_abs_error_rgb == r["mean_abs_error_rgb"], (scene, row.label)
            assert row.memory_bytes == r["memory_bytes"], (scene, row.label)
            assert row.reference_spp == r["reference_spp"] == 1
            assert json.loads(row.params) == r["params"]
            assert tuple(None if pd.isna(v) else v for v in (row.sweep_key, row.sweep_value)) == (
                (r["sweep"]["key"], r["sweep"]["value"]) if "sweep" in r else (None, None))
            assert row.width == m["width"] and row.covered_pixels == m["covered_pixels"]
            assert row.backend == "cpu" and pd.isna(row.adapter)
            assert row.time_ms > 0 and row.frame == 0


def test_a_sequence_gives_the_command_lines_numbers_frame_by_frame(tmp_path):
    scene = sl.Scene.load("street")
    m = scene.compare(TECHNIQUES, scene.camera.with_size(*SIZE), sweeps=SWEEP, frames=3)
    cli = cli_metrics(tmp_path, "street", ["--frames", "3"])
    assert [r["label"] for r in m["results"]] == [r["label"] for r in cli["results"]]
    for ours, theirs in zip(m["results"], cli["results"]):
        assert len(ours["frames"]) == 3
        for f, g in zip(ours["frames"], theirs["frames"]):
            assert f["frame"] == g["frame"]
            assert f["mismatch_rate"] == g["mismatch_rate"], (ours["label"], f["frame"])
            assert f["mean_abs_error"] == g["mean_abs_error"], (ours["label"], f["frame"])


def test_a_worker_killed_mid_job_loses_no_result(tmp_path, client):
    log, marker = tmp_path / "started.log", tmp_path / "killed"

    def kill_the_first(job):
        # Every start is logged; the first job to start kills its own worker process
        # (SIGKILL: nothing is cleaned up), once.
        import os as _os
        import signal as _signal

        with open(log, "a") as f:
            f.write(job.key + "\n")
        try:
            _os.close(_os.open(marker, _os.O_CREAT | _os.O_EXCL))
        except FileExistsError:
            return
        _os.kill(_os.getpid(), _signal.SIGKILL)

    lights = {"sun": "directional:-0.4,1,0.3", "low": "directional:1,0.6,0.2"}
    study = Study(SCENES[:2], TECHNIQUES, SWEEP, lights=lights, size=SIZE,
                  out=tmp_path / "study", before_job=kill_the_first)
    rows = study.run(client, progress=False)
    started = log.read_text().split()
    killed = started[0]
    assert marker.exists() and started.count(killed) == 2  # killed once, then run again
    assert sorted(set(started)) == sorted(j.key for j in study.jobs)
    assert rows["error"].isna().all() and len(rows) == 4 * 4
    job = next(j for j in study.jobs if j.key == killed)
    scene = sl.Scene.load(job.scene)
    light = sl.Light.directional([float(v) for v in lights[job.light_name].split(":")[1].split(",")])
    m = scene.compare(TECHNIQUES, scene.camera.with_size(*SIZE), light, sweeps=SWEEP)
    ours = rows[rows["job"] == killed]
    assert list(ours["mismatch_rate"]) == [r["mismatch_rate"] for r in m["results"]]
    assert list(ours["mean_abs_error"]) == [r["mean_abs_error"] for r in m["results"]]


def test_an_interrupted_study_runs_only_the_missing_jobs(tmp_path, client):
    log = tmp_path / "started.log"

    def note(job):
        with open(log, "a") as f:
            f.write(job.key + "\n")

    study = Study(SCENES, ["sm", "afsm"], size=SIZE, out=tmp_path / "study", before_job=note)
    whole = study.run(client, progress=False)
    paths = [result_path(study.out, j) for j in study.jobs]
    # As a study stopped after its first job leaves it: one file, and a temporary file of
    # a job that was being written.
    for p in paths[1:]:
        p.unlink()
    (paths[1].parent / f".{paths[1].name}.partial.tmp").write_bytes(b"PAR1")
    first_written = paths[0].stat().st_mtime_ns
    log.unlink()
    assert study.missing() == study.jobs[1:]
    again = study.run(client, progress=False)
    assert sorted(log.read_text().split()) == sorted(j.key for j in study.jobs[1:])
    assert paths[0].stat().st_mtime_ns == first_written
    cols = ["job", "label", "mismatch_rate", "mean_abs_error", "memory_bytes"]
    assert again[cols].equals(whole[cols])
    log.unlink()
    study.run(client, progress=False)  # nothing missing: nothing runs
    assert not log.exists()


def test_a_scene_that_does_not_load_is_one_error_row(tmp_path, client):
    study = Study(["cage", str(tmp_path / "missing.obj")], ["sm", "afsm"], size=SIZE,
                  out=tmp_path / "study")
    rows = study.run(client, progress=False)
    bad = rows[rows["error"].notna()]
    assert len(bad) == 1
    assert "missing.obj" in bad["error"].iloc[0] and "\n" not in bad["error"].iloc[0]
    assert bad["technique"].isna().all()
    assert list(rows[rows["scene"] == "cage"]["label"]) == ["sm", "afsm"]


def test_the_command_line_runs_a_toml_study_and_writes_its_summary(tmp_path, client, capsys):
    from shadowlab.study.__main__ import main

    (tmp_path / "study.toml").write_text(
        'scenes = ["cage", "fence-leak", "nope.obj"]\ntechniques = ["sm", "afsm"]\n'
        'size = [64, 48]\n[sweeps]\n"sm.resolution" = [256, 512]\n'
    )
    out = tmp_path / "out"
    assert main([str(tmp_path / "study.toml"), "--out", str(out),
                 "--scheduler", client.scheduler.address, "--quiet"]) == 0
    rows = pd.read_parquet(out / "rows.parquet")
    summary = pd.read_csv(out / "summary.csv")
    assert list(summary["label"]) == ["sm.resolution=256", "sm.resolution=512", "afsm"]
    for s in summary.itertuples():
        errors = sorted(rows[rows["label"] == s.label]["mean_abs_error"])
        assert len(errors) == s.rows == 2
        assert s.median_mean_abs_error == pytest.approx((errors[0] + errors[1]) / 2, rel=1e-12)
        assert s.worst_mean_abs_error == errors[-1]
    assert "nope.obj" in (out / "summary.md").read_text()
    assert (out / "summary.svg").read_text().startswith("<svg")
    (tmp_path / "bad.toml").write_text('scenes = ["cage"]\ntechnique = ["sm"]\n')
    assert main([str(tmp_path / "bad.toml"), "--out", str(out)]) == 2
    assert "unknown key 'technique'" in capsys.readouterr().err
