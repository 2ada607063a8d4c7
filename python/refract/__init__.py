"""refract: real-time refraction techniques against an exact reference ray tracer.

Render any method of the registry (Wyman 2005a/b, Umenhoffer et al. 2007, Kakimoto et al. 2007,
the refraction today's engines ship) and the exact reference on a scene, get frames as numpy
arrays, and measure them with the metrics ``refract compare`` writes::

    import refract

    scene = refract.Scene.load("sphere")
    reference = scene.render("reference", res=(256, 256), aovs=True)
    frame = scene.render("wyman", res=(256, 256), aovs=True)
    print(refract.metrics(frame, reference)["flip_mean"])

Everything here calls the library the ``refract`` CLI calls (``refract-lab``): a frame rendered
here is bit-identical to ``refract render`` of the same scene, method and resolution.
See docs/python.md.
"""

from __future__ import annotations

import json
import numbers
import os
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

from ._refract import Frame, RenderError, Scene, Tracer, __version__
from ._refract import builtin_scenes as _builtin_scenes
from ._refract import compare as _compare
from ._refract import error_maps as _error_maps
from ._refract import methods as _methods
from ._refract import metrics as _metrics
from ._refract import sweep as _sweep

__all__ = [
    "Frame",
    "Method",
    "Param",
    "RenderError",
    "Scene",
    "Tracer",
    "builtin_scenes",
    "compare",
    "error_maps",
    "methods",
    "metrics",
    "sweep",
    "__version__",
]

PathLike = Union[str, "os.PathLike[str]"]


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 60:
        text = text[:60] + "..."
    return f"{text} ({type(value).__name__})"


