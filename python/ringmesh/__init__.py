"""ringmesh from Python: the pretension design of the cable mesh of ring-truss
reflector antennas.

Every computation is the Rust library's (``ringmesh._ringmesh``); this package
holds the data classes that carry its numpy arrays and results:

* :class:`Scene` — a problem file (``Scene.from_toml(path)``,
  ``Scene.from_dict(tables)``, ``scene.to_toml()``, ``scene.mesh()``);
* :class:`Network` — a cable net as numpy arrays, read and written in the
  interchange JSON (``Network.from_json``, ``network.to_json()``);
* :func:`fdm`, :func:`uniformity`, :func:`design`, :func:`front`,
  :func:`study` — the CLI's commands, returning objects and records instead of
  writing files. Every solve releases the GIL; the long ones take an optional
  ``progress`` callable, called with one dict per step (from the solving
  threads, the GIL held for the call).

Errors are the classes of :mod:`ringmesh.errors`.
"""

from dataclasses import dataclass, field
from os import PathLike
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

import numpy as np

from . import _ringmesh
from .errors import (
    DesignError,
    FdmError,
    InputError,
    NetworkError,
    RingmeshError,
    SceneError,
    SettingError,
    StudyError,
    TrussError,
    UniformityError,
)

__version__ = _ringmesh.__version__

__all__ = [
    "Scene",
    "Network",
    "Equilibrium",
    "UniformityDesign",
    "DesignResult",
    "fdm",
    "uniformity",
    "design",
    "front",
    "study",
    "SOLVERS",
    "RingmeshError",
    "InputError",
    "SceneError",
    "NetworkError",
    "SettingError",
    "FdmError",
    "UniformityError",
    "TrussError",
    "DesignError",
    "StudyError",
]

#: The uniformity solvers, by the names the CLI takes.
SOLVERS = ("lp", "bisection", "gradient", "gradient-smooth", "least-squares")

Progress = Optional[Callable[[Dict[str, Any]], Any]]


class Scene:
    """A scene (problem file), validated by the library; a thin handle on the
    Rust value."""

    def __init__(self, native: "_ringmesh.Scene"):
        self._native = native

    @classmethod
    def from_toml(cls, path: Union[str, PathLike]) -> "Scene":
        """Reads a scene file, as the CLI reads it."""
        return cls(_ringmesh.Scene.from_toml(path))

    @classmethod
    def from_toml_str(cls, text: str, name: str = "scene", folder=None) -> "Scene":
        """A scene from TOML text."""
        return cls(_ringmesh.Scene.from_toml_str(text, name, folder))

    @classmethod
    def from_dict(cls, tables: Dict[str, Any], name: str = "scene", folder=None) -> "Scene":
        """A scene from a dict of the file's tables (the same keys, the same
        validation, the same messages as a file)."""
        if not isinstance(tables, dict):
            raise SceneError(f"a scene is a dict of tables, not {type(tables).__name__}")
        return cls(_ringmesh.Scene.from_dict(tables, name, folder))

    def to_toml(self) -> str:
        """The scene as TOML text."""
        return self._native.to_toml()

    def to_dict(self) -> Dict[str, Any]:
        """The scene's tables, every key resolved."""
        return self._native.to_dict()

    @property
    def name(self) -> str:
        return self._native.name

    def mesh(self) -> "Network":
        """The scene's nets at their design positions with their initial force
        densities (``ringmesh mesh``'s ``network.json``), with the front net's
        triangular ``facets``."""
        return Network._from_native(self._native.mesh())

    def __repr__(self) -> str:
        return f"Scene({self.name!r})"


def _groups_array(groups):
    return None if groups is None else np.asarray(groups, dtype=str)


