"""Type stubs of the extension module (python/src/)."""

import os
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class RenderError(RuntimeError):
    """A scene could not be prepared or a frame rendered (no GPU adapter, an unsupported
    method, a file that could not be written, ...). The message is the one the CLI prints."""

class Frame:
    """A frame: linear RGB colour and the AOV layers its method wrote."""

    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def color(self) -> npt.NDArray[np.float32]:
        """Linear RGB, shape ``(height, width, 3)``, rows from the top."""
    def srgb8(self) -> npt.NDArray[np.uint8]:
        """The colour as the CLI's PNGs show it (ACES filmic, sRGB), ``(h, w, 3)``."""
    @property
    def aovs(self) -> List[str]:
        """The AOV layers this frame has, named as in the EXR (``T2``, ``covered``, ...)."""
    def aov(self, name: str) -> npt.NDArray[Any]:
        """One layer: vectors ``float32 (h, w, 3)`` (NaN where absent), counts
        ``uint32 (h, w)``, flags ``bool (h, w)``. ``ValueError`` for a layer it lacks."""
    @property
    def timing(self) -> Optional[Dict[str, Any]]:
        """``{"ms": float, "source": "wall" | "gpu-timestamps"}``; ``None`` if loaded."""
    @property
    def method(self) -> Optional[str]: ...
    @property
    def backend(self) -> Optional[str]:
        """``cpu``, ``gpu`` or ``trace`` (the reference)."""
    @property
    def params(self) -> List[Tuple[str, str]]: ...
    @property
    def scene(self) -> Optional[str]: ...
    def save(self, path: Union[str, os.PathLike[str]]) -> None:
        """``.exr`` (colour and every AOV layer, 32-bit float) or ``.png`` (tonemapped)."""
    @staticmethod
    def load(path: Union[str, os.PathLike[str]]) -> "Frame":
        """A frame from an ``.exr`` written by ``refract render``, ``compare`` or ``save``."""

class Scene:
    """A built-in scene or a ``.toml`` scene file, with its own camera."""

    @staticmethod
    def load(name_or_path: Union[str, os.PathLike[str]], ior: Optional[float] = None) -> "Scene": ...
    @staticmethod
    def builtin_names() -> List[str]: ...
    @property
    def name(self) -> str: ...
    @property
    def ior(self) -> float: ...
    @property
    def roughness(self) -> List[float]:
        """Each refractor's roughness (0 smooth to 1), in the scene's refractor order."""
    @property
    def abbe(self) -> List[float]:
        """Each refractor's Abbe number (inf: no dispersion), in the scene's refractor order."""
    @property
    def warnings(self) -> List[str]: ...
    @property
    def eye(self) -> Tuple[float, float, float]: ...
    @eye.setter
    def eye(self, value: Tuple[float, float, float]) -> None: ...
    @property
    def target(self) -> Tuple[float, float, float]: ...
    @target.setter
    def target(self, value: Tuple[float, float, float]) -> None: ...
    @property
    def up(self) -> Tuple[float, float, float]: ...
    @up.setter
    def up(self, value: Tuple[float, float, float]) -> None: ...
    @property
    def fov(self) -> float:
        """Vertical field of view, degrees in (0, 180)."""
    @fov.setter
    def fov(self, value: float) -> None: ...
    def render(
        self,
        method: str,
        backend: str = "cpu",
        res: Tuple[int, int] = (512, 512),
        params: Optional[Mapping[str, Union[str, int]]] = None,
        aovs: bool = False,
    ) -> Frame:
        """One frame of ``method`` (or ``"reference"``); the GIL is released meanwhile."""

class Tracer:
    """The exact reference's closest-hit query on one mesh (its BVH), for measuring the tracer
    against another on the same triangles and rays (python/benchmarks/embree.py)."""

    @staticmethod
    def load(path: Union[str, "os.PathLike[str]"]) -> "Tracer": ...
    @property
    def vertices(self) -> npt.NDArray[np.float32]: ...
    @property
    def triangles(self) -> npt.NDArray[np.uint32]: ...
    def closest_hits(
        self,
        origins: npt.NDArray[np.float32],
        directions: npt.NDArray[np.float32],
        t_min: float = 0.0,
    ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.int64]]: ...

def methods() -> List[Dict[str, Any]]: ...
def builtin_scenes() -> List[Tuple[str, str]]: ...
def metrics(frame: Frame, reference: Frame) -> Dict[str, Any]: ...
def error_maps(frame: Frame, reference: Frame) -> Dict[str, npt.NDArray[np.float32]]: ...
def compare(
    scenes: List[Union[str, os.PathLike[str]]],
    methods: Optional[List[str]],
    backends: List[str],
    res: int,
    spp: int,
    frames: int,
    params: Optional[Dict[str, Union[str, int]]],
    out: str,
    reference_backend: str,
    engines: List[str],
) -> str: ...
def sweep(
    path: str,
    shard: Optional[Tuple[int, int]],
    out: str,
    cache: Optional[str],
) -> str: ...
