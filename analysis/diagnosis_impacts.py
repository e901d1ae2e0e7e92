"""Impacts of a local tooth fault: its rate in the envelope and its comb above the mesh band.

A local tooth fault (a crack, a pit, a broken tooth) strikes once per fault period: at every
engagement of the damaged tooth the mesh stiffness and the transmission error jump, and the
impact rings the housing's resonances. Besides the sidebands it raises around the mesh
harmonics (what :mod:`analysis.diagnosis` compares with simulated faults), this gives two
signatures that a healthy gearbox does not have and that need no model of the transfer path
(McFadden & Smith 1985; Randall 2011, ch. 5; the same evidence as for rolling bearings,
Antoni & Randall 2006):

* **The fault rate in the squared envelope** (:func:`impact_check`, method ``envelope``). The
  record is order-tracked on the reference shaft; the order spectrum without the mesh lattice
  (every mesh harmonic ``h z`` of every mesh with ``±span`` orders around it, where the
  mesh's own carrier and planet-pass sidebands lie, and the orders up to ``span``) is
  demodulated (squared envelope ``|x + j H(x)|^2`` of the whole remaining band) and its
  spectrum in orders is divided by its local noise level. The impacts of a fault at order
  ``f`` put lines at ``k f``; the healthy set's modulations (planet pass, shaft rotations)
  stand at the shafts' orders and their combinations, so a family's harmonics within two
  bins of a multiple of a shaft order (``known_orders``) are left out.
* **A comb above the mesh band** (method ``synchronous``). A fault whose rate is a whole
  order of the reference shaft (the fixed ring of a planetary set: ``N`` impacts per carrier
  revolution) repeats exactly with the shaft, so the impacts' ringing of a housing resonance
  above the mesh harmonics stands as a comb of lines at ``k f`` in the order spectrum of the
  whole record (a synchronous average's spectrum: noise averages out, the comb does not).
  The comb is checked from half a mesh order above the highest mesh harmonic present (some
  integer order within ``±span`` of it at least ``present_db`` above the noise; the run of
  present harmonics from the first ends at two absent ones, so that the fault's own comb
  meeting a harmonic position higher up does not take its band) up to the sample rate's
  limit, leaving out ``±span`` around every mesh harmonic position; a record whose mesh
  harmonics reach the top has no such band and no synchronous evidence.

**Chance.** Each line's power over the local mean noise power, ``r = P / (median / ln 2)``
(the running median over ``±width`` orders; for noise, the power of a line is exponentially
distributed, with median ``ln 2`` times its mean), is capped at ``cap`` and summed over the
family's ``n`` lines; the chance that noise reaches that sum is bounded by the upper tail of
the Gamma(``n``, 1) distribution (the sum of ``n`` exponential variables; capping only lowers
the sum). The cap keeps a single strong line (an unexplained tone, an eccentricity's first
harmonic) from carrying the family: with ``cap = 10`` a line adds at most 10, so a family of
10 harmonics needs several lines well above the noise to reach a chance of 1e-4. A family is
*detected* (:attr:`ImpactEvidence.detected`) at a chance of at most :data:`IMPACT_CHANCE`
with at least :data:`MIN_STRONG` lines 6 dB over the noise and, in the envelope, its
strongest lines no more than :data:`MIN_RELATIVE_DB` under the strongest shaft-order line.
The false-positive rates measured on records without the fault are stated in
``docs/diagnosis.md``.

References
----------
McFadden, P. D., Smith, J. D. (1985). An explanation for the asymmetry of the modulation
sidebands about the tooth meshing frequency in epicyclic gear vibration. Proc. IMechE C 199,
65-70.
Antoni, J., Randall, R. B. (2006). The spectral kurtosis: application to the vibratory
surveillance and diagnostics of rotating machines. Mech. Syst. Signal Process. 20, 308-331.
Randall, R. B. (2011). Vibration-based Condition Monitoring. Wiley, ch. 5 (gear and bearing
diagnostics, envelope analysis).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy import ndimage, stats

from analysis.cf import cf_dataset
from analysis.checks import require_int, require_real, require_real_array
from analysis.diagnosis_impact_plots import impact_figure
from analysis.fft import irfft, next_fast_len, rfft
from analysis.resample import resample_to_angle

if TYPE_CHECKING:
    import matplotlib.figure
    import xarray as xr

__all__ = ["IMPACT_CAP", "IMPACT_CHANCE", "IMPACT_HARMONICS", "MIN_RELATIVE_DB",
           "MIN_REVOLUTIONS", "MIN_STRONG",
           "ImpactCheck", "ImpactEvidence", "ImpactFamily", "impact_check"]

IMPACT_CAP = 10.0
"""Largest contribution of one line (its power over the mean noise power) to a family's sum."""

