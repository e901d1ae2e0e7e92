"""Find and classify the amplitude rises of a run-up map (rpm-frequency map, sonogram).

An engineer reads a run-up map (the paper's Figure 11) by its features: rays ``f = k f_mesh``
(order-locked) and vertical lines at the natural frequencies (frequency-locked); resonances
sit where they cross. :func:`detect_resonances` does the same, in three passes:

1. **Rises along the mesh-order rays.** For every harmonic ``k`` the level along the ray
   (the maximum inside the ray's width, which includes the sweep of the ray within one frame)
   is tracked over speed, only where the ray is resolved from its neighbours; a peak of that
   track with a prominence of at least ``threshold_db`` is a rise.
2. **Rises along the natural frequencies** off every ray crossing (frequency-locked).
3. **Isolated spots** anywhere else (local maxima of the map above its median over time).

Each rise is classified, with its evidence:

* **forced resonance** - the ray ``k`` crosses a natural frequency ``f_i`` inside the rise
  (predicted speed ``f_i / (k f_mesh per rpm)``; the crossing lies within the rise's -3 dB speed
  range widened by the speed tolerance), or another ray ``k'`` crosses ``f_i`` there and the
  rise on ray ``k`` is the same resonance seen through the mesh-stiffness modulation
  (``f_i + (k - k') f_mesh``);
* **parametric instability** - a rise at ``f_i`` (or at ``f_i + j f_mesh`` off the rays) while the
  speed is inside a Floquet-unstable band in which this run-up lets a disturbance grow by at
  least ``growth_threshold_db`` (:func:`analysis.instability.growth.runup_growth`); without a
  chart, inside an allowed theory candidate ``2 f_i / n`` or ``(f_i + f_j) / n`` (growth not
  checked);
* **unexplained** - anything else.

The start of the run is left out: frames before the settling time (automatic: the frames
whose window reaches back to the start of the record, and a decaying start transient of the
broadband level) and frames in which the mesh orders are closer than the map resolution (the
quasi-static start, where the response is the free vibration after each tooth-pair change).

Every row states the chance that a random rise gets its explanation (``coincidence``: the
fraction of the analysed speed range of its feature covered by the explaining windows).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.ndimage
import scipy.signal

from analysis.cf import cf_dataset
from analysis.checks import require_instance, require_positive, require_real
from analysis.identification import covered_fraction
from analysis.instability.growth import GrowthTable, runup_growth
from analysis.instability.theory import Candidates, MeshPhasingRule, natural_frequencies
from analysis.runup import MapLevels, map_levels

__all__ = ["FORCED", "PARAMETRIC", "UNEXPLAINED", "Crossing", "Resonances",
           "detect_resonances", "merge_mesh_frequencies"]

FORCED = "forced resonance"
PARAMETRIC = "parametric instability"
UNEXPLAINED = "unexplained"
MECHANISMS = (FORCED, PARAMETRIC, UNEXPLAINED)


@dataclass(frozen=True)
class Crossing:
    """A predicted crossing of mesh harmonic ``k`` with natural frequency ``mode``.

    Attributes
    ----------
    harmonic : int
        Mesh harmonic ``k``.
    mode : str
        Natural-frequency name.
    frequency_hz : float
        The natural frequency [Hz].
    rpm : float
        Predicted speed ``f_i / (k f_mesh per rpm)`` [min-1].
    status : str
        ``"rise"`` (a forced-resonance rise on ray ``k`` there), ``"no rise"`` (ray resolved,
        nothing above the threshold) or ``"not analysed"`` (ray not resolved or outside the
        analysed frames).
    strength_db : float
        Rise of the detected resonance [dB] (NaN unless ``status == "rise"``).
    group : str
        Mesh frequency the harmonic belongs to ("" for a set with one; see
        :func:`merge_mesh_frequencies`).
    """

    harmonic: int
    mode: str
    frequency_hz: float
    rpm: float
    status: str
    strength_db: float
    group: str = ""


@dataclass(frozen=True)
class Resonances:
    """Detected rises of a run-up map (one row each, sorted by speed).

    Attributes
    ----------
    time, rpm : ndarray
        Time [s] and speed [min-1] of the rise.
    frequency : ndarray
        Response frequency [Hz].
    f_mesh : ndarray
        Mesh frequency there [Hz].
    order : ndarray of int
        Mesh harmonic of the ray the rise lies on (0: not on a ray).
    feature : ndarray of str
        ``"ray"``, ``"natural frequency"`` or ``"spot"``.
    mechanism : ndarray of str
        ``"forced resonance"``, ``"parametric instability"`` or ``"unexplained"``.
    mode : ndarray of str
        Natural frequency involved ("" if none).
    cause : ndarray of str
        E.g. ``"3 f_mesh = f5"`` or ``"2 (f3=f4)/3"``.
    predicted_rpm : ndarray
        Speed the cause predicts [min-1] (NaN if none).
    strength_db : ndarray
        Rise above its track or background [dB].
    coincidence : ndarray
        Chance that a random rise of this feature gets an explanation of this kind.
    note : ndarray of str
        Evidence and remarks.
    crossings : tuple of Crossing
        Every predicted crossing of a mesh harmonic with a natural frequency in the analysed
        speed range, with what was found there.
    growth : GrowthTable or None
        Growth of every Floquet-unstable band along the run.
    settle_time : float
        Frames before this time [s] were left out.
    notes : tuple of str
        Remarks about the analysis (left-out ranges, resolution).
    mesh_frequency_per_rpm : float
        Mesh frequency per speed [Hz per min-1] (the first one after
        :func:`merge_mesh_frequencies`).
    group : ndarray of str
        Mesh frequency whose ray a rise lies on ("" when not on a ray or for a set with one mesh
        frequency; see :func:`merge_mesh_frequencies`).
    """

    time: np.ndarray
    rpm: np.ndarray
    frequency: np.ndarray
    f_mesh: np.ndarray
    order: np.ndarray
    mechanism: np.ndarray
    mode: np.ndarray
    strength_db: np.ndarray
    note: np.ndarray
    mesh_frequency_per_rpm: float = 1.0
    feature: np.ndarray = field(default_factory=lambda: np.zeros(0, object))
    cause: np.ndarray = field(default_factory=lambda: np.zeros(0, object))
    predicted_rpm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    coincidence: np.ndarray = field(default_factory=lambda: np.zeros(0))
    crossings: tuple[Crossing, ...] = ()
    growth: GrowthTable | None = None
    settle_time: float = 0.0
    notes: tuple[str, ...] = ()
    group: np.ndarray | None = None

    def __len__(self) -> int:
        return int(self.time.size)

    @property
    def groups(self) -> np.ndarray:
        """:attr:`group`, or "" for every row when not set."""
        if self.group is None:
            return np.full(len(self), "", dtype=object)
        return self.group

    def select(self, mask: Any) -> Resonances:
        """Rows where ``mask`` is true (crossings, growth and notes kept)."""
        m = np.asarray(mask, dtype=bool)
        kw = {k: getattr(self, k)[m] for k in _ROW_FIELDS}
        return Resonances(**kw, mesh_frequency_per_rpm=self.mesh_frequency_per_rpm,
                          crossings=self.crossings, growth=self.growth,
                          settle_time=self.settle_time, notes=self.notes,
                          group=self.groups[m])

    def counts(self) -> dict[str, int]:
        """Number of rises per mechanism."""
        return {m: int(np.sum(self.mechanism == m)) for m in MECHANISMS}

    @property
    def unexplained_fraction(self) -> float:
        """Fraction of the rises classified unexplained."""
        return float(np.mean(self.mechanism == UNEXPLAINED)) if len(self) else 0.0

    def summary(self) -> str:
        """One sentence: counts, unexplained fraction and, when a rise is explained, the mean
        coincidence of the explanations (over the explained rises only)."""
        c = self.counts()
        expl = self.mechanism != UNEXPLAINED
        chance = float(np.mean(self.coincidence[expl])) if expl.any() else 0.0
        def n(k: int, one: str, many: str) -> str:
            return f"{k} {one if k == 1 else many}"

        head = (f"{n(len(self), 'rise', 'rises')}: "
                f"{n(c[FORCED], 'forced resonance', 'forced resonances')}, "
                f"{n(c[PARAMETRIC], 'parametric instability', 'parametric instabilities')}, "
                f"{c[UNEXPLAINED]} unexplained "
                f"({100 * self.unexplained_fraction:.0f} %)")
        k = int(expl.sum())
        if not k:  # no explanation: no chance of a coincidence to state
            return head
        return (head + f"; a random rise would get such an explanation with a chance of "
                f"{100 * chance:.0f} %"
                + (f" on average over the {k} explained rises" if k > 1
                   else " (the explained rise)"))

    def evidence(self) -> list[tuple[str, str, int, float]]:
        """Per explaining cause family: ``(mechanism, mode, rises, joint chance)``.

        The joint chance is the product of the rows' coincidence probabilities: how likely it
        is that all these rises got their explanation by accident.
        """
        out = []
        for mech in (FORCED, PARAMETRIC):
            for mode in sorted({str(m) for m, x in zip(self.mode, self.mechanism, strict=True)
                                if x == mech}):
                sel = (self.mechanism == mech) & (self.mode == mode)
                out.append((mech, mode, int(sel.sum()),
                            float(np.prod(np.clip(self.coincidence[sel], 0.0, 1.0)))))
        return out

    def to_dataset(self):
        """Table as :class:`xarray.Dataset` (dimension ``resonance``; crossings as ``crossing``).
        """
        import xarray as xr

        def v(x, units, long_name, dim="resonance"):
            return (dim, x, {"units": units, "long_name": long_name})

        cr = self.crossings
        ds = xr.Dataset(
            {
                "speed": v(self.rpm, "min-1", "speed of the rise"),
                "time": v(self.time, "s", "time of the rise"),
                "frequency": v(self.frequency, "Hz", "response frequency"),
                "f_mesh": v(self.f_mesh, "Hz", "mesh frequency"),
                "order": v(self.order, "1", "mesh harmonic of the ray (0: none)"),
                "feature": v(self.feature.astype(str), "1", "feature the rise lies on"),
                "mechanism": v(self.mechanism.astype(str), "1", "classified mechanism"),
                "mode": v(self.mode.astype(str), "1", "natural frequency involved"),
                "cause": v(self.cause.astype(str), "1", "cause of the rise"),
                "predicted_speed": v(self.predicted_rpm, "min-1", "speed the cause predicts"),
                "strength_db": v(self.strength_db, "dB", "rise above its track or background"),
                "coincidence": v(self.coincidence, "1",
                                 "chance that a random rise gets this explanation"),
                "note": v(self.note.astype(str), "1", "evidence"),
                "group": v(np.asarray(self.groups, dtype=object).astype(str), "1",
                           "mesh frequency of the ray the rise lies on"),
                "crossing_harmonic": v(np.asarray([c.harmonic for c in cr], dtype=int), "1",
                                       "mesh harmonic of a predicted crossing", "crossing"),
                "crossing_mode": v(np.asarray([c.mode for c in cr], dtype=str), "1",
                                   "natural frequency of a predicted crossing", "crossing"),
                "crossing_speed": v(np.asarray([c.rpm for c in cr], dtype=float), "min-1",
                                    "predicted crossing speed", "crossing"),
                "crossing_status": v(np.asarray([c.status for c in cr], dtype=str), "1",
                                     "what the map shows there", "crossing"),
                "crossing_group": v(np.asarray([c.group for c in cr], dtype=str), "1",
                                    "mesh frequency of a predicted crossing", "crossing"),
            },
            coords={"resonance": ("resonance", np.arange(len(self)),
                                  {"units": "1", "long_name": "rise index"}),
                    "crossing": ("crossing", np.arange(len(cr)),
                                 {"units": "1", "long_name": "crossing index"})},
            attrs={"mesh_frequency_per_rpm": self.mesh_frequency_per_rpm,
                   "settle_time": self.settle_time, "summary": self.summary(),
                   "notes": " | ".join(self.notes)},
        )
        return cf_dataset(
            ds, title="run-up resonances",
            producer="analysis.instability.detect_resonances"
        )

    def __str__(self) -> str:
        lines = [f"{'speed':>7} {'f [Hz]':>8} {'k':>3} {'feature':>17} {'dB':>5} {'chance':>6}"
                 "  mechanism: cause"]
        for r in range(len(self)):
            cause = f": {self.cause[r]}" if self.cause[r] else ""
            lines.append(f"{self.rpm[r]:7.0f} {self.frequency[r]:8.1f} {self.order[r]:3d} "
                         f"{self.feature[r]:>17} {self.strength_db[r]:5.1f} "
                         f"{100 * self.coincidence[r]:5.0f}%  {self.mechanism[r]}{cause}")
        lines.append(self.summary())
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(lines)

    def plot(self, map_ds=None, ax=None, **kwargs: Any):
        """Rises over the rpm-frequency map (delegates to ``plots.plot_resonances``)."""
        from analysis.instability.plots import plot_resonances

        return plot_resonances(self, map_ds, ax=ax, **kwargs)


_ROW_FIELDS = ("time", "rpm", "frequency", "f_mesh", "order", "mechanism", "mode",
               "strength_db", "note", "feature", "cause", "predicted_rpm", "coincidence")


def merge_mesh_frequencies(parts: Sequence[tuple[str, Resonances]], *,
                           rpm_tolerance: float, frequency_tolerance: float) -> Resonances:
    """The rises of one map classified against several mesh frequencies, in one table.

    :func:`detect_resonances` tracks the rays of one mesh frequency per call. For a gear set
    with several (two stages, the two toothings of a Wolfrom planet) call it once per mesh
    frequency and merge the results here:

    * rises on the rays of a mesh frequency come from its own call (harmonic ``k`` of that mesh
      frequency; ``group`` names it, and the cause gets ``" [name]"``);
    * rises along the natural frequencies and isolated spots are found by every call, each
      leaving out its own rays: such a rise is kept only when every call found it (within
      ``rpm_tolerance`` and ``frequency_tolerance``) -- it then lies off every ray -- with the
      first call's classification;
    * the predicted crossings of every mesh frequency are listed, each with its ``group``;
      the growth table is the first call's (the same chart); the notes are merged.

    Parameters
    ----------
    parts : sequence of (str, Resonances)
        Name of each mesh frequency and its :func:`detect_resonances` result, reference first.
    rpm_tolerance : float
        Speeds of the same rise in two calls differ by at most this [min-1] (a frame).
    frequency_tolerance : float
        Frequencies of the same rise differ by at most this [Hz] (a resolution cell).

    Returns
    -------
    Resonances
        Sorted by speed, then frequency.
    """
    if not isinstance(parts, list | tuple):
        raise TypeError(f"parts must be a sequence of (name, Resonances) pairs; got "
                        f"{type(parts).__name__}")
    if not parts:
        raise ValueError("parts is empty: give one (name, Resonances) per mesh frequency")
    for k, part in enumerate(parts):
        if not isinstance(part, tuple | list) or len(part) != 2 or not isinstance(part[0], str):
            raise TypeError(f"parts[{k}] must be a (name, Resonances) pair")
        require_instance(part[1], Resonances, f"parts[{k}][1]")
    for name, value in (("rpm_tolerance", rpm_tolerance),
                        ("frequency_tolerance", frequency_tolerance)):
        require_positive(require_real(value, name), name, allow_zero=True)
    if len(parts) == 1:
        return parts[0][1]
    rows: list[tuple[str, Resonances, int]] = []
    first = parts[0][1]
    for name, res in parts:
        for i in np.flatnonzero(res.order > 0):
            rows.append((name, res, int(i)))
    for i in np.flatnonzero(first.order == 0):
        ok = all(
            np.any((other.order == 0)
                   & (np.abs(other.rpm - first.rpm[i]) <= rpm_tolerance)
                   & (np.abs(other.frequency - first.frequency[i]) <= frequency_tolerance))
            for _, other in parts[1:])
        if ok:
            rows.append(("", first, int(i)))
    rows.sort(key=lambda r: (float(r[1].rpm[r[2]]), float(r[1].frequency[r[2]])))
    kw: dict[str, Any] = {}
    for f in _ROW_FIELDS:
        values = [getattr(res, f)[i] for _, res, i in rows]
        dtype = getattr(first, f).dtype if len(first) else (
            object if f in ("mechanism", "mode", "note", "feature", "cause") else float)
        kw[f] = np.asarray(values, dtype=dtype)
    if rows:
        kw["cause"] = np.asarray([
            (f"{res.cause[i]} [{name}]" if name and res.cause[i] else str(res.cause[i]))
            for name, res, i in rows], dtype=object)
    crossings = tuple(dataclasses.replace(c, group=name) for name, res in parts
                      for c in res.crossings)
    notes = tuple(dict.fromkeys(
        (f"{name}: {n}" if n.startswith("rays analysed") else n)
        for name, res in parts for n in res.notes))
    return Resonances(**kw, mesh_frequency_per_rpm=first.mesh_frequency_per_rpm,
                      crossings=crossings, growth=first.growth,
                      settle_time=max(r.settle_time for _, r in parts), notes=notes,
                      group=np.asarray([name for name, _, _ in rows], dtype=object))


# ------------------------------------------------------------------------------ helpers


def _segments(mask: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` runs of True."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True))


def _track(level: np.ndarray, axis: np.ndarray, centre: np.ndarray, half: np.ndarray,
           frames: np.ndarray) -> np.ndarray:
    """Maximum level inside ``centre ± half`` for every frame (NaN outside ``frames``)."""
    out = np.full(level.shape[0], np.nan)
    lo = np.searchsorted(axis, centre - half, side="left")
    hi = np.searchsorted(axis, centre + half, side="right")
    for i in np.flatnonzero(frames):
        a, b = int(lo[i]), int(hi[i])
        if b <= a:  # narrower than one bin: nearest bin
            a = int(np.clip(np.searchsorted(axis, centre[i]), 0, axis.size - 1))
            b = a + 1
        out[i] = float(level[i, a:b].max())
    return out


def _rises(track: np.ndarray, threshold: float) -> list[tuple[int, float, int, int]]:
    """Peaks of a track with prominence >= threshold: (index, prominence, -3 dB left, right).

    The threshold is raised to 4 x the noise of the track (the robust spread of its frame-to-
    frame changes), so that a noisy track does not produce rises by chance.
    """
    out = []
    fin = track[np.isfinite(track)]
    if fin.size > 8:
        d = np.diff(fin)
        noise = 1.4826 * float(np.median(np.abs(d - np.median(d)))) / np.sqrt(2.0)
        threshold = max(threshold, 4.0 * noise)
    for a, b in _segments(np.isfinite(track)):
        if b - a < 3:
            continue
        y = track[a:b]
        idx, props = scipy.signal.find_peaks(y, prominence=threshold)
        for j, p in zip(idx, props["prominences"], strict=True):
            top = y[j] - 3.0
            lft = j
            while lft > 0 and y[lft - 1] >= top:
                lft -= 1
            rgt = j
            while rgt < y.size - 1 and y[rgt + 1] >= top:
                rgt += 1
            out.append((a + int(j), float(p), a + lft, a + rgt))
    return out


def _settle_time(lv: MapLevels, band: np.ndarray, frames: np.ndarray, threshold: float
                 ) -> tuple[float, str]:
    """Frames whose window reaches the record start, and a decaying start transient."""
    t0 = float(lv.time[0]) - 0.5 * lv.frame_duration  # start of the record
    t_set = t0 + lv.frame_duration
    why = "frames whose window reaches back to the start of the record"
    t_end = float(lv.time[-1]) + 0.5 * lv.frame_duration
    idx = np.flatnonzero(frames & (lv.time >= t_set) & (lv.time <= t0 + 0.1 * (t_end - t0)))
    if idx.size > 8:
        b = np.median(lv.level[idx][:, band], axis=1)
        b = scipy.ndimage.uniform_filter1d(b, 3, mode="nearest")
        floor = float(np.quantile(b, 0.1))
        if b[0] > floor + threshold:  # the broadband level decays from a start transient
            k = int(np.argmax(b <= floor + 0.5 * threshold))
            t_set = float(lv.time[idx[k]])
            why = (f"a decaying start transient (broadband level {b[0] - floor:.0f} dB above "
                   "its floor)")
    return t_set, why


# ------------------------------------------------------------------------------ detection


def detect_resonances(
    map_ds: Any,
    *,
    natural_frequencies_hz: Any,
    mesh_frequency_per_rpm: float,
    orders: Iterable[int] | None = None,
    names: Sequence[str] | None = None,
    candidates: Candidates | None = None,
    chart: Any = None,
    mode_families: Sequence[tuple[str, int]] | None = None,
    mesh_harmonic_rule: MeshPhasingRule | None = None,
    features: Any = None,
    speed_profile: tuple[Any, Any] | None = None,
    threshold_db: float = 6.0,
    growth_threshold_db: float = 20.0,
    natural_uncertainty: float = 0.05,
    settle_time: float | None = None,
    frequency_range: tuple[float, float] | None = None,
    dynamic_range_db: float = 40.0,
    neighbourhood: tuple[int, int] = (5, 5),
    repeat_rtol: float = 1e-6,
    variable: str = "amplitude",
) -> Resonances:
    """Detect the amplitude rises of an rpm-frequency map and classify their mechanism.

    Parameters
    ----------
    map_ds : xarray.Dataset
        ``amplitude(time, frequency)`` with coordinates ``time`` [s], ``frequency`` [Hz] and
        ``rpm(time)`` [min-1] (:meth:`analysis.maps.RpmFrequencyMap.to_dataset`); linear, or
        in dB with the attribute ``scale="dB"``.
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0).
    mesh_frequency_per_rpm : float
        Mesh frequency per speed of the map's rpm [Hz per min-1]; for a set with several mesh
        frequencies use the one of interest (or call once per mesh).
    orders : iterable of int, optional
        Mesh harmonics whose rays are tracked (default: every harmonic inside the map).
    names : sequence of str, optional
        Natural-frequency names (default ``f1, f2, ...``).
    candidates : Candidates, optional
        Theory candidates (with selection rules); used for parametric rises when no ``chart``.
    chart : StabilityChart, optional
        Floquet chart over speed: its unstable bands and growth rates decide whether a rise
        can be a parametric instability in this run (see ``growth_threshold_db``).
    mode_families : sequence of (str, int), optional
        Per natural frequency ``(kind, p)`` (rotational 0, translational 1, planet ``j``); with
        ``mesh_harmonic_rule`` it tells which mesh harmonics force which modes.
    mesh_harmonic_rule : MeshPhasingRule, optional
        Planetary mesh-phasing rule: harmonic ``k`` forces the family ``p`` only if
        ``k z_s = +-p (mod N)``. A rise at a crossing the rule forbids is not a forced
        resonance (parametric if it sits in a growing band, else unexplained).
    features : MapFeatures, optional
        Features of the same map (:func:`analysis.runup.map_features`): its frequency-locked
        lines that no natural frequency explains (structural resonances outside the model) are
        treated like natural frequencies named ``"line 2100 Hz"``.
    speed_profile : (array_like, array_like), optional
        ``(time [s], rpm [min-1])`` of the run for the growth (default: the map's frames).
    threshold_db : float
        Smallest rise counted [dB].
    growth_threshold_db : float
        Growth a band must allow during this run to explain a rise as parametric [dB].
    natural_uncertainty : float
        Relative uncertainty of the natural frequencies: the crossing speed tolerance and the
        width of the frequency-locked tracks (the effective natural frequencies of a run shift
        with contact loss and sweep rate).
    settle_time : float, optional
        Leave out frames before this time [s] (default: automatic, see the module notes).
    frequency_range : (float, float), optional
        Analysed band [Hz] (default: 0.15 x the lowest natural frequency to the top of the map).
    dynamic_range_db : float
        Rises more than this below the map maximum are background and not counted.
    neighbourhood : (int, int)
        Local-maximum window (frames, bins) of the isolated spots.
    repeat_rtol : float
        Natural frequencies equal within this relative tolerance are one degenerate cluster.
    variable : str
        Name of the map variable.

    Returns
    -------
    Resonances
    """
    lv = map_levels(map_ds, variable=variable)
    if lv.axis_name != "frequency":
        raise ValueError("detect_resonances needs an rpm-frequency map (dims time, frequency)")
    fn_all = natural_frequencies(natural_frequencies_hz)
    factor = require_positive(mesh_frequency_per_rpm, "mesh_frequency_per_rpm")
    thr = require_positive(threshold_db, "threshold_db")
    gthr = require_positive(growth_threshold_db, "growth_threshold_db")
    u_fn = require_positive(natural_uncertainty, "natural_uncertainty", allow_zero=True)
    dyn = require_positive(dynamic_range_db, "dynamic_range_db")
    labels = list(names) if names is not None else [f"f{i + 1}" for i in range(fn_all.size)]
    if len(labels) != fn_all.size:
        raise ValueError(f"names has {len(labels)} entries; natural_frequencies_hz has "
                         f"{fn_all.size}")
    nb = tuple(int(x) for x in neighbourhood)
    if len(nb) != 2 or min(nb) < 1:
        raise ValueError(f"neighbourhood = {neighbourhood!r} is not admissible: two integers >= 1")
    # degenerate clusters: one line per cluster, named "f3=f4"
    rtol = require_positive(repeat_rtol, "repeat_rtol", allow_zero=True)
    order_fn = np.argsort(fn_all, kind="stable")
    clusters: list[list[int]] = []
    for i in order_fn:
        if clusters and abs(fn_all[i] - fn_all[clusters[-1][0]]) <= rtol * fn_all[i]:
            clusters[-1].append(int(i))
        else:
            clusters.append([int(i)])
    fn = np.asarray([fn_all[c].mean() for c in clusters])
    fnames = ["=".join(labels[i] for i in c) for c in clusters]
    fam_p = None
    if mesh_harmonic_rule is not None:
        if mode_families is None or len(mode_families) != fn_all.size:
            raise ValueError("mesh_harmonic_rule needs mode_families, one (kind, p) per natural "
                             "frequency")
        fam_p = [mesh_harmonic_rule.check_family(tuple(x)) for x in mode_families]
    if features is not None:
        # frequency-locked lines the map shows that no natural frequency explains (structural
        # resonances outside the model): they get crossings and tracks of their own
        res_hz = float(map_ds.attrs.get("resolution_hz", 0.0))
        extra = [float(v) for v in np.atleast_1d(features.frequencies)
                 if np.all(np.abs(v - fn) > u_fn * fn + res_hz)]
        fn = np.concatenate([fn, extra])
        fnames += [f"line {v:.0f} Hz" for v in extra]
        clusters += [[] for _ in extra]

    def excited(k: int, c: int) -> bool:
        """Does mesh harmonic ``k`` force cluster ``c`` (True without a rule, or for a line of
        the map that is not a mode of the model)?"""
        if fam_p is None or mesh_harmonic_rule is None or not clusters[c]:
            return True
        n_pl = mesh_harmonic_rule.n_planets
        forced = set(mesh_harmonic_rule.forced_harmonics(k))
        return any(min(fam_p[i] % n_pl, (-fam_p[i]) % n_pl) in forced for i in clusters[c])

    f, level, rpm, t = lv.axis, lv.level, lv.rpm, lv.time
    if frequency_range is None:
        f_lo, f_hi = 0.15 * float(fn.min()), float(f[-1])
    else:
        f_lo, f_hi = (float(x) for x in frequency_range)
        if not (np.isfinite(f_lo) and np.isfinite(f_hi) and 0 <= f_lo < f_hi):
            raise ValueError(f"frequency_range = {frequency_range!r} is not admissible: "
                             "0 <= low < high")
    band = (f >= f_lo) & (f <= f_hi)
    if band.sum() < 3:
        raise ValueError(f"frequency_range {f_lo:g}–{f_hi:g} Hz holds fewer than 3 map lines")
    fmesh = factor * rpm
    moving = rpm > 0.02 * float(rpm.max()) if rpm.max() > 0 else np.zeros(rpm.size, bool)
    notes: list[str] = []
    if settle_time is None:
        t_set, why = _settle_time(lv, band, moving, thr)
    else:
        t_set, why = float(settle_time), "given"
    frames = moving & (t >= t_set)
    if frames.sum() < 3:
        raise ValueError("fewer than 3 frames left after the settling time and at speed > 0")
    notes.append(f"frames before {t_set:.4g} s left out ({why})")
    floor = float(level[frames][:, band].max()) - dyn
    # ray widths (resolution + sweep within a frame) of harmonic k: w(k) per frame
    k_max = int(np.floor(f_hi / max(float(fmesh[frames].min()), 1e-300)))
    k_all = [int(k) for k in orders] if orders is not None else list(range(1, k_max + 1))
    if not k_all or any(k < 1 for k in k_all):
        raise ValueError(f"orders = {orders!r} is not admissible: positive integers")
    k_track = max(k_all)
    k_top = max(k_track, k_max)  # every harmonic inside the map (masks of crossings and rays)
    # harmonic k is the shaft order 60 h k of the map's speed channel
    width = lv.ray_half_width(60.0 * factor * np.arange(1, k_top + 2, dtype=float))

    def w(k: int) -> np.ndarray:
        return width[k - 1]

    # quasi-static start: neighbouring mesh orders overlap at the first harmonic
    resolved_any = fmesh > w(1) + w(2)
    if frames.any() and not (resolved_any[frames]).all():
        r_q = float(rpm[frames & ~resolved_any].max())
        notes.append(f"below {r_q:.0f} min-1 the mesh orders are closer than the map "
                     "resolution (quasi-static start: free vibration after every tooth-pair "
                     "change); not analysed")
    frames_res = frames & resolved_any
    u_rate = 0.5 * np.abs(lv.rate) * lv.frame_duration  # speed change within half a frame

    # growth of the Floquet-unstable bands along this run
    growth = None
    if chart is not None:
        if speed_profile is not None:
            tp, rp = speed_profile
        else:
            tp, rp = t, rpm
        # the bands keep the chart's labels (one attribution, see attribute_region)
        growth = runup_growth(chart, tp, rp, threshold_db=gthr)
        for i in range(len(growth)):
            state = (f"grows by {growth.growth_db[i]:.0f} dB (time in band "
                     f"{1e3 * growth.time_in_band[i]:.1f} ms x growth rate <= "
                     f"{growth.peak_growth_rate[i]:.3g}/s)")
            if not growth.can_grow[i]:
                state += f": too fast to develop; {growth.advice[i]}"
            notes.append(f"unstable band {growth.lower_rpm[i]:.0f}–{growth.upper_rpm[i]:.0f} "
                         f"min-1 ({growth.label[i] or 'unattributed'}): {state}")

    def developing_band(r: float) -> tuple[int | None, str]:
        """Band containing ``r`` (with a speed tolerance) that grows enough in this run."""
        if growth is None:
            return None, ""
        for i in range(len(growth)):
            tol = 0.5 * (growth.upper_rpm[i] - growth.lower_rpm[i]) + float(np.interp(
                r, rpm, u_rate))
            if growth.lower_rpm[i] - tol <= r <= growth.upper_rpm[i] + tol:
                if growth.can_grow[i]:
                    return i, ""
                return None, (f"inside unstable band {growth.lower_rpm[i]:.0f}–"
                              f"{growth.upper_rpm[i]:.0f} min-1, but it grows only "
                              f"{growth.growth_db[i]:.0f} dB in this run")
        return None, ""

    rows: list[dict] = []

    # ---- 1. rises along the mesh-order rays ------------------------------------------------
    ray_frames: dict[int, np.ndarray] = {}
    for k in k_all:
        fk = k * fmesh
        ok = (frames_res & (fmesh > w(k) + w(k + 1)) & (fk - w(k) >= f_lo)
              & (fk + w(k) <= f_hi))
        if ok.sum() < 5:
            continue
        ray_frames[k] = ok
        tr = _track(level, f, fk, w(k), ok)
        for i, prom, a, b in _rises(tr, thr):
            if tr[i] < floor:
                continue
            rows.append({"i": i, "freq": float(fk[i]), "order": k, "feature": "ray",
                         "strength": prom, "r_lo": float(rpm[a]), "r_hi": float(rpm[b])})
    analysed = {k: (float(rpm[m].min()), float(rpm[m].max())) for k, m in ray_frames.items()}
    if analysed:
        notes.append("rays analysed where resolved: " + ", ".join(
            f"k={k} {lo:.0f}–{hi:.0f}" for k, (lo, hi) in sorted(analysed.items())))

    # ---- 2. rises along the natural frequencies, off the ray crossings -----------------------
    for c, fc in enumerate(fn):
        half = u_fn * fc + 0.5 * lv.resolution
        crossing = np.zeros(rpm.size, dtype=bool)
        for k in range(1, k_top + 1):
            crossing |= np.abs(k * fmesh - fc) <= w(k) + half
        ok = frames_res & ~crossing & (fc - half >= f_lo) & (fc + half <= f_hi)
        if ok.sum() < 5:
            continue
        centre = np.full(rpm.size, fc)
        tr = _track(level, f, centre, np.full(rpm.size, half), ok)
        for i, prom, a, b in _rises(tr, thr):
            if tr[i] < floor:
                continue
            j0, j1 = np.searchsorted(f, [fc - half, fc + half])
            jf = int(j0 + np.argmax(level[i, j0:max(j1, j0 + 1)]))
            rows.append({"i": i, "freq": float(f[min(jf, f.size - 1)]), "order": 0,
                         "feature": "natural frequency", "strength": prom,
                         "r_lo": float(rpm[a]), "r_hi": float(rpm[b]), "cluster": c})

    # ---- 3. isolated spots off every ray and natural frequency --------------------------------
    # incoherent smoothing over one frame length and one resolution cell, then the rise above
    # the median over time; the threshold adapts to the spread of that rise (noise maps)
    hop = float(np.median(np.diff(t))) if t.size > 1 else lv.frame_duration
    n_t = max(1, round(lv.frame_duration / max(hop, 1e-300)))
    n_f = max(1, round(lv.resolution / float(np.median(np.diff(f)))))
    smooth = scipy.ndimage.uniform_filter(level, size=(n_t, n_f), mode="nearest")
    med = np.median(smooth[frames_res], axis=0) if frames_res.any() else np.zeros(f.size)
    rise = smooth - med[None, :]
    sel = rise[frames_res][:, band] if frames_res.any() else rise[:, band]
    spread = 1.4826 * float(np.median(np.abs(sel - np.median(sel)))) if sel.size else 0.0
    thr_spot = max(thr, 5.0 * spread)
    if thr_spot > thr:
        notes.append(f"isolated spots need {thr_spot:.1f} dB (5 x the spread of the map "
                     "background)")
    # a maximum within one frame length of the first analysed frame is the tail of whatever
    # happened before (a start transient), not a rise
    first = float(t[frames_res].min()) if frames_res.any() else float(t[0])
    inner = frames_res & (t >= first + lv.frame_duration)
    peaks = (rise == scipy.ndimage.maximum_filter(rise, size=nb, mode="nearest")) & (
        rise >= thr_spot) & (level >= floor) & inner[:, None] & band[None, :]
    near = np.zeros_like(peaks)
    for k in range(1, k_top + 1):
        near |= np.abs(f[None, :] - k * fmesh[:, None]) <= 2 * w(k)[:, None] + lv.resolution
    for fc in fn:
        near |= (np.abs(f - fc) <= u_fn * fc + lv.resolution)[None, :]
    lab, n_lab = scipy.ndimage.label(peaks & ~near)
    for comp in range(1, n_lab + 1):
        ii, jj = np.nonzero(lab == comp)
        m = int(np.argmax(rise[ii, jj]))
        rows.append({"i": int(ii[m]), "freq": float(f[jj[m]]), "order": 0, "feature": "spot",
                     "strength": float(rise[ii[m], jj[m]]), "r_lo": float(rpm[ii[m]]),
                     "r_hi": float(rpm[ii[m]])})

    # ---- classification --------------------------------------------------------------------
    r_all = rpm[frames_res] if frames_res.any() else rpm[frames]
    r_min, r_max = float(r_all.min()), float(r_all.max())

    def cross_windows(half_width: float, ks: Iterable[int]) -> tuple[np.ndarray, np.ndarray]:
        cen, hw = [], []
        for kk in ks:
            for fc in fn:
                rc = fc / (kk * factor)
                cen.append(rc)
                hw.append(half_width + u_fn * rc + float(np.interp(rc, rpm, u_rate)))
        return np.asarray(cen), np.asarray(hw)

    direct_hits: dict[tuple[int, int], float] = {}
    for row in rows:
        row.update(mechanism=UNEXPLAINED, mode="", cause="", pred=np.nan, note="", chance=0.0)
        if row["feature"] != "ray":
            continue
        k, i = row["order"], row["i"]
        r0 = float(rpm[i])
        best = None
        for c, fc in enumerate(fn):
            rc = fc / (k * factor)
            tol = u_fn * rc + float(np.interp(rc, rpm, u_rate))
            if row["r_lo"] - tol <= rc <= row["r_hi"] + tol and (
                    best is None or abs(rc - r0) < abs(best[1] - r0)):
                best = (c, rc)
        if best is not None:
            c, rc = best
            evidence = (f"ray k={k} crosses {fnames[c]} = {fn[c]:.0f} Hz at {rc:.0f} min-1; "
                        f"rise {row['strength']:.1f} dB at {r0:.0f} min-1 (-3 dB range "
                        f"{row['r_lo']:.0f}–{row['r_hi']:.0f})")
            bi, _ = developing_band(r0)
            band_txt = "" if bi is None or growth is None else (
                f"; also inside the unstable band {growth.lower_rpm[bi]:.0f}–"
                f"{growth.upper_rpm[bi]:.0f} min-1 ({growth.label[bi]}), which grows "
                f"{growth.growth_db[bi]:.0f} dB in this run")
            if excited(k, c):
                row.update(mechanism=FORCED, mode=fnames[c], cause=f"{k} f_mesh = {fnames[c]}",
                           pred=rc, note=evidence + band_txt)
                direct_hits[(k, c)] = max(direct_hits.get((k, c), 0.0), row["strength"])
            elif bi is not None and growth is not None:
                row.update(mechanism=PARAMETRIC, mode=fnames[c],
                           cause=str(growth.label[bi]) or "Floquet band", pred=rc,
                           note=(evidence + f"; harmonic {k} does not force {fnames[c]} (mesh "
                                 "phasing)" + band_txt))
                row["parametric_band"] = bi
            else:
                row.update(mode=fnames[c], pred=rc,
                           note=(evidence + f"; but harmonic {k} does not force {fnames[c]} "
                                 "(mesh phasing) and no unstable band grows here"))
    events = [(r["pred"], 0.5 * (r["r_hi"] - r["r_lo"]), r["order"], r["mode"])
              for r in rows if r["mechanism"] == FORCED]
    for row in rows:
        if row["feature"] != "ray" or row["mechanism"] != UNEXPLAINED:
            continue
        k, i = row["order"], row["i"]
        r0 = float(rpm[i])
        options = []
        for rc, _, kk, mode in events:
            if kk == k:
                continue
            tol = u_fn * rc + float(np.interp(rc, rpm, u_rate))
            if row["r_lo"] - tol <= rc <= row["r_hi"] + tol:
                options.append((abs(rc - r0), kk, mode, rc))
        if options:
            _, kk, mode, rc = min(options)
            row.update(mechanism=FORCED, mode=mode, cause=f"{kk} f_mesh = {mode}", pred=rc,
                       coupled=True,
                       note=(f"on ray k={k} at the forced resonance of ray k={kk} with {mode} "
                             f"({rc:.0f} min-1): the same resonance seen through the "
                             f"mesh-stiffness modulation (f_i {k - kk:+d} f_mesh)"))
    for row in rows:
        i = row["i"]
        r0, fm0 = float(rpm[i]), float(fmesh[i])
        if row["feature"] == "ray":
            k = row["order"]
            lo_k, hi_k = analysed.get(k, (r_min, r_max))
            hw = 0.5 * (row["r_hi"] - row["r_lo"])
            cen, hwid = cross_windows(hw, [k])  # the ray's own crossings
            if row.get("coupled") or row["mechanism"] == UNEXPLAINED:
                # ... plus the confirmed resonances of the other rays
                ev = [(rc, h + u_fn * rc + float(np.interp(rc, rpm, u_rate)))
                      for rc, h, kk, _ in events if kk != k]
                if ev:
                    cen = np.concatenate([cen, [e[0] for e in ev]])
                    hwid = np.concatenate([hwid, [hw + e[1] for e in ev]])
            row["chance"] = covered_fraction(cen, hwid, lo_k, hi_k)
            if row["mechanism"] == PARAMETRIC and growth is not None:
                q = row["parametric_band"]
                row["chance"] = covered_fraction(
                    np.asarray([0.5 * (growth.lower_rpm[q] + growth.upper_rpm[q])]),
                    np.asarray([growth.upper_rpm[q] - growth.lower_rpm[q] + hw]), lo_k, hi_k)
            if row["mechanism"] == UNEXPLAINED and not row["note"]:
                _, why = developing_band(r0)
                row["note"] = why or "no crossing of a mesh harmonic with a natural frequency"
            continue
        # frequency-locked rises and spots: parametric if a growing band (or a candidate)
        targets = []
        for c, fc in enumerate(fn):
            for j in range(-3, 4):
                if abs(row["freq"] - abs(fc + j * fm0)) <= u_fn * fc + lv.resolution:
                    targets.append((abs(j), c, j))
        if row["feature"] == "natural frequency":
            targets = [(0, row["cluster"], 0)]
        bi, why = developing_band(r0)
        if growth is not None:
            mid = [0.5 * (growth.lower_rpm[q] + growth.upper_rpm[q]) for q in range(len(growth))
                   if growth.can_grow[q]]
            hws = [0.5 * (growth.upper_rpm[q] - growth.lower_rpm[q]) for q in range(len(growth))
                   if growth.can_grow[q]]
            row["chance"] = covered_fraction(np.asarray(mid), np.asarray(hws) * 2, r_min, r_max)
        if bi is not None and growth is not None and targets:
            _, c, j = min(targets)
            lab_b = str(growth.label[bi]) or "Floquet band"
            row.update(mechanism=PARAMETRIC, mode=fnames[c], cause=lab_b,
                       pred=0.5 * (growth.lower_rpm[bi] + growth.upper_rpm[bi]),
                       note=(f"response at {fnames[c]}" + (f" {j:+d} f_mesh" if j else "")
                             + f" inside the unstable band {growth.lower_rpm[bi]:.0f}–"
                               f"{growth.upper_rpm[bi]:.0f} min-1, which grows by "
                               f"{growth.growth_db[bi]:.0f} dB in this run"))
        elif growth is None and candidates is not None and targets:
            hit = None
            for q in range(len(candidates)):
                if not candidates.allowed[q] or candidates.kind[q] not in ("principal", "sum"):
                    continue
                rc = float(candidates.f_mesh_hz[q]) / factor
                dl = u_fn * rc + float(np.interp(rc, rpm, u_rate))
                err = abs(rc - r0)
                if row["r_lo"] - dl <= rc <= row["r_hi"] + dl and (hit is None or err < hit[0]):
                    hit = (err, q)
            if hit is not None:
                q = hit[1]
                _, c, j = min(targets)
                row.update(mechanism=PARAMETRIC, mode=fnames[c], cause=str(candidates.label[q]),
                           pred=float(candidates.f_mesh_hz[q]) / factor,
                           note=(f"f_mesh ≈ {candidates.label[q]} (theory candidate; growth "
                                 "not checked without a Floquet chart)"))
                row["chance"] = covered_fraction(
                    candidates.f_mesh_hz[candidates.allowed] / factor,
                    u_fn * candidates.f_mesh_hz[candidates.allowed] / factor, r_min, r_max)
        if row["mechanism"] == UNEXPLAINED:
            row["note"] = why or ("frequency-locked rise at " + fnames[row["cluster"]]
                                  if row["feature"] == "natural frequency" else
                                  "off every ray and natural frequency") + \
                " (no ray crossing, no growing unstable band)"
            if row["feature"] == "natural frequency":
                row["mode"] = fnames[row["cluster"]]

    # ---- predicted crossings and what was found there -----------------------------------------
    crossings = []
    for k in sorted(set(k_all)):
        for c, fc in enumerate(fn):
            rc = fc / (k * factor)
            if not (r_min <= rc <= r_max):
                continue
            if not excited(k, c):
                crossings.append(Crossing(k, fnames[c], float(fc), float(rc),
                                          "not forced (mesh phasing)", np.nan))
            elif k in analysed and analysed[k][0] <= rc <= analysed[k][1]:
                if (k, c) in direct_hits:
                    crossings.append(Crossing(k, fnames[c], float(fc), float(rc), "rise",
                                              direct_hits[(k, c)]))
                else:
                    crossings.append(Crossing(k, fnames[c], float(fc), float(rc), "no rise",
                                              np.nan))
            else:
                crossings.append(Crossing(k, fnames[c], float(fc), float(rc), "not analysed",
                                          np.nan))

    rows.sort(key=lambda r: (rpm[r["i"]], r["freq"]))

    def col(key, dtype):
        return np.asarray([r[key] for r in rows], dtype=dtype)

    idx = np.asarray([r["i"] for r in rows], dtype=int)
    return Resonances(
        time=t[idx] if rows else np.zeros(0), rpm=rpm[idx] if rows else np.zeros(0),
        frequency=col("freq", float), f_mesh=fmesh[idx] if rows else np.zeros(0),
        order=col("order", int), mechanism=col("mechanism", object), mode=col("mode", object),
        strength_db=col("strength", float), note=col("note", object),
        mesh_frequency_per_rpm=factor, feature=col("feature", object),
        cause=col("cause", object), predicted_rpm=col("pred", float),
        coincidence=col("chance", float), crossings=tuple(crossings), growth=growth,
        settle_time=t_set, notes=tuple(notes))