@dataclass
class Network:
    """A pin-jointed cable net in arrays (the interchange format's fields).

    ``positions``: (n, 3) float64, m; ``edges``: (m, 2) int64 node indices;
    ``fixed``: (k,) int64; ``q``: (m,) float64 force densities, N/m;
    ``loads``: (n, 3) float64 N or None; ``groups``: (m,) str or None;
    ``facets``: (t, 3) int64, the front net's triangles (a scene's mesh only:
    not part of the interchange format).

    The arrays are checked (shape, dtype, NaN, indices) by the library when
    the network is used or validated, raising :class:`NetworkError` naming the
    field.
    """

    positions: np.ndarray
    edges: np.ndarray
    fixed: np.ndarray
    q: np.ndarray
    loads: Optional[np.ndarray] = None
    groups: Optional[np.ndarray] = None
    facets: Optional[np.ndarray] = field(default=None, repr=False)

    @classmethod
    def _from_native(cls, d: Dict[str, Any]) -> "Network":
        return cls(
            positions=d["positions"],
            edges=d["edges"],
            fixed=d["fixed"],
            q=d["q"],
            loads=d["loads"],
            groups=_groups_array(d["groups"]),
            facets=d.get("facets"),
        )

    @classmethod
    def from_json(cls, text_or_path: Union[str, PathLike]) -> "Network":
        """A network from interchange JSON text or a file of it."""
        text = str(text_or_path)
        if not text.lstrip().startswith("{"):
            with open(text_or_path, encoding="utf-8") as f:
                text = f.read()
        return cls._from_native(_ringmesh.network_from_json(text))

    def to_json(self) -> str:
        """The interchange JSON, byte for byte as ``ringmesh mesh`` writes it."""
        return _ringmesh.network_to_json(self)

    def validate(self) -> None:
        """Checks the network as the library does before a solve."""
        _ringmesh.validate_network(self)

    @property
    def n_nodes(self) -> int:
        return len(self.positions)

    @property
    def n_edges(self) -> int:
        return len(self.edges)


@dataclass
class Equilibrium:
    """A forward solve (``ringmesh fdm``): positions (n, 3), cable lengths and
    forces (m,), reactions at the fixed nodes (k, 3) in the order of
    ``fixed``, the largest residual at a free node (N), and the library's own
    wall times (s): the network's validation and the solve."""

    positions: np.ndarray
    lengths: np.ndarray
    forces: np.ndarray
    reactions: np.ndarray
    max_residual: float
    validate_s: float
    solve_s: float


def fdm(network: Network) -> Equilibrium:
    """Forward equilibrium of ``network`` (its positions of free nodes ignored,
    fixed nodes as supports)."""
    return Equilibrium(**_ringmesh.fdm(network))


@dataclass
class UniformityDesign:
    """A uniformity design (``ringmesh uniformity``): force densities ``q`` and
    ``tensions`` (m,), ``ratio`` Tmax/Tmin over the uniformity set, the
    out-of-balance force ``max_residual`` (N), the solver, how it stopped
    (``termination``), its ``iterations``, wall time ``time_s``, its
    ``route`` (lp) and ``warnings``."""

    q: np.ndarray
    tensions: np.ndarray
    ratio: float
    max_residual: float
    solver: str
    termination: str
    iterations: int
    time_s: float
    route: Optional[str]
    warnings: List[str]


def uniformity(
    network: Network,
    solver: Optional[str] = None,
    *,
    groups: Optional[Sequence[str]] = None,
    mean_tension_n: Optional[float] = None,
    max_force_density_n_per_m: float = float("inf"),
    **settings: Any,
) -> UniformityDesign:
    """The tension-uniformity problem on ``network``, its positions the
    prescribed geometry (as ``ringmesh uniformity``).

    ``solver``: one of :data:`SOLVERS` (default ``lp`` for one unloaded set,
    else ``bisection``); ``settings``: the solver's settings by name
    (``epsilon_n=0.5`` for bisection; ``weight``, ``memory``,
    ``finish={"max_steps": 10}`` for gradient; ``lambda_=…`` or
    ``**{"lambda": …}`` for least-squares), validated by the library
    (:class:`SettingError` naming the setting). ``groups``: the uniformity
    set (default ``front`` when the network has groups, else every cable);
    ``mean_tension_n``: its target (default the mean tension of ``q``).
    """
    if "lambda_" in settings:
        settings["lambda"] = settings.pop("lambda_")
    return UniformityDesign(
        **_ringmesh.uniformity(
            network,
            solver,
            None if groups is None else list(groups),
            mean_tension_n,
            max_force_density_n_per_m,
            settings,
        )
    )


