"""Sweep descriptions: a base gear set, run settings, the varied keys, and the cases they give.

A sweep is a TOML file (or the same dict through :func:`sweep_from_dict`, or :class:`Sweep`
built in Python)::

    title = "Sun-mesh damping x planet phasing"
    base = "paper-case1"            # a preset or a gear-set TOML file (relative to this file)
    mode = "grid"                   # grid (default) | zip | random
    # max_cases = 10000             # bound on the number of cases (at most 1 000 000)

    [simulation]                    # overrides the base's [simulation] table (run settings)
    duration = 0.5

    [[parameter]]
    path = "meshes.sun.damping_ratio"
    values = [0.005, 0.01, 0.02]

    [[parameter]]
    path = "geometry.planet_angles_deg"
    values = [[0, 120, 240], [0, 122.45, 244.90]]
    labels = ["equal spacing", "paper case 2"]

    [summary]                       # see gearvib.sweep.summary.SummarySettings
    orders = [1, 2, 3]

``grid`` runs every combination (the last parameter varies fastest), ``zip`` the i-th value of
every parameter together (equal lengths), ``random`` draws ``samples`` cases with a ``seed``
from each parameter's ``distribution`` (``uniform`` with ``low``/``high``; ``normal`` with
``mean``/``std`` and optional truncation ``low``/``high``; bounds may be lists for list-valued
keys) or uniformly from its ``values``. Every key is checked; errors name the key.
"""

from __future__ import annotations

import copy
import itertools
import math
import pickle
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy import special

from gearvib import __version__
from gearvib.checks import check_items
from gearvib.checks import short as _short
from gearvib.config import (
    ConfigError,
    check_keys,
    config_hash,
    gearset_from_dict,
    load_config,
    read_toml,
)
from gearvib.memory import format_bytes, require_memory
from gearvib.simulation.settings import SIMULATION_KEYS, read_run_settings
from gearvib.sweep.keys import get_path, parse_path, path_units, set_path, value_kind, value_label
from gearvib.sweep.summary import SummarySettings

__all__ = [
    "DEFAULT_MAX_CASES",
    "HARD_MAX_CASES",
    "Parameter",
    "Sweep",
    "SweepCase",
    "load_sweep",
    "resolve_run_settings",
    "sweep_from_dict",
]

DEFAULT_MAX_CASES = 10_000
"""Default bound on the number of cases of a sweep."""

HARD_MAX_CASES = 1_000_000
"""Largest admissible ``max_cases``."""

_TOP = {"title", "description", "base", "mode", "samples", "seed", "max_cases", "simulation",
        "parameter", "summary"}
_PARAM = {"path", "values", "labels", "distribution", "low", "high", "mean", "std", "units",
          "long_name"}
_MODES = ("grid", "zip", "random")
_RESERVED = {"case", "mesh", "order", "floquet_speed", "flank", "bearing", "member",
             "translation_dof", "run_file", "case_sha256", "status", "failure"}
_DISTRIBUTIONS = {"uniform": ({"low", "high"}, set()), "normal": ({"mean", "std"},
                                                                 {"low", "high"})}


