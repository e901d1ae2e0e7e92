"""Study recipes: which gear sets to simulate, how, and how to analyse them (TOML).

A recipe names one or more *cases* (preset names or TOML files, relative paths resolved against
the recipe), optional run settings shared by all cases and optional analysis settings::

    [study]
    title = "Planet phasing: the paper's cases 1 and 2"
    cases = [ {name = "case1", config = "paper-case1"},
              {name = "case2", config = "paper-case2"} ]
    reference = "case1"          # optional: the case the others are compared with (default first)

    [run]                        # optional; defaults from each gear set's [simulation] table
    speed_start_rpm = 0.0
    speed_end_rpm = 4000.0
    duration = 1.0
    input_torque = 60.0
    fs_out = 25000.0

    [analysis]                   # optional
    n_max = 4
    stability_points = 300

Every table is checked like :mod:`gearvib.config`: an unknown key is an error naming the key and
the admissible ones, and every value is type- and range-checked (:data:`ANALYSIS_LIMITS`).
:func:`check_report_size` refuses maps whose frames would not fit into memory before a run is
simulated or analysed (with :func:`check_report_duration` and :func:`check_cut_resolution`:
:mod:`gearvib.report.report_limits`).
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

from gearvib.checks import RECIPE, check_integer, check_items, check_number
from gearvib.checks import short as _short
from gearvib.config import ConfigError, check_keys, list_presets, load_config, read_toml
from gearvib.report.report_limits import (  # re-exported: checked before a run
    check_cut_resolution,
    check_report_duration,
    check_report_size,
)
from gearvib.simulation.settings import MAX_DURATION, MAX_SPEED_RPM, MAX_TORQUE, MIN_DURATION

__all__ = [
    "ANALYSIS_LIMITS",
    "DEFAULT_RUN",
    "MAX_CUT_ORDERS",
    "AnalysisSettings",
    "Case",
    "RunSettings",
    "Study",
    "check_cut_orders",
    "check_cut_resolution",
    "check_order_resolution",
    "check_report_duration",
    "check_report_size",
    "load_study",
    "resolve_run",
]

DEFAULT_RUN = {"speed_start_rpm": 0.0, "speed_end_rpm": 4000.0, "duration": 1.0,
               "input_torque": 60.0, "fs_out": 25000.0}
"""Run settings used when neither the recipe nor the gear set's ``[simulation]`` gives one."""

_TOP = {"study", "run", "analysis"}
_STUDY = {"title", "cases", "reference", "description"}
_CASE = {"name", "config", "label"}
_RUN = set(DEFAULT_RUN)
_ANALYSIS = {"n_max", "stability_points", "map_resolution_hz", "map_overlap", "orders",
             "threshold_db", "tolerance", "frequency_max_hz", "force_mesh", "spectrum_peaks",
             "stability", "cut_orders", "order_resolution"}
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,99}$")
ANALYSIS_LIMITS: dict[str, tuple[float, float]] = {
    "n_max": (1, 20),
    "stability_points": (2, 20_000),
    "orders": (0, 100),
    "spectrum_peaks": (1, 200),
    "map_resolution_hz": (1e-3, 1e6),
    "tolerance": (0.0, 0.5),
    "threshold_db": (0.0, 200.0),
    "frequency_max_hz": (0.0, 1e9),
    "cut_orders": (0.0, 1e4),
    "order_resolution": (0.01, 10.0),
}
"""Admissible ranges of the ``[analysis]`` keys (integers: inclusive; ``stability_points``
bounds the Floquet chart's computing time, about 1-5 ms per point; ``cut_orders``: each order
> 0 and at most 1e4, at most :data:`MAX_CUT_ORDERS` of them; ``order_resolution``: 0 for the
automatic resolution, else 0.01..10 orders)."""
MAX_CUT_ORDERS = 20
"""Most orders a report cuts on request (``cut_orders``, ``gearvib report --orders``)."""
_RUN_LIMITS = {"speed_start_rpm": (0.0, MAX_SPEED_RPM), "speed_end_rpm": (0.0, MAX_SPEED_RPM),
               "duration": (MIN_DURATION, MAX_DURATION), "input_torque": (-MAX_TORQUE, MAX_TORQUE),
               "fs_out": (0.0, 1e12)}
