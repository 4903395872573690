"""The Python package: arrays in, images out, the command line's values, errors, the GIL."""

import os
import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import shadowlab as sl

REPO = Path(__file__).resolve().parents[3]
CLI = Path(os.environ.get("SHADOWLAB_CLI", REPO / "target" / "release" / "shadowlab"))


def ground_and_box():
    """A ground quad and a unit box floating above it, as arrays."""
    ground = np.array([[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]], np.float32)
    corners = np.array(
        [[x, y, z] for z in (-0.5, 0.5) for y in (0.5, 1.5) for x in (-0.5, 0.5)], np.float32
    )
    box = np.array(
        [[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4],
         [2, 6, 3], [3, 6, 7], [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]],
        np.uint32,
    )
    return ground, np.array([[0, 1, 2], [0, 2, 3]], np.uint32), corners, box


def box_scene():
    g, gf, b, bf = ground_and_box()
    scene = sl.Scene.from_arrays(g, gf, name="box")
    scene.add_mesh(b, bf, color=(0.8, 0.2, 0.2))
    return scene


CAMERA = sl.Camera((0.0, 5.0, 7.0), (0.0, 0.0, 0.0), 50.0, 96, 72)
SUN = sl.Light.directional((0.0, 1.0, 0.0))


def test_arrays_in_image_out():
    scene = box_scene()
    assert scene.triangles == 14
    img = scene.render("afsm", CAMERA, SUN)
    assert img.shape == (72, 96, 3) and img.dtype == np.float32
    # The shadow of the box falls straight down: the pixel at the box's foot is dark,
    # the ground near the image's corner is lit, and afsm equals the reference.
    ref = scene.render("raytrace", CAMERA, SUN)
    assert np.array_equal(img, ref)
    assert 0.0 < (img[..., 0] == 0.0).mean() < 0.5
    assert img[70, 2, 0] == 1.0
    points = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 3.0]], np.float32)
    normals = np.array([[0.0, 1.0, 0.0]] * 2, np.float32)
    vis = scene.visibility(points, normals, SUN)
    assert vis.shape == (2, 3) and vis.dtype == np.float32
    assert vis[0].tolist() == [0.0, 0.0, 0.0] and vis[1].tolist() == [1.0, 1.0, 1.0]
    assert np.array_equal(scene.visibility(points, normals, SUN, technique="afsm"), vis)


def test_equal_to_the_cli_exr(tmp_path):
    assert CLI.is_file(), f"build the command line first (cargo build --release); looked for {CLI}"
    for technique, params in [("pcf", {"resolution": 1024}), ("afsm", {}), ("csm", {})]:
        exr = tmp_path / f"{technique}.exr"
        args = [str(CLI), "render", "--scene", "chessboard", "--width", "160", "--height", "120",
                "--technique", technique, "--output", str(tmp_path / f"{technique}.png"),
                "--visibility", str(exr)]
        for k, v in params.items():
            args += ["--param", f"{k}={v}"]
        subprocess.run(args, check=True, capture_output=True)
        cli = sl.read_exr(exr)
        scene = sl.Scene.load("chessboard")
        ours = scene.render(technique, scene.camera.with_size(160, 120), params=params)
        assert ours.shape == (120, 160, 3)
        assert np.array_equal(ours, cli[..., :3]), technique
        assert 0.0 < cli[..., 3].mean() <= 1.0


