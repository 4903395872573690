"""Hostile input from Python, one test per class: integer arguments checked by name,
special and foreign files refused by read_exr, the command line's caps and up-front memory
estimate applied, and a malformed glTF image named, all as ShadowlabError."""

import os
import threading
from pathlib import Path

import numpy as np
import pytest

import shadowlab as sl

EYE, TARGET = (0.0, 5.0, 7.0), (0.0, 0.0, 0.0)


def box_scene():
    ground = np.array([[-4, 0, -4], [-4, 0, 4], [4, 0, 4], [4, 0, -4]], np.float32)
    return sl.Scene.from_arrays(ground, np.array([[0, 1, 2], [0, 2, 3]], np.uint32))


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: sl.Camera(EYE, TARGET, 45.0, -1, 10), "width"),
        (lambda: sl.Camera(EYE, TARGET, 45.0, 2**32, 10), "width"),
        (lambda: sl.Camera(EYE, TARGET, 45.0, 10, 2**200), "height"),
        (lambda: sl.Camera(EYE, TARGET, 45.0, 0.5, 10), "width"),
        (lambda: sl.Camera.orthographic(EYE, TARGET, 2.0, width=-5), "width"),
        (lambda: sl.Light.sphere((0, 3, 0), 0.5, samples=-1), "samples"),
        (lambda: sl.Light.rect((0, 3, 0), (1, 0, 0), (0, 0, 1), samples=2**40), "samples"),
        (lambda: box_scene().compare(["sm"], camera=sl.Camera(EYE, TARGET, 45.0, 8, 8),
                                     reference_spp=-1), "reference_spp"),
        (lambda: box_scene().set_mesh_vertices(-1, np.zeros((4, 3), np.float32)), "mesh"),
        (lambda: box_scene().visibility(np.zeros((1, 3), np.float32),
                                        np.array([[0, 1, 0]], np.float32), SUN,
                                        triangles=[-1]), "triangles[0]"),
    ],
)
def test_integer_arguments_checked_by_name(make, name):
    with pytest.raises(sl.ShadowlabError, match=rf"^{name.replace('[', '.').replace(']', '.')}"):
        make()


SUN = sl.Light.directional((0.0, 1.0, 0.0))


def test_fractional_face_indices_refused():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32)
    with pytest.raises(sl.ShadowlabError, match=r"faces row 0 names vertex 0\.5, which is not an integer"):
        sl.Scene.from_arrays(v, np.array([[0.5, 1, 2]]))
    # Whole numbers in a float array are indices like any other.
    assert sl.Scene.from_arrays(v, np.array([[0.0, 1.0, 2.0]])).triangles >= 1


def test_read_exr_refuses_fifos_and_other_formats(tmp_path):
    fifo = tmp_path / "vis.exr"
    os.mkfifo(fifo)
    done = []

    def read():
        try:
            sl.read_exr(fifo)
        except sl.ShadowlabError as e:
            done.append(str(e))

    t = threading.Thread(target=read, daemon=True)
    t.start()
    t.join(20)
    assert done and "FIFO" in done[0], "read_exr on a FIFO must be refused, not block"
    png = tmp_path / "bomb.exr"
    # A PNG under an .exr name: refused by its first bytes, never decoded.
    png.write_bytes(b"\x89PNG\r\n\x1a\n" + b"\0" * 64)
    with pytest.raises(sl.ShadowlabError, match="not an OpenEXR image"):
        sl.read_exr(png)
    with pytest.raises(sl.ShadowlabError, match="character device"):
        sl.read_exr("/dev/zero")


def test_compare_runs_capped_like_the_cli():
    with pytest.raises(sl.ShadowlabError, match=r"10000 runs, more than the limit of 128"):
        box_scene().compare(["sm"] * 10000, camera=sl.Camera(EYE, TARGET, 45.0, 8, 8))


def test_render_memory_estimated_up_front():
    import resource

    # A child process under a 2 GB address-space limit: an 8192² frame needs more, and
    # must be refused by the estimate before anything is allocated.
    code = (
        "import resource, numpy as np, shadowlab as sl\n"
        "resource.setrlimit(resource.RLIMIT_AS, (2_000_000_000, 2_000_000_000))\n"
        "g = np.array([[-4,0,-4],[-4,0,4],[4,0,4],[4,0,-4]], np.float32)\n"
        "s = sl.Scene.from_arrays(g, np.array([[0,1,2],[0,2,3]], np.uint32))\n"
        "c = sl.Camera((0,5,7), (0,0,0), 45.0, 8192, 8192)\n"
        "try:\n"
        "    s.render('sm', camera=c, light=sl.Light.directional((0,1,0)))\n"
        "except sl.ShadowlabError as e:\n"
        "    print('refused:', e)\n"
    )
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert "refused: a 8192x8192 image (the camera)" in out.stdout, out.stdout + out.stderr
    assert resource is not None


def test_gltf_image_without_source_is_shadowlab_error(tmp_path):
    doc = (
        '{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],'
        '"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],'
        '"accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3",'
        '"min":[0,0,0],"max":[1,1,0]}],"bufferViews":[{"buffer":0,"byteLength":36}],'
        '"buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,'
        'AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],"images":[{}]}'
    )
    f = tmp_path / "nosource.gltf"
    f.write_text(doc)
    with pytest.raises(sl.ShadowlabError, match=r"images\[0\]"):
        sl.Scene.load(str(f))