"""Ranges of the run settings (as ``[simulation]``, :mod:`gearvib.simulation.settings`)."""
MAX_CASES = 100
"""Most cases of one study."""
STABILITY = ("full", "coarse", "off")
"""Values of ``[analysis] stability``: the Floquet chart at ``stability_points`` speeds,
at most 80 speeds with looser accuracy, or none."""


def _number(value: Any, where: str, *, positive: bool = False, minimum: float | None = None,
            maximum: float | None = None) -> float:
    """A finite number; ``positive`` (> 0) is checked before ``minimum``."""
    v = check_number(value, where, low=0.0 if positive else minimum, low_open=positive,
                     high=maximum, error=ConfigError, wording=RECIPE)
    if positive and minimum is not None:
        check_number(value, where, low=minimum, error=ConfigError, wording=RECIPE)
    return v


def _integer(value: Any, where: str, minimum: int, maximum: int | None = None) -> int:
    return check_integer(value, where, low=minimum, high=maximum, error=ConfigError,
                         types=(int,), wording=RECIPE)


@dataclass(frozen=True)
class Case:
    """One gear set of a study.

    Attributes
    ----------
    name : str
        Short identifier (letters, digits, ``_.-``); the run file is ``<name>.nc``.
    config : str
        Preset name (``paper-case1``) or path of a gear-set TOML file (absolute, or relative to
        the recipe when loaded with :func:`load_study`).
    label : str
        Display name in the report (default: the gear set's title).
    """

    name: str
    config: str
    label: str = ""

    def __post_init__(self) -> None:
        for k in ("name", "config", "label"):
            if not isinstance(getattr(self, k), str):
                raise ConfigError(f"Case.{k} must be a string, got {_short(getattr(self, k))}")
        if not self.config:
            raise ConfigError("Case.config must name a preset or a gear-set file")

    def load(self) -> tuple[dict, Path | None]:
        """The gear-set description dict and its base directory (see
        :func:`gearvib.config.load_config`)."""
        return load_config(self.config)


@dataclass(frozen=True)
class RunSettings:
    """Run-up settings shared by all cases; ``None`` takes the gear set's value.

    Attributes
    ----------
    speed_start_rpm, speed_end_rpm : float or None
        Input speed at the start and end of the linear ramp [min^-1].
    duration : float or None
        Ramp duration [s].
    input_torque : float or None
        Constant input torque [N m].
    fs_out : float or None
        Output sample rate [Hz].
    """

    speed_start_rpm: float | None = None
    speed_end_rpm: float | None = None
    duration: float | None = None
    input_torque: float | None = None
    fs_out: float | None = None

    def __post_init__(self) -> None:
        for k, (lo, hi) in _RUN_LIMITS.items():
            v = getattr(self, k)
            if v is None:
                continue
            if k == "duration":
                object.__setattr__(self, k, _number(v, f"RunSettings.{k}", minimum=lo,
                                                    maximum=hi))
            elif k == "fs_out":
                object.__setattr__(self, k, _number(v, f"RunSettings.{k}", positive=True,
                                                    maximum=hi))
            else:  # speeds and torque: their signs are checked with the gear set's drive
                object.__setattr__(self, k, _number(v, f"RunSettings.{k}", minimum=-hi,
                                                    maximum=hi))

    def to_dict(self) -> dict[str, float]:
        """The settings that are given (``None`` omitted)."""
        return {k: v for k, v in asdict(self).items() if v is not None}