def _int(name: str, value: Any) -> int:
    """``value`` as an int, or a TypeError naming ``name`` (ranges are checked in Rust)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} = {_describe(value)}: expected an int")
    return int(value)


def _names(name: str, value: Any, what: str, paths: bool = False) -> List[Any]:
    """A str (one name) or a sequence of str as a list, or a TypeError naming ``name``; with
    ``paths``, os.PathLike values count as names too."""
    if isinstance(value, str) or (paths and isinstance(value, os.PathLike)):
        return [value]
    if isinstance(value, (bytes, Mapping)) or not isinstance(value, Iterable):
        raise TypeError(f"{name} = {_describe(value)}: expected {what}: a str or a list of str")
    names = list(value)
    for item in names:
        if not (isinstance(item, str) or (paths and isinstance(item, os.PathLike))):
            raise TypeError(
                f"{name} = {_describe(value)}: expected {what}: a str or a list of str, "
                f"not {_describe(item)}"
            )
    return names


def _path(name: str, value: Any) -> str:
    """``value`` as a path, or a TypeError naming ``name``."""
    try:
        return os.fspath(value)
    except TypeError:
        raise TypeError(f"{name} = {_describe(value)}: expected a path (str or os.PathLike)") from None


def _params(value: Any) -> Optional[Dict[Any, Any]]:
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise TypeError(
            f"params = {_describe(value)}: expected a dict of parameter names to str or int values"
        )
    return dict(value)


@dataclass(frozen=True)
class Param:
    """One parameter of a method: ``kind`` is ``"choice"`` (one of ``choices``) or
    ``"integer"`` (``minimum`` to ``maximum``, inclusive); ``default`` is text, as the CLI's
    ``--param NAME=VALUE`` takes it."""

    name: str
    doc: str
    kind: str
    default: str
    choices: Tuple[str, ...] = ()
    minimum: Optional[int] = None
    maximum: Optional[int] = None


@dataclass(frozen=True)
class Method:
    """One row of the registry (``refract methods``)."""

    id: str
    paper: str
    section: str
    family: str
    summary: str
    params: Tuple[Param, ...]
    aovs: Tuple[str, ...]
    backends: Tuple[str, ...]


def methods() -> List[Method]:
    """The registry: every method with its paper, family, parameters (ranges and defaults),
    AOV layers and backends, in the order ``refract methods`` lists them."""
    rows = []
    for row in _methods():
        params = tuple(
            Param(
                name=p["name"],
                doc=p["doc"],
                kind=p["kind"],
                default=p["default"],
                choices=tuple(p.get("choices", ())),
                minimum=p.get("min"),
                maximum=p.get("max"),
            )
            for p in row["params"]
        )
        rows.append(
            Method(
                id=row["id"],
                paper=row["paper"],
                section=row["section"],
                family=row["family"],
                summary=row["summary"],
                params=params,
                aovs=tuple(row["aovs"]),
                backends=tuple(row["backends"]),
            )
        )
    return rows


def builtin_scenes() -> List[Tuple[str, str]]:
    """The built-in scenes as ``(name, description)`` pairs (``refract scenes``)."""
    return list(_builtin_scenes())


def _frames(frame: Any, reference: Any) -> None:
    for name, value in (("frame", frame), ("reference", reference)):
        if not isinstance(value, Frame):
            raise TypeError(f"{name} = {_describe(value)}: expected a refract.Frame")


def metrics(frame: Frame, reference: Frame) -> Dict[str, Any]:
    """The metrics of ``frame`` against ``reference``: a dict with every field of
    ``metrics.json`` (docs/metrics.md), computed as ``refract compare`` computes them. Both
    frames must come from one :class:`Scene` and camera, rendered with ``aovs=True``;
    ``reference`` is a ``"reference"`` frame. Fields that do not apply are ``None``."""
    _frames(frame, reference)
    return _metrics(frame, reference)


def error_maps(frame: Frame, reference: Frame) -> Dict[str, Any]:
    """The per-pixel error maps behind :func:`metrics`: ``flip`` (FLIP, 0 to 1), ``t2_deg``
    (angle between the T2 directions, degrees) and ``p2_rel`` (exit-point distance over the
    refractor's diameter), each ``float32`` of shape ``(height, width)``, NaN where undefined."""
    _frames(frame, reference)
    return _error_maps(frame, reference)


def compare(
    scenes: Union[PathLike, Sequence[PathLike]],
    methods: Optional[Sequence[str]] = None,
    backends: Sequence[str] = ("cpu",),
    res: int = 256,
    spp: int = 1,
    frames: int = 3,
    params: Optional[Mapping[str, Union[str, int]]] = None,
    out: PathLike = "out",
    reference_backend: str = "cpu",
    engines: Sequence[str] = (),
) -> List[Dict[str, Any]]:
    """Every method (default: all but the reference) against the exact reference on each
    scene, as ``refract compare`` runs it: images, ``metrics.json``, ``report.md`` and
    ``index.html`` go into ``out``. Returns one record per (scene, method, backend), the
    reference's own row first per scene: the fields of ``metrics.json``, ready for
    ``pandas.DataFrame(records)``. ``params`` apply to every method that has them.
    ``reference_backend`` traces the reference on ``"cpu"`` (the CPU tracer) or ``"gpu"``
    (the WGSL tracer, ``docs/reference.md``). ``engines`` (``"threejs"``) also render each
    scene with the engines themselves, a row ``threejs@VERSION`` on backend ``webgl``
    (``docs/engines.md``); one that cannot run raises. Ctrl-C stops the run between frames."""
    if not isinstance(reference_backend, str):
        raise TypeError(
            f"reference_backend = {_describe(reference_backend)}: expected \"cpu\" or \"gpu\""
        )
    text = _compare(
        _names("scenes", scenes, "built-in scene names or scene files", paths=True),
        None if methods is None else _names("methods", methods, "method ids"),
        _names("backends", backends, "backends (\"cpu\", \"gpu\")"),
        _int("res", res),
        _int("spp", spp),
        _int("frames", frames),
        _params(params),
        _path("out", out),
        reference_backend,
        _names("engines", engines, "engine ids"),
    )
    return json.loads(text)


def _flatten(result: Dict[str, Any]) -> Dict[str, Any]:
    """A sweep job's result as one flat record: the job's fields, ``param.NAME`` for each
    swept parameter, ``status``, ``error``, then every metric."""
    job = result["job"]
    record: Dict[str, Any] = {
        "id": job["id"],
        "scene": job["scene"],
        "ior": job["ior"],
        "res": job["res"],
        "backend": job["backend"],
        "method": job["method"],
    }
    for name, value in job["params"].items():
        record[f"param.{name}"] = value
    record["status"] = result["status"]
    record["error"] = result["error"]
    for name, value in (result["metrics"] or {}).items():
        if name not in ("scene", "method", "backend"):
            record[name] = value
    return record


def sweep(
    path: PathLike,
    shard: Optional[Tuple[int, int]] = None,
    out: PathLike = "sweep-out",
    cache: Optional[PathLike] = None,
) -> List[Dict[str, Any]]:
    """Runs the jobs of a sweep file (docs/sweeps.md), or of shard ``(i, n)`` (every n-th job
    from job i), as ``refract sweep`` does: results go into ``out/jobs``, finished jobs are not
    run again, references are shared through ``cache`` when given. Returns one flat record per
    job of the shard (its axes, ``param.NAME`` columns, ``status``, ``error`` and the metrics),
    ready for ``pandas.DataFrame(records)``. Ctrl-C stops the run between jobs."""
    if shard is not None:
        if isinstance(shard, (str, bytes)) or not isinstance(shard, Sequence) or len(shard) != 2:
            raise TypeError(f"shard = {_describe(shard)}: expected (i, n), two ints, or None")
        shard = (_int("shard[0]", shard[0]), _int("shard[1]", shard[1]))
    text = _sweep(
        _path("path", path),
        shard,
        _path("out", out),
        None if cache is None else _path("cache", cache),
    )
    return [_flatten(result) for result in json.loads(text)]
