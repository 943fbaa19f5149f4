"""sluice: huge particle-fluid sequences (SPH, MPM, FLIP output) from disk.

    import sluice
    seq = sluice.open("run.sluice")      # header and index only
    f = seq[0]                           # numpy arrays: f.positions (N, 3), f.lod, f["rho"]
    for f in seq.frames(step=10, lod_level=0.1):
        ...                              # streamed, read ahead on threads
    img = sluice.render(seq, 10, size=(960, 540), color="rho")   # RGBA (540, 960, 4)
    sluice.convert("out/*.vtk", "run.sluice", progress=print)
    sluice.export(seq, "out/run.vtp", frames=range(0, 100, 10), lod_level=0.5)   # + out/run.pvd

See help(sluice.open), help(sluice.Sequence.frame), help(sluice.render),
help(sluice.convert) and docs/python.md.
"""

from ._core import LAYERS, Error, Frame, FrameStream, Sequence, convert, export, open  # noqa: F401

try:
    from ._core import LiveView, Renderer
except ImportError:  # built without the Vulkan renderer
    LiveView = Renderer = None

__all__ = ["open", "convert", "export", "render", "Sequence", "Frame", "FrameStream", "Renderer", "LiveView", "Error", "LAYERS"]

_last_renderer = None  # (key, Renderer): consecutive renders of one file reuse it


def render(seq, frame, size=(960, 540), *, camera=None, layers="surface", color=None, particles="auto", **look):
    """Draws frame `frame` of `seq` (a Sequence, or anything sluice.open() takes) as liquid.

    Returns a uint8 RGBA array (height, width, 4). `camera` is None (frame
    the data) or a string in `sluice render --camera` form; `color` names an
    attribute to colour by; `particles` is 'auto', 'spheres' or 'ellipsoids'
    (anisotropic); `look` takes Renderer.render's keywords: lod_level,
    display, ground. Consecutive calls for one file, size, layers, colour
    and particles reuse one sluice.Renderer; make Renderers yourself to keep
    several.
    """
    global _last_renderer
    if Renderer is None:
        raise Error("this sluice module was built without the Vulkan renderer")
    if not isinstance(seq, Sequence):
        seq = open(seq)  # anything open() takes: a .sluice file, or solver output converted once into its cache
    path = seq.path
    key = (path, tuple(size), layers, color, particles)
    if _last_renderer is None or _last_renderer[0] != key:
        _last_renderer = None  # release the old one before making the next
        _last_renderer = (key, Renderer(path, size=tuple(size), layers=layers, color=color, particles=particles))
    return _last_renderer[1].render(frame, camera=camera, **look)