@dataclass(frozen=True)
class AnalysisSettings:
    """How the runs are analysed.

    Attributes
    ----------
    n_max : int
        Highest order ``n`` of the theory candidates ``2 f_i/n``, ``(f_i + f_j)/n``.
    stability_points : int
        Speeds of the Floquet stability chart over the run-up range (boundaries refined).
    stability : str
        ``"full"`` (default): the Floquet chart at ``stability_points`` speeds, ``max|mu|``
        to 1e-7 near the stability limit; ``"coarse"``: at most 80 speeds, ``max|mu|`` to
        1e-6, boundaries to 1e-6; ``"off"``: no chart (parametric rises are then judged by
        the theory candidates alone).
    map_resolution_hz : float
        Resolution bandwidth of the rpm-frequency map [Hz].
    map_overlap : float
        Frame overlap of the maps, in ``[0, 1)``.
    orders : int
        Mesh orders ``1..orders`` of every mesh frequency, drawn in the sonogram and used for
        resonance detection; 0 (default): per mesh frequency enough orders to reach the
        highest natural frequency in the map at the top speed, 7 to 20 (7 for the paper's
        set).
    threshold_db : float
        Minimum rise above the background of a detected resonance [dB].
    tolerance : float
        Relative uncertainty of the natural frequencies in the peak identification and the
        resonance classification (their windows; see docs/catalogue-identification.md).
    frequency_max_hz : float
        Upper frequency of the sonogram and spectra [Hz] (0: automatic, 2.2 x the highest
        natural frequency, at most fs/2).
    force_mesh : str
        Mesh whose tooth force is order-analysed (default: the first sun mesh).
    spectrum_peaks : int
        Peaks labelled in each tooth-force spectrum.
    cut_orders : tuple of float
        Orders of the order cuts, as multiples of the reference (input) shaft, cut besides
        the 1st to 3rd mesh harmonics (``gearvib report --orders``); the catalogue's named
        fault and sideband orders are added where the resolution separates them.
    order_resolution : float
        Resolution bandwidth of the order cuts [orders]; 0 (default): automatic, the finest
        that leaves 8 frames in the run and at most 1/4 order
        (:func:`analysis.runup_levels.runup_levels`).
    """

    n_max: int = 4
    stability_points: int = 300
    map_resolution_hz: float = 20.0
    map_overlap: float = 0.9
    orders: int = 0
    threshold_db: float = 6.0
    tolerance: float = 0.03
    frequency_max_hz: float = 0.0
    force_mesh: str = ""
    spectrum_peaks: int = 10
    stability: str = "full"
    cut_orders: tuple[float, ...] = ()
    order_resolution: float = 0.0

    def __post_init__(self) -> None:
        given = {k: getattr(self, k) for k in _ANALYSIS}
        if not isinstance(self.stability, str) or self.stability not in STABILITY:
            raise ConfigError(f"[analysis].stability = {_short(self.stability)}; admissible: "
                              + ", ".join(repr(x) for x in STABILITY))
        for k, v in _checked_analysis(given, "AnalysisSettings").items():
            object.__setattr__(self, k, v)

    def with_cuts(self, orders: Any = None, resolution: float | None = None
                  ) -> AnalysisSettings:
        """A copy with the order cuts asked for (``gearvib report --orders``,
        ``--order-resolution``); None keeps the setting.

        Parameters
        ----------
        orders : sequence of float, optional
            ``cut_orders`` (checked by :func:`check_cut_orders`).
        resolution : float, optional
            ``order_resolution`` [orders] (0: automatic; :func:`check_order_resolution`).

        Returns
        -------
        AnalysisSettings
        """
        kw: dict[str, Any] = {}
        if orders is not None:
            kw["cut_orders"] = check_cut_orders(list(orders), "--orders")
        if resolution is not None:
            kw["order_resolution"] = check_order_resolution(resolution, "--order-resolution")
        return replace(self, **kw) if kw else self

    def to_dict(self) -> dict[str, Any]:
        """All settings as a plain dict (``cut_orders`` as a list)."""
        d = asdict(self)
        d["cut_orders"] = list(self.cut_orders)
        return d

    @classmethod
    def from_dict(cls, table: dict, where: str = "[analysis]") -> AnalysisSettings:
        """Checked settings from a dict (unknown keys rejected)."""
        check_keys(table, _ANALYSIS, where)
        return cls(**_checked_analysis(table, where))