class DesignResult:
    """A design run (``ringmesh design``, without files).

    ``report``: the content of ``design.json`` as a dict, its keys also read as
    attributes (``result.ratio``, ``result.verification["rms_mm"]``);
    ``network``: the net at the design's geometry; per cable, as arrays:
    ``q``, ``tensions``, ``lengths``, ``cut_lengths`` (the unstressed length
    to cut, m); per node: ``positions`` (design) and ``assembled_positions``
    (cut to length and assembled on the flexible truss); ``facets``.
    """

    def __init__(self, d: Dict[str, Any]):
        self.report: Dict[str, Any] = d["report"]
        self.network = Network._from_native(d["network"])
        self.network.facets = d["facets"]
        self.q: np.ndarray = d["q"]
        self.tensions: np.ndarray = d["tensions"]
        self.lengths: np.ndarray = d["lengths"]
        self.cut_lengths: np.ndarray = d["cut_lengths"]
        self.positions: np.ndarray = d["positions"]
        self.assembled_positions: np.ndarray = d["assembled_positions"]

    def __getattr__(self, name: str) -> Any:
        report = self.__dict__.get("report")
        if report is not None and name in report:
            return report[name]
        raise AttributeError(name)

    def to_dict(self) -> Dict[str, Any]:
        """The report (``design.json``'s content)."""
        return self.report

    def __repr__(self) -> str:
        r = self.report
        return (
            f"DesignResult(scene={r['scene']!r}, solver={r['solver']!r}, "
            f"termination={r['termination']!r}, ratio={r['ratio']:.6f})"
        )


def design(
    scene: Scene,
    solver: Optional[str] = None,
    truss: Optional[str] = None,
    relaxation: Union[None, str, Sequence[str]] = None,
    *,
    tolerance_m: Optional[float] = None,
    max_iterations: Optional[int] = None,
    progress: Progress = None,
) -> DesignResult:
    """The whole design job of ``scene``: outer loop, verification by
    assembly, the conventional design, the margin and the surface budget.

    ``solver``: one of :data:`SOLVERS` (default the scene's); ``truss``:
    ``rigid``, ``linear`` or ``exact`` (default the scene's); ``relaxation``:
    ``anderson``, ``paper``, ``aitken`` or a list of them (the first makes the
    design, the others are compared); ``progress(record)`` sees each outer
    iteration (its ``relaxation``, ``iteration``, ``ratio``, …).
    """
    return DesignResult(
        _ringmesh.design(
            scene._native, solver, truss, relaxation, tolerance_m, max_iterations, progress
        )
    )


def front(
    scene: Scene,
    solvers: Union[str, Sequence[str]] = ("bisection", "gradient", "least-squares"),
    points: int = 8,
    *,
    rms: str = "design",
    progress: Progress = None,
) -> List[Dict[str, Any]]:
    """The design front (``ringmesh front``): each solver's accuracy knob
    swept over ``points`` values. One record per point, in sweep order:
    ``solver``, ``knob``, ``ratio``, ``rms_mm``, ``time_s``, ``termination``,
    ``error`` (a failed point's message, else None); with ``rms="total"``
    also ``total_rms_mm`` (with the net's facet RMS). ``pandas.DataFrame(records)``
    makes the table of ``front.csv``."""
    records, facets_mm = _ringmesh.front(scene._native, solvers, points, rms, progress)
    if facets_mm is not None:
        for r in records:
            r["total_rms_mm"] = float(np.hypot(facets_mm, r["rms_mm"]))
    return records


def _flatten(record: Dict[str, Any], prefix: str = "") -> Dict[str, Any]:
    flat: Dict[str, Any] = {}
    for k, v in record.items():
        if isinstance(v, dict):
            flat.update(_flatten(v, f"{prefix}{k}."))
        else:
            flat[f"{prefix}{k}"] = v
    return flat


def study(
    scene: Scene,
    *,
    knobs: Union[None, str, Sequence[str]] = None,
    tolerances_m: Optional[Sequence[float]] = None,
    elements_per_rod: Optional[Sequence[int]] = None,
    rings: Optional[Sequence[int]] = None,
    truss_models: Union[None, str, Sequence[str]] = None,
    solvers: Union[None, str, Sequence[str]] = None,
    max_iterations: Optional[int] = None,
    jobs: int = 1,
    progress: Progress = None,
) -> List[Dict[str, Any]]:
    """The accuracy study (``ringmesh study``): what accuracy costs in time,
    one knob at a time against a converged reference. One flat record per
    point (nested settings as ``settings.rings``, ``summary.outer_iterations``)
    in sweep order, ``index`` its place in the sweep."""
    rows = _ringmesh.study(
        scene._native,
        knobs,
        None if tolerances_m is None else list(tolerances_m),
        None if elements_per_rod is None else list(elements_per_rod),
        None if rings is None else list(rings),
        truss_models,
        solvers,
        max_iterations,
        jobs,
        progress,
    )
    return [_flatten(r) for r in rows]