IMPACT_HARMONICS = 10
"""Harmonics of a fault order checked in the envelope."""

IMPACT_CHANCE = 1e-4
"""Chance at or below which a family's impacts count as detected (with a handful of families
per gear set, noise detects one in well under 0.1 % of records)."""

MIN_RELATIVE_DB = -15.0
"""Level of a family's strongest envelope lines (mean of the three largest) relative to the
strongest modulation of the healthy set in the same envelope (the largest line at the first
harmonics of the shaft orders: planet pass, shaft rotations) [dB] below which the family does
not count as detected, however significant: a periodicity that much weaker than the gearbox's
own modulation is no tooth fault's impact."""

STRONG = 4.0
"""A line at least this many times the mean noise power (6 dB; chance e^-4 = 1.8 % for noise)
counts as *strong*."""

MIN_STRONG = 3
"""Strong lines a detected family needs: an impact train fills several harmonics, a single
tone (or one noise peak) only one (as for the bearing families, ``docs/diagnosis.md``)."""

BACKGROUND_DB = 6.0
"""Background (the running median between the whole orders) over the record's noise floor
[dB] around a mesh harmonic at which the harmonic counts as present however smeared its
lines are."""

MIN_REVOLUTIONS = 4
"""Reference revolutions a record must cover for :func:`impact_check`."""

_LN2 = math.log(2.0)
_BACKGROUND = 10.0 ** (BACKGROUND_DB / 10.0)
_MIN_LINES = 3
_MIN_COMB = 10


@dataclass(frozen=True)
class ImpactFamily:
    """A fault's impact rate: ``name`` (e.g. ``"sun_fault"``) and ``fundamental`` [orders]."""

    name: str
    fundamental: float

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise TypeError(f"ImpactFamily name must be a non-empty str; got {self.name!r}")
        f = require_real(self.fundamental, f"family {self.name!r}: fundamental")
        if not 0.0 < f <= 1e6:
            raise ValueError(f"family {self.name!r}: fundamental = {f!r} is not admissible "
                             "(admissible: 0 < orders <= 1e6)")