def _checked_analysis(table: dict, where: str) -> dict[str, Any]:
    """The ``[analysis]`` values of ``table`` checked (:class:`AnalysisSettings`)."""
    kw: dict[str, Any] = {}
    for k in ("n_max", "stability_points", "orders", "spectrum_peaks"):
        if k in table:
            lo, hi = ANALYSIS_LIMITS[k]
            kw[k] = _integer(table[k], f"{where}.{k}", int(lo), int(hi))
    if "stability" in table:
        if not isinstance(table["stability"], str) or table["stability"] not in STABILITY:
            raise ConfigError(f"{where}.stability = {_short(table['stability'])}; "
                              "admissible: " + ", ".join(repr(x) for x in STABILITY))
        kw["stability"] = table["stability"]
    for k in ("map_resolution_hz", "tolerance"):
        if k in table:
            lo, hi = ANALYSIS_LIMITS[k]
            kw[k] = _number(table[k], f"{where}.{k}", positive=True,
                            minimum=lo if k != "tolerance" else None,
                            maximum=hi if k != "tolerance" else None)
    for k in ("threshold_db", "frequency_max_hz"):
        if k in table:
            kw[k] = _number(table[k], f"{where}.{k}", minimum=0.0,
                            maximum=ANALYSIS_LIMITS[k][1])
    if "map_overlap" in table:
        v = _number(table["map_overlap"], f"{where}.map_overlap", minimum=0.0)
        if v >= 1.0:
            raise ConfigError(f"{where}.map_overlap = {v!r}; admissible: 0 <= overlap < 1")
        kw["map_overlap"] = v
    if "tolerance" in kw and kw["tolerance"] >= 0.5:
        raise ConfigError(f"{where}.tolerance = {kw['tolerance']!r}; admissible: < 0.5")
    if "force_mesh" in table:
        if not isinstance(table["force_mesh"], str) or len(table["force_mesh"]) > 200:
            raise ConfigError(f"{where}.force_mesh must be a mesh name (string)")
        kw["force_mesh"] = table["force_mesh"]
    if "cut_orders" in table:
        kw["cut_orders"] = check_cut_orders(table["cut_orders"], f"{where}.cut_orders")
    if "order_resolution" in table:
        kw["order_resolution"] = check_order_resolution(table["order_resolution"],
                                                        f"{where}.order_resolution")
    return kw


def check_cut_orders(value: Any, where: str = "cut_orders") -> tuple[float, ...]:
    """Orders of the order cuts: a list of at most :data:`MAX_CUT_ORDERS` numbers in
    (0, 1e4] (bools and strings refused), as a tuple of floats.

    Raises
    ------
    ConfigError
        Naming ``where`` and the admissible range.
    """
    if isinstance(value, str | bytes) or not isinstance(value, list | tuple):
        raise ConfigError(f"{where} = {_short(value)}: expected a list of orders, e.g. "
                          "[1, 2, 24]")
    if len(value) > MAX_CUT_ORDERS:
        raise ConfigError(f"{where}: {len(value)} orders; admissible: at most "
                          f"{MAX_CUT_ORDERS}")
    hi = ANALYSIS_LIMITS["cut_orders"][1]
    return tuple(check_number(v, f"{where}[{i}]", low=0.0, low_open=True, high=hi,
                              error=ConfigError, wording=RECIPE) for i, v in enumerate(value))


def check_order_resolution(value: Any, where: str = "order_resolution") -> float:
    """Resolution of the order cuts: 0 (automatic) or a number in 0.01..10 orders.

    Raises
    ------
    ConfigError
        Naming ``where`` and the admissible range.
    """
    lo, hi = ANALYSIS_LIMITS["order_resolution"]
    if not isinstance(value, bool) and isinstance(value, int | float) and value == 0:
        return 0.0
    v = check_number(value, where, low=lo, high=hi, error=ConfigError, wording=RECIPE)
    return float(v)