def _num(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{where} must be a finite number, got {_short(value)}")
    return float(value)


def _bound(value: Any, where: str) -> np.ndarray:
    """A number or a list of numbers as a float array."""
    if isinstance(value, list):
        if not value:
            raise ConfigError(f"{where} must not be an empty list")
        return np.array([_num(v, f"{where}[{i}]") for i, v in enumerate(value)])
    return np.array(_num(value, where))


@dataclass(frozen=True)
class Parameter:
    """One varied key of a sweep.

    Attributes
    ----------
    path : str
        Key path into the base description (:mod:`gearvib.sweep.keys`), e.g.
        ``"meshes.sun.damping_ratio"``; ``"simulation.<key>"`` varies a run setting.
    values : tuple or None
        The values (grid and zip modes; in random mode the values drawn from).
    labels : tuple of str or None
        Display labels of ``values`` (used for the coordinate of list or table values).
    distribution : str or None
        ``"uniform"`` or ``"normal"`` (random mode, instead of ``values``).
    low, high, mean, std : float, list of float or None
        Parameters of the distribution (lists for list-valued keys, element by element).
    units, long_name : str or None
        Metadata of the coordinate (default: from the key, see
        :data:`gearvib.sweep.keys.KEY_UNITS`).
    """

    path: str
    values: tuple | None = None
    labels: tuple[str, ...] | None = None
    distribution: str | None = None
    low: Any = None
    high: Any = None
    mean: Any = None
    std: Any = None
    units: str | None = None
    long_name: str | None = None

    def __post_init__(self) -> None:
        where = f"parameter {_short(self.path)}"
        parse_path(self.path, "parameter path")
        if self.values is not None:
            vals = tuple(self.values) if isinstance(self.values, list | tuple) else None
            if vals is None:
                raise ConfigError(f"{where}: values must be a list, got {_short(self.values)}")
            if not vals:
                raise ConfigError(f"{where}: values is empty; give at least one value")
            for i, v in enumerate(vals):
                if value_kind(v) == "other":
                    raise ConfigError(f"{where}: values[{i}] = {_short(v)} is not a TOML value")
                if isinstance(v, float) and not math.isfinite(v):
                    raise ConfigError(f"{where}: values[{i}] = {_short(v)}; admissible: finite")
            object.__setattr__(self, "values", vals)
        if self.labels is not None:
            labels = tuple(self.labels) if isinstance(self.labels, list | tuple) else ()
            if self.values is None or len(labels) != len(self.values) or \
                    not all(isinstance(x, str) and x for x in labels):
                raise ConfigError(f"{where}: labels must be a list of non-empty strings, one per "
                                  "value")
            if len(set(labels)) != len(labels):
                raise ConfigError(f"{where}: labels must be distinct")
            object.__setattr__(self, "labels", labels)
        if self.distribution is not None:
            if self.values is not None:
                raise ConfigError(f"{where}: give values or a distribution, not both")
            if not isinstance(self.distribution, str) or self.distribution not in _DISTRIBUTIONS:
                raise ConfigError(f"{where}: distribution = "
                                  f"{_short(self.distribution)}; admissible: "
                                  f"{', '.join(_DISTRIBUTIONS)}")
            req, opt = _DISTRIBUTIONS[self.distribution]
            given = {k for k in ("low", "high", "mean", "std") if getattr(self, k) is not None}
            if req - given:
                raise ConfigError(f"{where}: distribution {_short(self.distribution)} needs "
                                  f"{_short(sorted(req - given)[0])}")
            if given - req - opt:
                raise ConfigError(f"{where}: {_short(sorted(given - req - opt)[0])} is not a "
                                  f"parameter of distribution {_short(self.distribution)} "
                                  f"(admissible: {', '.join(sorted(req | opt))})")
            arrs = {k: _bound(getattr(self, k), f"{where}.{k}") for k in given}
            shapes = {a.shape for a in arrs.values()} - {()}
            if len(shapes) > 1:
                raise ConfigError(f"{where}: the distribution's lists have different lengths")
            if "std" in arrs and np.any(arrs["std"] < 0):
                raise ConfigError(f"{where}.std must be >= 0")
            if "low" in arrs and "high" in arrs and np.any(arrs["high"] <= arrs["low"]):
                raise ConfigError(f"{where}: high must be > low")
        elif self.values is None:
            raise ConfigError(f"{where}: give values = [...] (or a distribution in random "
                              "mode)")
        else:
            for k in ("low", "high", "mean", "std"):
                if getattr(self, k) is not None:
                    raise ConfigError(f"{where}: {k} applies to a distribution (give values "
                                      "or a distribution)")
        for k in ("units", "long_name"):
            v = getattr(self, k)
            if v is not None and not isinstance(v, str):
                raise ConfigError(f"{where}.{k} must be a string")

    @property
    def listed(self) -> tuple:
        """``values``, which a parameter of a grid or zip sweep always has."""
        if self.values is None:
            raise ConfigError(f"parameter {_short(self.path)}: give values = [...] (a distribution "
                              "needs mode = 'random')")
        return self.values

    @classmethod
    def from_dict(cls, table: Any, where: str) -> Parameter:
        """Checked parameter from a ``[[parameter]]`` table."""
        check_keys(table, _PARAM, where)
        if "path" not in table:
            raise ConfigError(f"missing key 'path' in {where}")
        try:
            return cls(**table)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    @property
    def is_simulation(self) -> bool:
        """Whether the parameter varies a run setting (``simulation.<key>``)."""
        return parse_path(self.path)[0] == "simulation"

    def to_dict(self) -> dict[str, Any]:
        """The table that :meth:`from_dict` reads back."""
        out: dict[str, Any] = {"path": self.path}
        for k in ("values", "labels"):
            if getattr(self, k) is not None:
                out[k] = list(getattr(self, k))
        for k in ("distribution", "low", "high", "mean", "std", "units", "long_name"):
            if getattr(self, k) is not None:
                out[k] = getattr(self, k)
        return out

    def sample(self, rng: np.random.Generator, n: int) -> list[Any]:
        """``n`` values drawn with ``rng`` (random mode)."""
        if self.values is not None:
            return [copy.deepcopy(self.values[i]) for i in rng.integers(0, len(self.values), n)]
        b = {k: np.asarray(getattr(self, k), dtype=float) for k in ("low", "high", "mean", "std")
             if getattr(self, k) is not None}
        shape = np.broadcast_shapes(*(a.shape for a in b.values()))
        if self.distribution == "uniform":
            x = rng.uniform(b["low"], b["high"], size=(n, *shape))
        else:
            mean = np.broadcast_to(b["mean"], shape)
            std = np.broadcast_to(b["std"], shape)
            lo = np.broadcast_to(b.get("low", np.array(-np.inf)), shape)
            hi = np.broadcast_to(b.get("high", np.array(np.inf)), shape)
            with np.errstate(divide="ignore", invalid="ignore"):
                a = special.ndtr(np.where(std > 0, (lo - mean) / std, -np.inf))
                c = special.ndtr(np.where(std > 0, (hi - mean) / std, np.inf))
            u = rng.uniform(0.0, 1.0, size=(n, *shape))
            z = special.ndtri(a + u * (c - a))  # inverse CDF of the truncated normal
            x = np.where(std > 0, mean + std * z, mean)
        return [row.tolist() if shape else float(row) for row in x]


@dataclass(frozen=True)
class SweepCase:
    """One case of a sweep: the gear-set description and run settings to simulate.

    Attributes
    ----------
    index : int
        Position in the sweep (0-based), the ``case`` coordinate.
    values : tuple
        The value of every parameter, in the sweep's order.
    labels : tuple of str
        Their display labels.
    description : dict
        The base description with the values set (``[simulation]`` merged).
    run : dict
        Resolved run settings (:func:`resolve_run_settings`).
    base_dir : str or None
        Directory of the base description (relative CSV paths).
    sha256 : str
        Hash of description, run settings, base directory and gearvib version: a run file
        carrying it in its ``sweep_case_sha256`` attribute is this case's finished run.
    """

    index: int
    values: tuple
    labels: tuple[str, ...]
    description: dict
    run: dict
    base_dir: str | None
    sha256: str


def resolve_run_settings(simulation: dict) -> dict[str, Any]:
    """Complete, checked run settings from a ``[simulation]`` table.

    The settings of :func:`gearvib.simulation.settings.read_run_settings` (the same defaults
    and checks as ``gearvib simulate``: speed, torque or motor drive).

    Raises
    ------
    ConfigError
        A value of the wrong type or out of range (the message names ``[simulation].<key>``).
    """
    try:
        return read_run_settings(simulation)
    except ValueError as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(str(exc)) from None


def _coordinate_kind(values: list[Any]) -> str:
    kinds = {value_kind(v) for v in values}
    if kinds == {"number"}:
        return "number"
    if kinds == {"string"}:
        return "string"
    if kinds == {"bool"}:
        return "bool"
    return "label"


@dataclass(frozen=True)
class Sweep:
    """A sweep description (see the module docstring).

    Attributes
    ----------
    base : str
        Preset name or gear-set TOML path (relative paths against ``base_dir``).
    parameters : tuple of Parameter
        The varied keys (at least one).
    mode : str
        ``"grid"``, ``"zip"`` or ``"random"``.
    samples, seed : int or None
        Number of cases and random seed (random mode only; both required there).
    simulation : dict
        Run settings overriding the base's ``[simulation]`` table.
    summary : SummarySettings
        What is summarised per case.
    title : str
        Title of the combined dataset and the report.
    max_cases : int
        Bound on the number of cases (default :data:`DEFAULT_MAX_CASES`).
    base_dir : Path or None
        Directory of the sweep file (relative ``base`` paths).
    """

    base: str
    parameters: tuple[Parameter, ...]
    mode: str = "grid"
    samples: int | None = None
    seed: int | None = None
    simulation: dict = field(default_factory=dict)
    summary: SummarySettings = field(default_factory=SummarySettings)
    title: str = ""
    max_cases: int = DEFAULT_MAX_CASES
    base_dir: Path | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.base, str) or not self.base:
            raise ConfigError("base must be a preset name or a gear-set TOML path")
        params = check_items(self.parameters, Parameter, "parameters", error=ConfigError)
        if not params:
            raise ConfigError("a sweep needs at least one [[parameter]]")
        object.__setattr__(self, "parameters", params)
        paths = [p.path for p in params]
        for path in paths:
            if path in _RESERVED:
                raise ConfigError(f"parameter path {_short(path)} is the name of a dimension or "
                                  "coordinate of sweep.nc; vary its elements instead (e.g. "
                                  f"'{path}.0.<key>')")
        dup = sorted({p for p in paths if paths.count(p) > 1})
        if dup:
            raise ConfigError(f"parameter path {_short(dup[0])} is listed twice")
        for a in paths:
            for b in paths:
                if a != b and b.startswith(a + "."):
                    raise ConfigError(f"parameter paths {_short(a)} and {_short(b)} "
                                      f"overlap (one contains "
                                      "the other)")
        if self.mode not in _MODES:
            raise ConfigError(f"mode = {_short(self.mode)}; admissible: {', '.join(_MODES)}")
        mc = self.max_cases
        if isinstance(mc, bool) or not isinstance(mc, int) or not 1 <= mc <= HARD_MAX_CASES:
            raise ConfigError(f"max_cases = {_short(mc)}; admissible: an integer "
                              f"1..{HARD_MAX_CASES}")
        if self.mode == "random":
            for k in ("samples", "seed"):
                v = getattr(self, k)
                if isinstance(v, bool) or not isinstance(v, int) or v < (1 if k == "samples"
                                                                          else 0):
                    raise ConfigError(f"mode = 'random' needs {k} = an integer "
                                      f"{'>= 1' if k == 'samples' else '>= 0'}, got {_short(v)}")
            assert self.samples is not None  # (checked just above)
            if self.samples > self.max_cases:
                raise ConfigError(f"samples = {self.samples} is more than max_cases = "
                                  f"{self.max_cases}; raise max_cases (at most "
                                  f"{HARD_MAX_CASES}) or draw fewer samples")
        else:
            for k in ("samples", "seed"):
                if getattr(self, k) is not None:
                    raise ConfigError(f"{k} is a key of mode = 'random' only (mode is "
                                      f"{_short(self.mode)})")
            for p in params:
                if p.distribution is not None:
                    raise ConfigError(f"parameter {_short(p.path)}: a distribution needs mode = "
                                      "'random'")
        if self.mode == "zip":
            n0 = len(params[0].listed)
            for p in params[1:]:
                if len(p.listed) != n0:
                    raise ConfigError(f"mode = 'zip' needs as many values for every parameter:"
                                      f" {_short(params[0].path)} has {n0}, {_short(p.path)} has "
                                      f"{len(p.listed)}")
        n = self.n_cases
        if n > self.max_cases:
            sizes = " x ".join(str(len(p.listed)) for p in params)
            what = f"the grid has {sizes} = {n} cases" if self.mode == "grid" else \
                f"the sweep has {n} cases"
            raise ConfigError(f"{what}, more than max_cases = {self.max_cases}; use fewer "
                              f"values or raise max_cases (at most {HARD_MAX_CASES})")
        if not isinstance(self.simulation, dict):
            raise ConfigError("[simulation] must be a table")
        for k, v in self.simulation.items():  # the values: with the base's, per case
            if k not in SIMULATION_KEYS:
                raise ConfigError(f"unknown key {_short(k)} in [simulation] (admissible: "
                                  f"{', '.join(sorted(SIMULATION_KEYS))})")
            if isinstance(v, float) and not math.isfinite(v):
                raise ConfigError(f"[simulation].{k} = {v!r}; admissible: finite")
        if self.base_dir is not None and not isinstance(self.base_dir, str | Path):
            raise ConfigError(f"base_dir must be a folder (a path), got "
                              f"{type(self.base_dir).__name__}")
        if not isinstance(self.summary, SummarySettings):
            raise ConfigError("summary must be a SummarySettings")
        if not isinstance(self.title, str):
            raise ConfigError("title must be a string")

    @property
    def n_cases(self) -> int:
        """Number of cases (computed without building them)."""
        if self.mode == "random":
            assert self.samples is not None  # __post_init__: random mode needs samples
            return int(self.samples)
        if self.mode == "zip":
            return len(self.parameters[0].listed)
        return math.prod(len(p.listed) for p in self.parameters)

    def load_base(self) -> tuple[dict, str | None]:
        """The base description with the sweep's ``[simulation]`` merged, and its directory."""
        ref = self.base
        p = Path(ref)
        if self.base_dir is not None and (p.suffix == ".toml" or "/" in ref) \
                and not p.is_absolute():
            p = self.base_dir / p
            ref = str(p)
        try:
            cfg, base_dir = load_config(ref)
        except ConfigError as exc:
            raise ConfigError(f"base = {_short(self.base)}: {exc}") from None
        cfg = copy.deepcopy(cfg)
        sim = dict(cfg.get("simulation", {}))
        sim.update(self.simulation)
        cfg["simulation"] = sim
        return cfg, (str(base_dir) if base_dir is not None else None)

    def _values(self) -> list[tuple]:
        ps = self.parameters
        if self.mode == "grid":
            return list(itertools.product(*(p.listed for p in ps)))
        if self.mode == "zip":
            return list(zip(*(p.listed for p in ps), strict=True))
        rng = np.random.default_rng(self.seed)
        assert self.samples is not None  # __post_init__: random mode needs samples
        cols = [p.sample(rng, int(self.samples)) for p in ps]
        return list(zip(*cols, strict=True))

    def _label(self, p: Parameter, v: Any) -> str:
        if p.labels is not None and p.values is not None:
            for val, lab in zip(p.values, p.labels, strict=True):
                if val == v:
                    return lab
        return value_label(v)

    def _apply(self, base: dict, p: Parameter, v: Any, where: str) -> dict:
        exists, old = get_path(base, p.path)
        if exists:
            k_old, k_new = value_kind(old), value_kind(v)
            compatible = {"number": {"number", "string"}, "string": {"string", "number"},
                          "list": {"list"}, "table": {"table"}, "bool": {"bool"}}
            if k_new not in compatible.get(k_old, {k_old}):
                raise ConfigError(f"{where}: {_short(v)} is a {k_new}, but the base "
                                  f"description has "
                                  f"a {k_old} at {_short(p.path)} ({_short(old)})")
        return set_path(base, p.path, v)

    def _check_description(self, desc: dict, base_dir: str | None, where: str) -> dict:
        run = resolve_run_settings(desc.get("simulation", {}))
        try:
            gearset_from_dict(desc, base=Path(base_dir) if base_dir else None)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        return run

    def cases(self) -> list[SweepCase]:
        """Build and check every case.

        Every value of every parameter (in random mode: the distribution's bounds) is checked
        alone against the base description first, so a wrong path, type or value is reported
        with the parameter and the value.

        Raises
        ------
        ConfigError
            Unknown path, a value of the wrong type, an invalid value, an invalid run setting.
        """
        base, base_dir = self.load_base()
        # every case holds its own description: check the memory before building them
        # (measured: about 20 x the pickled size of the description per case)
        per_case = 24 * len(pickle.dumps(base)) + 4096
        require_memory(self.n_cases * per_case, f"building the sweep's {self.n_cases} cases "
                       f"(about {format_bytes(per_case)} each)",
                       "use fewer values or samples, or split the sweep")
        for i, p in enumerate(self.parameters):
            exists, old = get_path(base, p.path)  # every table on the way exists
            probes: list[Any]
            if p.values is not None:
                probes = list(p.values)
            else:
                probes = [getattr(p, k) for k in ("low", "high", "mean")
                          if getattr(p, k) is not None]
                if exists and value_kind(old) not in ("number", "list", "string"):
                    raise ConfigError(f"parameter {_short(p.path)}: a distribution "
                                      f"draws numbers, but "
                                      f"the base has {_short(old)} there")
            for v in probes:
                where = f"parameter #{i + 1} ({_short(p.path)}), value {_short(value_label(v))}"
                if p.distribution is not None:
                    v = np.asarray(v, dtype=float).tolist()
                desc = self._apply(base, p, v, where)
                self._check_description(desc, base_dir, where)
            numeric = p.distribution is not None or _coordinate_kind(probes) == "number"
            if numeric and (p.units or path_units(p.path)) is None:
                raise ConfigError(f"parameter {_short(p.path)}: the units of this key "
                                  f"are not known; "
                                  "give units = \"...\" (UDUNITS, e.g. \"N m-1\", \"1\")")
        out = []
        for idx, vals in enumerate(self._values()):
            desc = base
            for p, v in zip(self.parameters, vals, strict=True):
                desc = self._apply(desc, p, v, f"parameter {_short(p.path)}")
            run = resolve_run_settings(desc.get("simulation", {}))
            if idx == 0:
                self._check_description(desc, base_dir, "case 0")
            sha = config_hash({"kind": "gearvib sweep case", "gearset": desc, "run": run,
                               "base_dir": base_dir, "gearvib_version": __version__})
            labels = tuple(self._label(p, v) for p, v in zip(self.parameters, vals, strict=True))
            out.append(SweepCase(idx, tuple(vals), labels, desc, run, base_dir, sha))
        return out

    def to_dict(self) -> dict[str, Any]:
        """The description as a dict that :func:`sweep_from_dict` reads back."""
        out: dict[str, Any] = {"title": self.title, "base": self.base, "mode": self.mode,
                               "max_cases": self.max_cases}
        if self.mode == "random":
            out["samples"], out["seed"] = self.samples, self.seed
        if self.simulation:
            out["simulation"] = dict(self.simulation)
        out["parameter"] = [p.to_dict() for p in self.parameters]
        out["summary"] = self.summary.to_dict()
        return out

    def coordinate_kinds(self) -> list[str]:
        """Per parameter: ``"number"``, ``"string"``, ``"bool"`` or ``"label"`` (lists,
        tables, mixed)."""
        kinds = []
        for p in self.parameters:
            if p.values is not None:
                kinds.append(_coordinate_kind(list(p.values)))
            else:
                b = np.asarray(p.low if p.low is not None else p.mean)
                kinds.append("number" if b.ndim == 0 else "label")
        return kinds