def test_gpu_techniques_are_named_like_the_others():
    # gpu:raytrace traces the reference's own rays on the GPU: equal to raytrace on every
    # pixel. Without a GPU adapter (none installed) it is skipped, except under CI.
    scene = box_scene()
    try:
        img = scene.render("gpu:raytrace", CAMERA, SUN)
    except sl.ShadowlabError as e:
        if "no GPU adapter" in str(e) and os.environ.get("CI") != "true":
            pytest.skip(str(e))
        raise
    assert np.array_equal(img, scene.render("raytrace", CAMERA, SUN))
    sm = scene.render("gpu:sm", CAMERA, SUN, params={"resolution": 1024})
    cpu = scene.render("sm", CAMERA, SUN, params={"resolution": 1024})
    assert sm.shape == cpu.shape == (72, 96, 3)
    assert (sm != cpu).any(axis=2).mean() < 0.01
    with pytest.raises(sl.ShadowlabError, match="gpu:sm"):
        scene.render("gpu:sm", CAMERA, SUN, params={"no-such-key": 1})
    # "gpu:all" expands as in `compare --techniques`, each GPU twin right after its CPU
    # technique.
    m = scene.compare(["gpu:all", "sm", "psm"], CAMERA, SUN)
    names = [r["technique"] for r in m["results"]]
    assert names[names.index("sm") + 1] == "gpu:sm"
    assert names[names.index("psm") + 1] == "gpu:psm"
    assert {
        "gpu:lispsm", "gpu:cascaded", "gpu:raytrace", "gpu:afsm", "gpu:asm", "gpu:pcss",
        "gpu:subpixel", "gpu:vsm", "gpu:evsm", "gpu:msm", "gpu:csm", "gpu:csm-soft",
    } <= set(names)


def test_nan_vertices_raise_the_library_sentence():
    g, gf, _, _ = ground_and_box()
    g[2, 1] = np.nan
    with pytest.raises(sl.ShadowlabError) as e:
        sl.Scene.from_arrays(g, gf, name="broken")
    assert str(e.value) == "scene broken: triangle 0 has a non-finite (NaN or infinite) vertex"
    assert isinstance(e.value, ValueError)


def test_bad_input_is_named():
    g, gf, _, _ = ground_and_box()
    with pytest.raises(sl.ShadowlabError, match=r"faces row 1 names vertex 7, outside 0\.\.4"):
        sl.Scene.from_arrays(g, np.array([[0, 1, 2], [0, 2, 7]]))
    with pytest.raises(sl.ShadowlabError, match=r"vertices must have shape \(n, 3\), not \(4, 2\)"):
        sl.Scene.from_arrays(g[:, :2], gf)
    scene = box_scene()
    with pytest.raises(sl.ShadowlabError, match="unknown technique \"nope\""):
        scene.render("nope", CAMERA, SUN)
    with pytest.raises(sl.ShadowlabError, match="technique sm has no parameter \"size\""):
        scene.render("sm", CAMERA, SUN, {"size": 3})
    with pytest.raises(sl.ShadowlabError, match="directional light direction must be a finite"):
        sl.Light.directional((0.0, 0.0, 0.0))
    with pytest.raises(sl.ShadowlabError, match="technique psm cannot answer point queries"):
        scene.visibility(np.zeros((1, 3)), np.ones((1, 3)), SUN, technique="psm")


def test_the_gil_is_released_while_rendering():
    scene = sl.Scene.load("chessboard")
    camera = scene.camera.with_size(640, 480)
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    worker = threading.Thread(target=count)
    worker.start()
    try:
        time.sleep(0.05)  # the worker is running
        t0 = time.perf_counter()
        scene.render("raytrace", camera)
        t1 = time.perf_counter()
    finally:
        stop.set()
        worker.join()
    during = [t for t in ticks if t0 < t < t1]
    # With the GIL held the worker could not tick at all until the call returned.
    assert t1 - t0 > 0.05, "the frame is long enough to tell"
    assert len(during) >= 10, f"{len(during)} ticks during a {1e3 * (t1 - t0):.0f} ms render"


def test_two_lights_equal_two_one_light_frames():
    scene = box_scene()
    lights = [SUN, sl.Light.point((2.0, 4.0, 1.0))]
    both = scene.render_lights("sm", lights, CAMERA)
    assert len(both) == 2
    for vis, light in zip(both, lights):
        assert np.array_equal(vis, scene.render("sm", CAMERA, light))
    assert not np.array_equal(both[0], both[1])