@dataclass(frozen=True)
class Study:
    """A study recipe (see the module docstring).

    Attributes
    ----------
    title : str
        Report title (empty: from the gear sets' titles or names).
    cases : tuple of Case
        The gear sets, in report order (names unique).
    run : RunSettings
        Run-up settings overriding each gear set's ``[simulation]`` table.
    analysis : AnalysisSettings
        Analysis settings.
    reference : str
        Name of the case the others are compared with (default: the first case).
    source : Path or None
        The recipe file, if loaded from one.
    """

    title: str
    cases: tuple[Case, ...]
    run: RunSettings = field(default_factory=RunSettings)
    analysis: AnalysisSettings = field(default_factory=AnalysisSettings)
    reference: str = ""
    source: Path | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.title, str):
            raise ConfigError(f"title must be a string, got {_short(self.title)}")
        object.__setattr__(self, "cases", check_items(self.cases, Case, "cases",
                                                      error=ConfigError))
        for k, cls in (("run", RunSettings), ("analysis", AnalysisSettings)):
            if not isinstance(getattr(self, k), cls):
                raise ConfigError(f"{k} must be a {cls.__name__}, got "
                                  f"{type(getattr(self, k)).__name__}")
        if not isinstance(self.reference, str):
            raise ConfigError(f"reference must be a case name, got {_short(self.reference)}")
        if self.source is not None and not isinstance(self.source, str | Path):
            raise ConfigError(f"source must be a path, got {type(self.source).__name__}")
        if not self.cases:
            raise ConfigError("a study needs at least one case")
        if len(self.cases) > MAX_CASES:
            raise ConfigError(f"a study has at most {MAX_CASES} cases, got {len(self.cases)}")
        names = [c.name for c in self.cases]
        for n in names:
            if not _NAME.match(n):
                raise ConfigError(f"case name {_short(n)} is not admissible: use letters, "
                                  "digits, '_', '.', '-' (it names the output file)")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ConfigError(f"case name {dup[0]!r} is used twice")
        if self.reference and self.reference not in names:
            raise ConfigError(f"reference = {_short(self.reference)} is not a case (cases: "
                              f"{', '.join(names)})")

    @property
    def reference_case(self) -> str:
        """Name of the reference case (the first case unless ``reference`` is set)."""
        return self.reference or self.cases[0].name

    @classmethod
    def for_presets(cls, names: list[str] | tuple[str, ...], *, title: str | None = None,
                    analysis: AnalysisSettings | None = None, **run: float) -> Study:
        """A study of built-in presets (or TOML paths), case names from the preset names.

        Parameters
        ----------
        names : sequence of str
            Preset names or gear-set TOML paths.
        title : str, optional
            Report title (default: from the gear sets' titles or names).
        analysis : AnalysisSettings, optional
            Analysis settings.
        **run : float
            Run settings (``speed_start_rpm``, ``speed_end_rpm``, ``duration``,
            ``input_torque``, ``fs_out``).

        Examples
        --------
        >>> Study.for_presets(["paper-case1", "paper-case2"], duration=0.25).cases[1].name
        'paper-case2'
        """
        check_keys(run, _RUN, "the run settings")
        settings = RunSettings(**{k: _number(v, k) for k, v in run.items()})
        if isinstance(names, str) or not isinstance(names, list | tuple):
            raise ConfigError("names must be a list of preset names or TOML paths")
        cases = tuple(Case(name=Path(n).stem if n.endswith(".toml") else n, config=str(n))
                      for n in names)
        return cls(title=title or "",
                   cases=cases, run=settings, analysis=analysis or AnalysisSettings())

    def with_duration(self, duration: float) -> Study:
        """A copy whose run-up lasts ``duration`` seconds (same speed range)."""
        return replace(self, run=replace(self.run, duration=_number(
            duration, "duration", minimum=MIN_DURATION, maximum=MAX_DURATION)))


