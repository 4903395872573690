"""Shadow rendering algorithms on NumPy arrays, measured against a ray-traced reference.

A scene comes from a file or a built-in name (``Scene.load``) or from arrays
(``Scene.from_arrays``: vertices ``(n, 3)`` float32, faces ``(m, 3)`` integers). Each
frame's shadow term is RGB transmittance towards the light, 1 = lit:

- ``Scene.render(technique, camera, light, params)`` -> ``(H, W, 3)`` float32;
- ``Scene.visibility(points, normals, light)`` -> ``(n, 3)`` float32;
- ``Scene.render_lights(technique, lights)`` -> one ``(H, W, 3)`` array per light;
- ``Scene.compare(techniques)`` -> a dict shaped like the command line's ``metrics.json``
  (with ``sweeps`` and ``frames`` as ``--sweep`` and ``--frames``).

``shadowlab.study`` (the ``study`` extra) runs studies over many scenes, lights, cameras and
parameter values on a Dask cluster.

A light is punctual (``Light.directional``, ``point``, ``spot``) or has an area
(``Light.rect``, ``disk``, ``sphere``, or ``light.sized(size)``): under an area light
``raytrace`` is the soft-shadow reference and ``pcss``, ``afsm-soft`` and the filtered soft
variants see the light's size; ``compare`` states the reference's own standard error.

Frames are set up as ``shadowlab render`` sets them up, so the same scene and parameters
give the command line's values bit for bit. Rendering releases the GIL. Bad input raises
``ShadowlabError`` (a ``ValueError``) with the command line's one-sentence message.
"""

from ._shadowlab import (
    Camera,
    Light,
    Scene,
    ShadowlabError,
    __version__,
    read_exr,
    techniques,
)

__all__ = [
    "Camera",
    "Light",
    "Scene",
    "ShadowlabError",
    "__version__",
    "read_exr",
    "techniques",
]