@dataclass(frozen=True)
class ImpactEvidence:
    """How strongly a family's impact lines stand in a record.

    Attributes
    ----------
    family : str
        Family name.
    fundamental : float
        Its order.
    method : str
        ``"envelope"`` (harmonics in the squared envelope) or ``"synchronous"`` (a comb in the
        order spectrum above the mesh band).
    lines : int
        Lines checked (0: none could be, the chance is 1).
    strong : int
        Lines at least :data:`STRONG` times the mean noise power.
    statistic : float
        Sum of the capped line-to-noise power ratios.
    chance : float
        Upper bound of the chance that noise gives that sum (Gamma tail; 1 without lines).
    relative_db : float
        Envelope: the mean power of the three strongest lines relative to the strongest
        shaft-order line of the envelope (or the noise, if stronger) [dB]; NaN for a
        synchronous comb (its band holds no healthy modulation).
    """

    family: str
    fundamental: float
    method: str
    lines: int
    strong: int
    statistic: float
    chance: float
    relative_db: float = float("nan")

    @property
    def detected(self) -> bool:
        """Chance at most :data:`IMPACT_CHANCE`, at least :data:`MIN_STRONG` strong lines
        and, in the envelope, the lines no more than :data:`MIN_RELATIVE_DB` below the
        healthy set's strongest modulation."""
        return (self.lines > 0 and self.chance <= IMPACT_CHANCE and self.strong >= MIN_STRONG
                and not self.relative_db < MIN_RELATIVE_DB)

    def text(self) -> str:
        """One line for a report."""
        if self.lines == 0:
            return (f"{self.family} (order {self.fundamental:.4g}): no impact lines could be "
                    f"checked ({self.method})")
        where = ("in the squared envelope of the band without the mesh lattice"
                 if self.method == "envelope" else
                 "as a comb in the order spectrum above the mesh band")
        ch = "below 1e-12" if self.chance < 1e-12 else f"{self.chance:.2g}"
        rel = ("" if not np.isfinite(self.relative_db) else
               f", strongest lines {self.relative_db:+.1f} dB from the strongest shaft-order "
               "modulation")
        return (f"{self.family} (order {self.fundamental:.4g}) impacts {where}: {self.strong} "
                f"of {self.lines} lines 6 dB over the noise, mean line-to-noise ratio "
                f"{self.statistic / self.lines:.2f}, chance {ch}{rel}"
                + (" (detected)" if self.detected else ""))