def resolve_run(run: RunSettings, gearset_cfg: dict) -> dict[str, Any]:
    """Complete, checked run settings for one gear set.

    The gear set's ``[simulation]`` table decides the drive (``"speed"``, ``"torque"`` or
    ``"motor"``, see :mod:`gearvib.simulation.settings`); the study's ``[run]`` values replace
    its values; :data:`DEFAULT_RUN` fills what neither gives (a speed drive without
    ``input_torque`` or ``load_torque`` gets the default input torque).

    Returns
    -------
    dict
        :func:`gearvib.simulation.settings.read_run_settings` of the merged table (``drive``,
        ``speed_start_rpm``, ``speed_end_rpm``, ``duration``, ``input_torque`` where the drive
        has one, ``load_torque``, ``motor``, ...) with ``fs_out`` always set.

    Raises
    ------
    ConfigError
        A value is not admissible, or a ``[run]`` value does not apply to the drive (the
        message names the key, the drive and the admissible range).
    """
    from gearvib.simulation.settings import read_run_settings

    sim = gearset_cfg.get("simulation", {}) if isinstance(gearset_cfg, dict) else {}
    if not isinstance(sim, dict):
        raise ConfigError(f"[simulation] must be a table, got {type(sim).__name__}")
    sim = dict(sim)
    given = run.to_dict()
    fs_out = given.pop("fs_out", None)
    drive = sim.get("drive", "speed")
    if "input_torque" in given and drive == "motor":
        raise ConfigError("[run].input_torque does not apply to this gear set: its "
                          "[simulation] drive is 'motor' (the torque follows the motor "
                          "characteristic); remove it from [run] or use a speed or torque drive")
    if drive == "speed" and "input_torque" in given:
        sim.pop("load_torque", None)  # the study's input torque replaces the set's load
    if drive == "speed" and not ({"input_torque", "load_torque"} & (set(sim) | set(given))):
        given["input_torque"] = DEFAULT_RUN["input_torque"]
    for k in ("speed_start_rpm", "speed_end_rpm", "duration"):
        if k not in sim and k not in given and (drive == "speed" or k == "duration"):
            given[k] = DEFAULT_RUN[k]
    try:
        out = read_run_settings(sim, given)
    except ValueError as exc:
        raise ConfigError(str(exc)) from None
    out["fs_out"] = _number(fs_out if fs_out is not None else (
        out.get("fs_out") or DEFAULT_RUN["fs_out"]), "run setting fs_out", positive=True,
        maximum=_RUN_LIMITS["fs_out"][1])
    if drive == "speed" and (out["speed_end_rpm"] <= out["speed_start_rpm"]
                             or out["speed_start_rpm"] < 0):
        raise ConfigError(f"speed range {out['speed_start_rpm']:g} -> {out['speed_end_rpm']:g} "
                          "min-1 is not admissible: need 0 <= start < end (a run-up)")
    return out


def _case(table: Any, i: int, base: Path) -> Case:
    where = f"[study].cases #{i + 1}"
    check_keys(table, _CASE, where)
    for k in ("name", "config"):
        if k not in table:
            raise ConfigError(f"missing key {k!r} in {where}")
        if not isinstance(table[k], str) or not table[k]:
            raise ConfigError(f"{where}.{k} must be a non-empty string")
    config = table["config"]
    p = Path(config)
    if config not in list_presets() and (p.suffix == ".toml" or "/" in config):
        if not p.is_absolute():
            p = base / p
        if not p.is_file():
            raise ConfigError(f"{where}: gear-set file {str(p)!r} not found")
        config = str(p)
    elif config not in list_presets():
        raise ConfigError(f"{where}: unknown preset {config!r} (available: "
                          f"{', '.join(list_presets())}; or give a path to a .toml file)")
    label = table.get("label", "")
    if not isinstance(label, str):
        raise ConfigError(f"{where}.label must be a string")
    return Case(name=table["name"], config=config, label=label)


def load_study(path: str | Path) -> Study:
    """Read and check a study recipe.

    Parameters
    ----------
    path : path-like
        The recipe TOML file.

    Returns
    -------
    Study

    Raises
    ------
    ConfigError
        Invalid TOML, unknown or missing keys (the message names the key), unknown presets or
        missing gear-set files.
    """
    p = Path(path)
    doc = read_toml(p, "study file")
    check_keys(doc, _TOP, f"{p.name} (top level)")
    st = check_keys(doc.get("study", None) if "study" in doc else None, _STUDY, "[study]") \
        if "study" in doc else None
    if st is None:
        raise ConfigError(f"{p.name}: missing table [study]")
    cases_t = st.get("cases")
    if not isinstance(cases_t, list) or not 1 <= len(cases_t) <= MAX_CASES:
        raise ConfigError(f"[study].cases must be a list of 1..{MAX_CASES} tables "
                          "{name = ..., config = ...}")
    base = p.resolve().parent
    cases = tuple(_case(t, i, base) for i, t in enumerate(cases_t))
    title = st.get("title", "")
    if not isinstance(title, str):
        raise ConfigError("[study].title must be a string")
    if not isinstance(st.get("description", ""), str):
        raise ConfigError("[study].description must be a string")
    run_t = check_keys(doc.get("run", {}), _RUN, "[run]")
    run = RunSettings(**{k: _number(v, f"[run].{k}") for k, v in run_t.items()})
    analysis = AnalysisSettings.from_dict(doc.get("analysis", {}))
    reference = st.get("reference", "")
    if not isinstance(reference, str):
        raise ConfigError("[study].reference must be a case name (string)")
    return Study(title=title, cases=cases, run=run, analysis=analysis, reference=reference,
                 source=p)
