"""sluice: huge particle-fluid sequences (SPH, MPM, FLIP output) from disk.

    import sluice
    seq = sluice.open("run.sluice")      # header and index only
    f = seq[0]                           # numpy arrays: f.positions (N, 3), f.lod, f["rho"]
    for f in seq.frames(step=10, lod_level=0.1):
        ...                              # streamed, read ahead on threads
    sluice.convert("out/*.vtk", "run.sluice", progress=print)

See help(sluice.open), help(sluice.Sequence.frame), help(sluice.convert)
and docs/python.md.
"""

from ._core import LAYERS, Error, Frame, FrameStream, Sequence, convert, open  # noqa: F401

__all__ = ["open", "convert", "Sequence", "Frame", "FrameStream", "Error", "LAYERS"]