def sweep_from_dict(d: dict, *, base_dir: str | Path | None = None) -> Sweep:
    """A :class:`Sweep` from a parsed TOML dict (keys checked; errors name the key)."""
    check_keys(d, _TOP, "the sweep description (top level)")
    if "base" not in d:
        raise ConfigError("missing key 'base' in the sweep description (a preset name or a "
                          "gear-set TOML file)")
    params_t = d.get("parameter")
    if not isinstance(params_t, list) or not params_t:
        raise ConfigError("the sweep description needs at least one [[parameter]] table with "
                          "path and values")
    params = tuple(Parameter.from_dict(t, f"[[parameter]] #{i + 1}")
                   for i, t in enumerate(params_t))
    sim = d.get("simulation", {})
    if not isinstance(sim, dict):
        raise ConfigError("[simulation] must be a table")
    for k in sim:
        if k not in SIMULATION_KEYS:
            raise ConfigError(f"unknown key {_short(k)} in [simulation] (admissible: "
                              f"{', '.join(sorted(SIMULATION_KEYS))})")
    summary = SummarySettings.from_dict(d.get("summary", {}))
    return Sweep(base=d["base"], parameters=params, mode=d.get("mode", "grid"),
                 samples=d.get("samples"), seed=d.get("seed"), simulation=dict(sim),
                 summary=summary, title=d.get("title", ""),
                 max_cases=d.get("max_cases", DEFAULT_MAX_CASES),
                 base_dir=Path(base_dir) if base_dir is not None else None)


def load_sweep(path: str | Path) -> Sweep:
    """Read and check a sweep TOML file.

    Raises
    ------
    ConfigError
        Missing file, invalid TOML, unknown or invalid keys (the message names the key).
    """
    p = Path(path)
    d = read_toml(p, "sweep file")
    sweep = sweep_from_dict(d, base_dir=p.resolve().parent)
    if not sweep.title:
        sweep = replace(sweep, title=p.stem)
    return sweep