def test_a_moving_object_moves_its_shadow():
    g, gf, b, bf = ground_and_box()
    scene = box_scene()
    before = scene.render("asm", CAMERA, SUN, {"time-budget-ms": "none"})
    revision = scene.revision
    scene.set_mesh_vertices(1, b + np.float32([2.0, 0.0, 0.0]))
    assert scene.revision == revision + 1
    after = scene.render("asm", CAMERA, SUN, {"time-budget-ms": "none"})
    moved = sl.Scene.from_arrays(g, gf, name="box")
    moved.add_mesh(b + np.float32([2.0, 0.0, 0.0]), bf)
    assert np.array_equal(after, moved.render("asm", CAMERA, SUN, {"time-budget-ms": "none"}))
    assert not np.array_equal(before, after)


def test_compare_is_shaped_like_metrics_json():
    scene = box_scene()
    m = scene.compare(["raytrace", "afsm", "sm"], CAMERA, SUN, {"sm": {"resolution": 512}})
    assert m["width"] == 96 and m["height"] == 72 and m["triangles"] == 14
    assert m["reference"]["technique"] == "raytrace"
    assert m["reference"]["samples_per_pixel"] == 1
    assert m["light"] == {"kind": "directional", "to_light": [0.0, 1.0, 0.0]}
    assert set(m["camera"]) >= {"eye", "target", "up", "fov_y_deg", "near", "far", "width", "height"}
    by = {r["technique"]: r for r in m["results"]}
    assert by["raytrace"]["mismatch_rate"] == 0.0 and by["afsm"]["mismatch_rate"] == 0.0
    assert by["sm"]["params"]["resolution"] == 512
    for r in m["results"]:
        assert {"time_ms", "stages_ms", "memory_bytes", "counters", "mean_abs_error"} <= set(r)
    assert sl.techniques()[0] == "raytrace"


def test_params_read_as_written_and_set_the_values_the_run_used():
    scene = box_scene()
    given = {"msm": {"depth-bias": 0.0003}, "cascaded": {"blend": "0.30"}}
    m = scene.compare(["msm", "cascaded", "csm"], CAMERA, SUN, given)
    by = {r["technique"]: r for r in m["results"]}
    # Single-precision values read as a person writes them, not widened to double.
    assert repr(by["msm"]["params"]["depth-bias"]) == "0.0003"
    assert repr(by["cascaded"]["params"]["blend"]) == "0.3"
    assert repr(by["csm"]["params"]["pivot"]) == "0.1"
    for r in m["results"]:
        t = r["technique"]
        again = scene.render(t, CAMERA, SUN, r["params"])
        assert np.array_equal(again, scene.render(t, CAMERA, SUN, given.get(t, {}))), t


def test_area_lights_give_soft_shadows_measured_against_their_reference():
    scene = box_scene()
    rect = sl.Light.rect((0.0, 4.0, 0.0), (1.5, 0.0, 0.0), (0.0, 0.0, 1.5), samples=64)
    assert rect.kind == "rect" and rect.is_area and rect.samples == 64
    assert rect.to_dict()["area"]["kind"] == "rect" and rect.to_dict()["samples"] == 64
    assert not SUN.is_area and SUN.kind == "directional"

    # The reference under an area light has a penumbra: values strictly between 0 and 1,
    # which a point light at the rectangle's centre does not give.
    soft = scene.render("raytrace", CAMERA, rect)
    hard = scene.render("raytrace", CAMERA, sl.Light.point((0.0, 4.0, 0.0)))
    penumbra = (soft[..., 0] > 0.0) & (soft[..., 0] < 1.0)
    assert penumbra.mean() > 0.01
    assert not ((hard[..., 0] > 0.0) & (hard[..., 0] < 1.0)).any()

    # The same soft shadow as a sized point light gives, and deterministic.
    assert np.array_equal(soft, scene.render("raytrace", CAMERA, rect))
    sphere = sl.Light.point((0.0, 4.0, 0.0)).sized(0.75, samples=64)
    assert sphere.kind == "sphere" and sphere.samples == 64

    m = scene.compare(["raytrace", "pcf", "pcss"], CAMERA, rect)
    assert m["area_light"]["kind"] == "rect"
    assert m["reference"]["mean_std_error"] > 0.0
    by = {r["technique"]: r for r in m["results"]}
    assert by["raytrace"]["mean_abs_error"] == 0.0
    # PCSS sizes its filter from the light: closer to the soft reference than fixed PCF.
    assert by["pcss"]["mean_abs_error"] < by["pcf"]["mean_abs_error"]