@dataclass(frozen=True)
class ImpactCheck:
    """Result of :func:`impact_check`.

    Attributes
    ----------
    envelope_order : numpy.ndarray
        Orders of the squared envelope spectrum.
    envelope_ratio : numpy.ndarray
        Its power over the local mean noise power (1: noise).
    order : numpy.ndarray
        Orders of the synchronous band (empty when there is none).
    order_ratio : numpy.ndarray
        The order spectrum's power there over the local mean noise power.
    band : tuple of float
        The synchronous band [orders] (``(top, top)`` when the mesh harmonics reach the top).
    evidence : tuple of ImpactEvidence
        One per family, in the order given.
    mesh_orders : tuple of float
        The meshes' orders.
    span : float
        Half-width of the mesh lattice left out [orders].
    revolutions : int
        Reference revolutions analysed (resolution ``1 / revolutions`` orders).
    name : str
        Channel name.
    """

    envelope_order: np.ndarray
    envelope_ratio: np.ndarray
    order: np.ndarray
    order_ratio: np.ndarray
    band: tuple[float, float]
    evidence: tuple[ImpactEvidence, ...]
    mesh_orders: tuple[float, ...]
    span: float
    revolutions: int
    name: str = "x"

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: ``envelope_ratio(envelope_order)``, ``order_ratio(order)`` and one
        row per family (``family`` dimension: fundamental, lines, strong lines, statistic,
        chance, method)."""
        import xarray as xr

        ev = self.evidence
        fam = [e.family for e in ev]
        ds = xr.Dataset(
            {"envelope_ratio": ("envelope_order", self.envelope_ratio, {
                "units": "1", "long_name": "squared envelope order spectrum over its local "
                                           "mean noise power"}),
             "order_ratio": ("order", self.order_ratio, {
                 "units": "1", "long_name": "order spectrum above the mesh band over its "
                                            "local mean noise power"}),
             "fundamental": ("family", np.array([e.fundamental for e in ev], float), {
                 "units": "1", "long_name": "fault order of the family"}),
             "lines": ("family", np.array([e.lines for e in ev], np.int64), {
                 "units": "1", "long_name": "lines checked"}),
             "strong": ("family", np.array([e.strong for e in ev], np.int64), {
                 "units": "1", "long_name": f"lines at least {STRONG:g} times the mean noise "
                                            "power"}),
             "statistic": ("family", np.array([e.statistic for e in ev], float), {
                 "units": "1", "long_name": f"sum of the line-to-noise power ratios capped at "
                                            f"{IMPACT_CAP:g}"}),
             "chance": ("family", np.array([e.chance for e in ev], float), {
                 "units": "1", "long_name": "chance of the sum for noise (Gamma upper "
                                            "bound)"}),
             "relative_level": ("family", np.array([e.relative_db for e in ev], float), {
                 "units": "dB", "long_name": "strongest envelope lines relative to the "
                                             "strongest shaft-order modulation"}),
             "detected": ("family", np.array([e.detected for e in ev], np.int8), {
                 "units": "1", "long_name": "impacts detected (1) or not (0)"}),
             "method": ("family", np.array([e.method for e in ev], dtype=object), {
                 "long_name": "where the lines were checked"})},
            coords={"envelope_order": ("envelope_order", self.envelope_order, {
                        "units": "1", "long_name": "order of the reference shaft"}),
                    "order": ("order", self.order, {
                        "units": "1", "long_name": "order of the reference shaft"}),
                    "family": ("family", np.array(fam, dtype=object), {
                        "long_name": "impact family"})},
            attrs={"synchronous_band_orders": np.array(self.band, float),
                   "mesh_orders": np.array(self.mesh_orders, float),
                   "mesh_span_orders": self.span, "revolutions": self.revolutions,
                   "channel": self.name})
        return cf_dataset(ds, title=f"tooth-fault impact evidence of {self.name}",
                          producer="analysis.diagnosis_impacts.impact_check")

    def plot(self, **kwargs: Any) -> matplotlib.figure.Figure:
        """Figure (see :func:`analysis.diagnosis_impact_plots.impact_figure`)."""
        return impact_figure(self, **kwargs)


def _noise_mean(power: np.ndarray, revolutions: int, width: float) -> np.ndarray:
    """The local mean noise power: the running median over ``±width`` orders over ln 2."""
    n = max(3, round(2 * width * revolutions) | 1)
    n = min(n, max(3, (power.size - 1) | 1))
    return np.maximum(ndimage.median_filter(power, size=n, mode="nearest") / _LN2, 1e-300)


def _chance(ratios: np.ndarray, cap: float) -> tuple[float, float]:
    s = float(np.sum(np.minimum(ratios, cap)))
    return s, float(stats.gamma.sf(s, ratios.size))


def _evidence(fam: ImpactFamily, method: str, ratios: np.ndarray, cap: float,
              reference: float | None = None) -> ImpactEvidence:
    if ratios.size < _MIN_LINES:
        return ImpactEvidence(fam.name, fam.fundamental, method, 0, 0, 0.0, 1.0)
    s, p = _chance(ratios, cap)
    rel = float("nan")
    if reference is not None:
        top3 = float(np.mean(np.sort(ratios)[-3:]))
        rel = 10.0 * math.log10(max(top3, 1e-300) / max(reference, 1.0))
    return ImpactEvidence(fam.name, fam.fundamental, method, int(ratios.size),
                          int(np.sum(ratios >= STRONG)), s, p, rel)


def _is_whole(f: float, tol: float) -> bool:
    return abs(f - round(f)) <= tol and round(f) >= 1


def impact_check(x: Any, fs: float, rpm: Any, *, mesh_orders: Sequence[float],
                 families: Sequence[ImpactFamily], known_orders: Sequence[float] = (),
                 span: float = 4.0, harmonics: int = IMPACT_HARMONICS,
                 cap: float = IMPACT_CAP, present_db: float = 20.0, width: float = 3.0,
                 name: str = "x") -> ImpactCheck:
    """Check every family's impact lines in a record (module docstring).

    Parameters
    ----------
    x : array_like
        The record (1-D, uniform at ``fs``).
    fs : float
        Sample rate [Hz].
    rpm : array_like
        Speed of the reference shaft at every sample [min-1] (> 0).
    mesh_orders : sequence of float
        The meshes' orders (tooth-passing rates in reference orders), at least one.
    families : sequence of ImpactFamily
        The faults' impact rates. A family whose fundamental is a whole order (within
        ``1e-6``) is checked as a synchronous comb above the mesh band, any other in the
        squared envelope.
    known_orders : sequence of float
        The turning shafts' speeds [reference orders] (fixed frame, zeros skipped): their
        multiples are the healthy set's own modulations, left out of the envelope families.
    span : float
        Half-width [orders] of the mesh lattice left out around every mesh harmonic (the
        mesh's own sidebands), and the orders up to it.
    harmonics : int
        Harmonics of a fault order checked in the envelope (1 .. 100).
    cap : float
        Largest contribution of one line to a family's sum (> 1).
    present_db : float
        Level over the noise at which a mesh harmonic counts as present [dB].
    width : float
        Half-width of the running median of the noise level [orders].
    name : str
        Channel name.

    Returns
    -------
    ImpactCheck

    Raises
    ------
    ValueError
        Bad parameters, a speed that is not > 0, or fewer than 4 reference revolutions.
    """
    fs = require_real(fs, "fs")
    if not fs > 0:
        raise ValueError(f"fs = {fs!r} is not admissible (admissible: > 0 Hz)")
    xv = require_real_array(x, "x", ndim=1, min_size=16)
    rv = require_real_array(rpm, "rpm", ndim=1, min_size=16)
    if rv.shape != xv.shape:
        raise ValueError(f"x and rpm need one value per sample (x {xv.shape}, rpm {rv.shape})")
    if not float(np.min(rv)) > 0:
        raise ValueError("rpm: the reference speed must be > 0 throughout")
    meshes = require_real_array(mesh_orders, "mesh_orders", ndim=1, min_size=1, max_abs=1e6)
    if not np.all(meshes > 0):
        raise ValueError("mesh_orders must all be > 0")
    fams = list(families)
    for item in fams:
        if not isinstance(item, ImpactFamily):
            raise TypeError(f"families: {item!r} is not an ImpactFamily")
    known = np.abs(require_real_array(known_orders, "known_orders", ndim=1, min_size=0,
                                      max_abs=1e6))
    known = known[known > 0]
    span = require_real(span, "span")
    if not 0.0 < span <= 1e4:
        raise ValueError(f"span = {span!r} is not admissible (admissible: 0 < orders <= 1e4)")
    harmonics = require_int(harmonics, "harmonics", 1)
    if harmonics > 100:
        raise ValueError(f"harmonics = {harmonics!r} is not admissible (admissible: 1 .. 100)")
    cap = require_real(cap, "cap")
    if not 1.0 < cap <= 1e6:
        raise ValueError(f"cap = {cap!r} is not admissible (admissible: 1 < cap <= 1e6)")
    present_db = require_real(present_db, "present_db")
    width = require_real(width, "width")
    if not 0.0 < width <= 1e3:
        raise ValueError(f"width = {width!r} is not admissible (admissible: 0 < orders <= 1e3)")

    # order tracking up to the sample rate's limit at the top speed
    top = fs / 2.56 / (float(np.max(rv)) / 60.0)
    spr = next_fast_len(max(8, math.ceil(2.56 * top)))  # the whole record is one FFT
    ang = resample_to_angle(xv, fs, rpm=rv, samples_per_rev=spr, max_order=top, min_rpm=0.0)
    revs = int(ang.values.size // spr)
    if revs < MIN_REVOLUTIONS:
        raise ValueError(f"{name}: the record covers {ang.values.size / spr:.1f} revolutions of "
                         f"the reference shaft; the impact check needs at least "
                         f"{MIN_REVOLUTIONS}")
    spec = rfft(np.ascontiguousarray(ang.values[:revs * spr]))
    nb = int(min(spec.size, math.floor(top * revs) + 1))
    spec = spec[:nb]
    order = np.arange(nb) / revs
    power = spec.real ** 2 + spec.imag ** 2

    # the mesh lattice: every harmonic position of every mesh, +-span
    near = order <= span
    hi = 0.0
    whole = np.zeros(nb, bool)
    whole[::revs] = True
    # the whole orders (the healthy set's lattice, a synchronous comb) stand out of the noise:
    # the running median takes the next bin's power there
    noise = _noise_mean(np.where(whole, np.roll(power, -1), power), revs, width)
    level = 10.0 ** (present_db / 10.0)
    # the record's noise floor: the quietest background below the anti-alias roll-off at the
    # top (a running median: about 1 dB under the mean level of white noise, its spread)
    body = (order > span) & (order < 0.9 * top)
    floor = float(np.min(noise[body])) if np.any(body) else float(np.min(noise))
    for z in meshes:
        absent = 0  # the run of present harmonics from the first ends at two absent ones
        for h in range(1, int(top / z) + 2):
            c = h * float(z)
            i0 = max(0, math.ceil((c - span) * revs))
            i1 = min(nb, math.floor((c + span) * revs) + 1)
            if i0 >= i1:
                continue
            near[i0:i1] = True
            ii = np.arange(math.ceil(i0 / revs) * revs, i1, revs)
            line = absent < 2 and ii.size and np.any(power[ii] > level * noise[ii])
            # a mesh smeared by the speed reference (a 1-pulse tacho on a run-up) raises the
            # background around it instead: BACKGROUND_DB over the floor, whatever the run
            smeared = float(np.max(noise[i0:i1])) > _BACKGROUND * floor
            if line or smeared:
                hi, absent = max(hi, c), 0
            else:
                absent += 1
    lo = hi + 0.5 * float(np.min(meshes))

    # squared envelope of the band without the mesh lattice
    kept = np.where(near, 0.0, spec)
    n_time = next_fast_len(2 * (nb - 1))  # zeros above the top order: the same revolutions
    re = irfft(kept, n=n_time)
    im = irfft(-1j * kept, n=n_time)
    env = re * re + im * im
    env -= float(np.mean(env))
    env *= np.hanning(env.size)
    es = rfft(env)
    # the envelope is read up to the highest harmonic checked (families and shaft orders)
    rates = [f.fundamental for f in fams if not _is_whole(f.fundamental, 1e-6)]
    e_top = harmonics * max([*rates, *known.tolist(), 1.0]) + 2.0 * width
    es = es[:min(es.size, math.ceil(e_top * revs) + 1)]
    e_pow = es.real ** 2 + es.imag ** 2
    e_order = np.arange(e_pow.size) / revs
    e_ratio = e_pow / _noise_mean(e_pow, revs, width)
    tol = 2.0 / revs
    # a shaft so slow that its multiples lie closer than 4 tolerances would explain every
    # line: it explains none (as the known families of the bearing check)
    known = known[known > 4.0 * tol]
    # the healthy set's strongest modulation: the largest line at the shafts' first harmonics
    ref = 0.0
    for q in known:
        for k in range(1, harmonics + 1):
            i = round(k * q * revs)
            if i + 2 <= e_ratio.size:
                ref = max(ref, float(np.max(e_ratio[max(i - 1, 0):i + 2])))

    sync_sel = (order >= lo) & ~near
    out = []
    for fam in fams:
        f = float(fam.fundamental)
        if _is_whole(f, 1e-6):
            comb = np.arange(math.ceil(lo / f), math.floor(top / f) + 1)
            idx = np.rint(comb * f * revs).astype(np.int64)
            idx = idx[(idx >= 0) & (idx < nb)]
            idx = idx[sync_sel[idx]]
            if idx.size < _MIN_COMB:  # too short a band: no comb to speak of
                idx = idx[:0]
            out.append(_evidence(fam, "synchronous", power[idx] / noise[idx], cap))
            continue
        ks = [k for k in range(1, harmonics + 1)
              if k * f <= e_order[-1] - width
              and not any(abs(k * f - round(k * f / q) * q) <= tol for q in known)]
        idx = np.rint(np.asarray(ks, float) * f * revs).astype(np.int64)
        out.append(_evidence(fam, "envelope", e_ratio[idx], cap, ref))
    keep = sync_sel
    return ImpactCheck(e_order, e_ratio, order[keep], power[keep] / noise[keep],
                       (float(min(lo, top)), float(top)), tuple(out),
                       tuple(float(z) for z in meshes), float(span), revs, str(name))
