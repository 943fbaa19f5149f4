# Type stubs for the sluice module (the `_core` extension re-exported).
from os import PathLike
from typing import Any, Callable, Iterable, Iterator, Optional, Sequence as _Seq, Tuple, Union, overload

import numpy as np
import numpy.typing as npt

LAYERS: Tuple[str, str, str, str]

class Error(RuntimeError): ...

class Frame:
    index: int
    time: Optional[float]
    bytes_read: int
    positions: npt.NDArray[np.float32]  # (N, 3)
    lod: npt.NDArray[np.uint16]
    layer: npt.NDArray[np.uint8]
    attributes: dict[str, npt.NDArray[np.float32]]
    def __len__(self) -> int: ...
    def __getitem__(self, name: str) -> npt.NDArray[np.float32]: ...

class FrameStream(Iterator[Frame]):
    window: int
    def __iter__(self) -> "FrameStream": ...
    def __next__(self) -> Frame: ...
    def __len__(self) -> int: ...

class Sequence:
    path: str
    times: Optional[npt.NDArray[np.float64]]
    counts: npt.NDArray[np.uint64]
    bounds: Tuple[Tuple[float, float, float], Tuple[float, float, float]]
    up: str
    spacing: float
    radius: float
    frame_rate: float
    attributes: list[str]
    layers: list[str]
    def __len__(self) -> int: ...
    @overload
    def __getitem__(self, i: int) -> Frame: ...
    @overload
    def __getitem__(self, i: slice) -> list[Frame]: ...
    def __iter__(self) -> FrameStream: ...
    def frame(self, i: int, *, layers: str = "all", lod_level: Optional[float] = None,
              attributes: Optional[_Seq[str]] = None) -> Frame: ...
    def frames(self, start: int = 0, stop: Optional[int] = None, step: int = 1, *, layers: str = "all",
               lod_level: Optional[float] = None, attributes: Optional[_Seq[str]] = None,
               memory: int = 0, window: int = 0, loop: bool = False) -> FrameStream: ...
    def info(self) -> dict[str, Any]: ...

def open(path: Union[str, PathLike[str]], *, cache: bool = True, cache_dir: Optional[Union[str, PathLike[str]]] = None,
         progress: Optional[Callable[[dict[str, int]], None]] = None) -> Sequence: ...

def convert(input: Union[str, PathLike[str]], output: Union[str, PathLike[str]], *,
            progress: Optional[Callable[[dict[str, int]], None]] = None,
            attributes: Optional[_Seq[str]] = None, all_attributes: bool = False,
            spacing: float = 0.0, radius: float = 0.0, fps: float = 0.0, dt: float = 0.0,
            up: Optional[str] = None, ids: Optional[str] = None, no_ids: bool = False,
            lossless: bool = False, layers: bool = True, skip_bad: bool = False,
            jobs: int = 0, isolate: bool = True, precision: float = 0.0, drop_outliers: float = 0.0,
            chunk: int = 65536, level: int = 3, planes: str = "packed", tiers: bool = True,
            band_voxel: float = 0.0, band_f2: str = "all", read_timeout: float = 120.0,
            force: bool = False) -> dict[str, Any]: ...

class Renderer:
    camera: str
    device: str
    color: Optional[str]
    def __init__(self, path: Union[str, PathLike[str]], *, size: Tuple[int, int] = (960, 540),
                 layers: str = "surface", color: Optional[str] = None, particles: str = "auto") -> None: ...
    def render(self, i: int, *, camera: Optional[str] = None, lod_level: Optional[float] = None,
               display: str = "transparent", ground: bool = True) -> npt.NDArray[np.uint8]: ...

def render(seq: Union[Sequence, str, PathLike[str]], frame: int, size: Tuple[int, int] = (960, 540), *,
           camera: Optional[str] = None, layers: str = "surface", color: Optional[str] = None,
           particles: str = "auto", **look: Any) -> npt.NDArray[np.uint8]: ...

def export(seq: Union[Sequence, str, PathLike[str]], output: Union[str, PathLike[str]], *,
           frames: Optional[Iterable[int]] = None, lod_level: Optional[float] = None,
           attributes: Optional[_Seq[str]] = None, force: bool = False,
           progress: Optional[Callable[[dict[str, int]], None]] = None) -> dict[str, Any]: ...

class LiveView:
    open: bool
    pushed: int
    shown: int
    dropped: int
    def __init__(self, bounds: Tuple[Tuple[float, float, float], Tuple[float, float, float]], *, window: bool = True,
                 size: Tuple[int, int] = (960, 540), spacing: float = 0.0, radius: float = 0.0, up: str = "+z",
                 attributes: _Seq[str] = (), color: Optional[str] = None, ids: bool = False,
                 record: Optional[Union[str, PathLike[str]]] = None, fps: float = 30.0, keep_all: bool = False,
                 title: str = "sluice live", force: bool = False) -> None: ...
    def push(self, positions: npt.ArrayLike, ids: Optional[npt.ArrayLike] = None, time: Optional[float] = None,
             **attributes: npt.ArrayLike) -> bool: ...
    def close(self) -> None: ...
    def image(self) -> Optional[npt.NDArray[np.uint8]]: ...
    def __enter__(self) -> "LiveView": ...
    def __exit__(self, *exc: Any) -> None: ...