def test_bad_area_lights_are_named():
    with pytest.raises(sl.ShadowlabError, match="samples"):
        sl.Light.rect((0, 4, 0), (1, 0, 0), (0, 0, 1), samples=0)
    with pytest.raises(sl.ShadowlabError, match="radius"):
        sl.Light.sphere((0, 4, 0), float("nan"))
    rect = sl.Light.rect((0, 4, 0), (1, 0, 0), (0, 0, 1))
    with pytest.raises(sl.ShadowlabError, match="already has an area"):
        rect.sized(1.0)
    with pytest.raises(sl.ShadowlabError, match="punctual"):
        box_scene().render_lights("sm", [rect], CAMERA)


def test_orthographic_camera():
    cam = sl.Camera.orthographic((0.0, 5.0, 7.0), (0.0, 0.0, 0.0), 2.5, width=96, height=72)
    assert cam.projection == "orthographic" and cam.ymag == 2.5
    assert abs(cam.xmag - 2.5 * 96 / 72) < 1e-6
    assert CAMERA.projection == "perspective" and CAMERA.xmag is None and CAMERA.ymag is None
    scene = box_scene()
    img = scene.render("afsm", cam, SUN)
    # Parallel rays, the same exactness: afsm equals the reference, and the box's shadow
    # is in view.
    assert np.array_equal(img, scene.render("raytrace", cam, SUN))
    assert 0.0 < (img[..., 0] == 0.0).mean() < 0.5
    wide = cam.with_size(144, 72)
    assert wide.ymag == 2.5 and abs(wide.xmag - 5.0) < 1e-6
    with pytest.raises(sl.ShadowlabError, match="xmag"):
        sl.Camera.orthographic((0.0, 5.0, 7.0), (0.0, 0.0, 0.0), 1.0, xmag=0.0)
    with pytest.raises(sl.ShadowlabError, match="ymag"):
        sl.Camera.orthographic((0.0, 5.0, 7.0), (0.0, 0.0, 0.0), float("nan"))


def test_up_axis_and_obj_cut_outs():
    masked = REPO / "crates" / "shadowlab" / "assets" / "masked"
    y_up = sl.Scene.load(str(masked / "cards.obj"))
    z_up = sl.Scene.load(str(masked / "cards-zup.obj"), up="z")
    # Turned upright, the Z-up file is its Y-up twin: same bounds, same shadows.
    assert z_up.bounds == y_up.bounds
    a = y_up.render("raytrace", y_up.camera.with_size(96, 72), y_up.light)
    b = z_up.render("raytrace", y_up.camera.with_size(96, 72), y_up.light)
    assert np.array_equal(a, b)
    assert np.array_equal(z_up.render("afsm", y_up.camera.with_size(96, 72), y_up.light), b)
    # The map_Kd card kept whole casts more shadow than cut out.
    whole = sl.Scene.load(str(masked / "cards.obj"), obj_kd_alpha=False)
    c = whole.render("raytrace", y_up.camera.with_size(96, 72), y_up.light)
    assert (c[..., 0] < 0.5).sum() > (a[..., 0] < 0.5).sum()
    with pytest.raises(sl.ShadowlabError, match=r'up "w" is not an axis'):
        sl.Scene.load(str(masked / "cards.obj"), up="w")
    with pytest.raises(sl.ShadowlabError, match=r"--up z .*bunny"):
        sl.Scene.load("bunny", up="z")
