"""Fault lines of a described machine checked in a measurement: bearings and gear faults.

A local fault strikes once per passage: a rolling bearing's race or ball defect at BPFO,
BPFI, BSF or the cage rate FTF, a damaged tooth at its gear's fault rate (``sun_fault``,
``planet_fault``, ``ring_fault``, ``gear_fault`` of :mod:`analysis.catalogue`). These lines
are faint or absent in the spectrum of the raw signal (the resonances they excite dominate
it) and stand out in the squared envelope of a band around an excited resonance
(:mod:`analysis.envelope`). :func:`check_fault_lines` takes every such family of the
description's catalogue (the declared ``[[rolling_bearing]]`` tables and the gear faults)
and checks it **at its own position** (:mod:`analysis.line_evidence`) in

* the squared envelope spectrum [Hz] of a record at a stated constant speed, or the squared
  envelope **order** spectrum of one with a speed or angle channel (the lines follow the
  shaft while the speed varies; Borghesani et al. 2013), the band chosen by the fast
  kurtogram among the bands at least ``min_bandwidth`` wide (default twice the highest line
  checked, as ``docs/condition-monitoring.md`` advises) or given;
* the order spectrum of the raw signal.

Every family comes with its prominence and its chance of a coincidence in that spectrum; the
shaft harmonics (and mesh harmonics) are known lines, so a family that rests on them, or on
the lines of a stronger detected family (an inner-race fault's shaft-modulation lattice), is
*explained* by them rather than detected. In the order spectrum the families the envelope
spectrum detected explain their lattice as well.

Families (Randall & Antoni 2011): BPFO without sidebands (a stationary outer ring), BPFI with
sidebands at the relative speed of the rings (the fault turns through the load zone), BSF
with sidebands at FTF, FTF; gear faults without sidebands; three harmonics each.

References
----------
R. B. Randall, J. Antoni, "Rolling element bearing diagnostics - a tutorial", MSSP 25(2),
485-520, 2011. P. Borghesani, R. Ricci, S. Chatterton, P. Pennacchi, "A new procedure for
using envelope analysis for rolling element bearing diagnostics in variable operating
conditions", MSSP 38(1), 23-35, 2013.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from analysis.checks import require_instance
from analysis.envelope import EnvelopeSpectrum, envelope_spectrum
from analysis.envelope_orders import EnvelopeOrderSpectrum, envelope_order_spectrum
from analysis.line_evidence import (
    MAX_CHANCE,
    LineEvidence,
    claim_tolerance,
    explained_positions,
    line_evidence,
)
from analysis.lines import LineFamily, check_lines
from gearvib.checks import check_count, check_items, check_real, check_text

MAX_ORDER = 1e6
"""Largest order of a fault family [orders of the reference shaft]."""
MAX_HARMONICS = 1000
"""Most harmonics (or sidebands per side) of a fault family."""

if TYPE_CHECKING:
    import xarray as xr
    from matplotlib.figure import Figure

    from analysis.catalogue import KinematicCatalogue, RollingBearing
    from analysis.kurtogram import Kurtogram
    from analysis.measurement import Measurement
    from analysis.orders import OrderSpectrum

__all__ = [
    "COMB_DIVISORS",
    "FAULT_KINDS",
    "KNOWN_HARMONICS",
    "KNOWN_MARGIN_DB",
    "KNOWN_MAX_COVER",
    "MIN_BANDWIDTH_FACTOR",
    "FaultFamily",
    "FaultLines",
    "catalogue_families",
    "check_fault_lines",
    "confirmed_catalogue",
    "known_families",
]

FAULT_KINDS = {"bearing_bpfo": "BPFO", "bearing_bpfi": "BPFI", "bearing_bsf": "BSF",
               "bearing_ftf": "FTF", "sun_fault": "sun fault", "planet_fault": "planet fault",
               "ring_fault": "ring fault", "gear_fault": "gear fault"}
"""Catalogue families of local faults, and their short labels."""

MIN_BANDWIDTH_FACTOR = 2.0
"""Default ``min_bandwidth`` of the kurtogram: this many times the highest line checked (the
squared envelope of a band of width ``B`` holds modulation frequencies below ``B`` only)."""


KNOWN_HARMONICS = 5
"""A known family explains lines only when it is present: its fundamental and another of its
first this many harmonics found in the same spectrum."""
KNOWN_MARGIN_DB = 3.0
"""A known family's harmonic explains a line at most this much stronger than the strongest
of the family's first :data:`KNOWN_HARMONICS` harmonics found."""
KNOWN_MAX_COVER = 0.25
"""A known family (shaft, mesh harmonics) explains a fault family's lines only when its windows
cover at most this fraction of the axis: ``2 tol(H) / f_known <= 0.25``, ``tol`` of
:func:`analysis.line_evidence.claim_tolerance` at the highest harmonic ``H`` checked. A slow
shaft (a planet carrier at a fifth of the input speed) has harmonics so close together in the
envelope spectrum that any line lies near one: they would explain every family, so they
explain none (as the peak labels of :mod:`gearvib.report.measured`)."""


@dataclass(frozen=True)
class FaultFamily:
    """A fault's line family in orders of the reference shaft.

    Attributes
    ----------
    source : str
        The bearing or the member (gear) whose fault it is.
    kind : str
        Catalogue family (:data:`FAULT_KINDS`).
    order : float
        Fundamental [orders of the reference shaft].
    sideband_order : float
        Sideband spacing [orders] (0: none).
    harmonics, sidebands : int
        Harmonics and sidebands per side checked.
    """

    source: str
    kind: str
    order: float
    sideband_order: float = 0.0
    harmonics: int = 3
    sidebands: int = 0

    def __post_init__(self) -> None:
        check_text(self.source, "source")
        check_text(self.kind, "kind")
        check_real(self.order, "order", low=0.0, low_open=True, high=MAX_ORDER)
        check_real(self.sideband_order, "sideband_order", low=0.0, high=MAX_ORDER)
        check_count(self.harmonics, "harmonics", low=1, high=MAX_HARMONICS)
        check_count(self.sidebands, "sidebands", low=0, high=MAX_HARMONICS)

    @property
    def label(self) -> str:
        """Short label, e.g. ``"BPFI"``."""
        return FAULT_KINDS.get(self.kind, self.kind)

    @property
    def name(self) -> str:
        """``"BPFI (drive-end bearing)"``."""
        return f"{self.label} ({self.source})"

    def line_family(self, scale: float = 1.0) -> LineFamily:
        """The family on an axis ``scale`` times the orders (1: orders; ``f_ref`` [Hz]: Hz)."""
        return LineFamily(self.name, self.order * scale, self.harmonics,
                          self.sideband_order * scale, self.sidebands)


def _catalogue(catalogue: Any) -> None:
    from analysis.catalogue import KinematicCatalogue

    require_instance(catalogue, KinematicCatalogue, "catalogue")


def catalogue_families(catalogue: KinematicCatalogue, bearings: Sequence[RollingBearing] = (),
                       *, harmonics: int = 3, sidebands: int = 1) -> list[FaultFamily]:
    """The fault families of a catalogue: its bearings' and gears' fault lines.

    Parameters
    ----------
    catalogue : KinematicCatalogue
        Orders of the reference shaft (:func:`gearvib.catalogue.gear_set_catalogue`,
        :meth:`gearvib.rig.ShaftRig.catalogue`).
    bearings : sequence of RollingBearing
        The bearings (their rings' members give BPFI's sideband spacing, the relative speed
        ``|n_inner - n_outer|``); without them BPFI has no sidebands.
    harmonics, sidebands : int
        Harmonics of every family; sidebands per side of BPFI (ring speed) and BSF (FTF).

    Returns
    -------
    list of FaultFamily
        Per bearing BPFO, BPFI, BSF, FTF, then the gear faults, in catalogue order.
    """
    from analysis.catalogue import RollingBearing

    _catalogue(catalogue)
    bearings = check_items(bearings, RollingBearing, "bearings")
    check_count(harmonics, "harmonics", low=1, high=MAX_HARMONICS)
    check_count(sidebands, "sidebands", low=0, high=MAX_HARMONICS)
    speeds = dict(catalogue.member_speeds)
    rings = {b.name: abs(speeds.get(b.inner, 0.0) - speeds.get(b.outer, 0.0)) for b in bearings}
    first = (catalogue.harmonic == 1) & (catalogue.sideband == 0)
    rows: dict[tuple[str, str], float] = {}
    for fam, member, order in zip(catalogue.family[first], catalogue.member[first],
                                  catalogue.order[first], strict=True):
        if str(fam) in FAULT_KINDS:
            rows.setdefault((str(member), str(fam)), float(order))
    out = []
    order_kinds = list(FAULT_KINDS)
    for (member, kind), order in sorted(rows.items(), key=lambda kv: (
            not kv[0][1].startswith("bearing"), kv[0][0],
            order_kinds.index(kv[0][1]) if kv[0][1] != "bearing_ftf" else 3.5)):
        spacing, n_sb = 0.0, 0
        if kind == "bearing_bpfi" and rings.get(member, 0.0) > 0:
            spacing, n_sb = rings[member], sidebands
        elif kind == "bearing_bsf" and (member, "bearing_ftf") in rows:
            spacing, n_sb = rows[(member, "bearing_ftf")], sidebands
        out.append(FaultFamily(member, kind, order, spacing, harmonics, n_sb))
    return out


def known_families(catalogue: KinematicCatalogue, top_order: float) -> list[LineFamily]:
    """The shaft and mesh harmonics of a catalogue up to ``top_order`` (known lines)."""
    _catalogue(catalogue)
    top_order = check_real(top_order, "top_order", low=0.0, high=MAX_ORDER)
    first = (catalogue.harmonic == 1) & (catalogue.sideband == 0)
    out = []
    seen: set[float] = set()
    for fam, member, order in zip(catalogue.family[first], catalogue.member[first],
                                  catalogue.order[first], strict=True):
        if str(fam) not in ("shaft", "mesh") or order <= 0:
            continue
        key = round(float(order), 9)
        if key in seen:
            continue
        seen.add(key)
        n = max(1, min(5000, int(top_order / order) + 1))
        out.append(LineFamily(f"{fam} {member}", float(order), n))
    return out


def confirmed_catalogue(catalogue: KinematicCatalogue, fault_lines: FaultLines | None
                        ) -> KinematicCatalogue:
    """The catalogue without the bearing lines whose family the check did not detect.

    A bearing line is a candidate label for a spectrum peak only when its family stands out
    where it should (:func:`check_fault_lines` reports it detected in the envelope spectrum
    or the order spectrum): on a healthy machine a peak that falls in the window of, say,
    BPFI is not evidence of an inner-race fault, and labelling it so would claim one.

    Parameters
    ----------
    catalogue : KinematicCatalogue
        The description's catalogue.
    fault_lines : FaultLines or None
        The check (None: every bearing line is removed).

    Returns
    -------
    KinematicCatalogue
        The same lines but the ``bearing_*`` ones of families not detected (shaft, mesh and
        gear-fault lines are kept).
    """
    import dataclasses

    _catalogue(catalogue)
    if fault_lines is not None:
        require_instance(fault_lines, FaultLines, "fault_lines")
    ok: set[tuple[str, str]] = set()
    if fault_lines is not None:
        for ev in (fault_lines.envelope_evidence, fault_lines.order_evidence):
            if ev is None:
                continue
            ok |= {(f.source, f.kind) for f, d in zip(fault_lines.families, ev.detected,
                                                      strict=True) if d}
    fam = np.asarray(catalogue.family).astype(str)
    keep = ~np.char.startswith(fam, "bearing_") | np.asarray(
        [(str(m), f) in ok for m, f in zip(catalogue.member, fam, strict=True)], dtype=bool)
    if keep.all():
        return catalogue
    return dataclasses.replace(catalogue, **{k: np.asarray(getattr(catalogue, k))[keep] for k in (
        "family", "harmonic", "sideband", "member", "formula", "order", "phasing")})


@dataclass(frozen=True)
class FaultLines:
    """Fault families checked in the envelope (order) spectrum and the order spectrum.

    Attributes
    ----------
    families : tuple of FaultFamily
        The families, in orders of the reference shaft.
    envelope : EnvelopeSpectrum or EnvelopeOrderSpectrum
        The squared envelope spectrum [Hz] (stated constant speed) or order spectrum.
    envelope_evidence : LineEvidence
        The families checked in it (in its axis units).
    order_evidence : LineEvidence or None
        The families checked in the order spectrum of the raw signal.
    order_spectrum : OrderSpectrum or None
        That order spectrum.
    domain : str
        ``"frequency"`` or ``"order"``: the envelope spectrum's axis.
    speed_rpm : float
        Mean reference speed [min-1] (families in Hz are placed at it).
    min_bandwidth : float or None
        Narrowest band [Hz] the kurtogram could choose (None: band given).
    notes : tuple of str
        What could not be checked, and why.
    """

    families: tuple[FaultFamily, ...]
    envelope: EnvelopeSpectrum | EnvelopeOrderSpectrum
    envelope_evidence: LineEvidence
    order_evidence: LineEvidence | None
    order_spectrum: OrderSpectrum | None
    domain: str
    speed_rpm: float
    min_bandwidth: float | None
    notes: tuple[str, ...] = field(default_factory=tuple)

    @property
    def kurtogram(self) -> Kurtogram | None:
        """The kurtogram that chose the band (None when the band was given)."""
        return self.envelope.kurtogram

    @property
    def detected(self) -> list[FaultFamily]:
        """Families reported detected in the envelope spectrum."""
        return [f for f, d in zip(self.families, self.envelope_evidence.detected, strict=True)
                if d]

    def to_dataset(self) -> xr.Dataset:
        """CF Dataset: the envelope spectrum and both checks (variables prefixed
        ``envelope_`` and ``order_``), the families' sources and kinds."""
        import xarray as xr

        from analysis.cf import cf_dataset

        env = self.envelope.to_dataset()
        ev = self.envelope_evidence.to_dataset()
        ds = xr.merge([env, ev.rename({k: f"envelope_{k}" for k in ev.data_vars})],
                      combine_attrs="drop_conflicts")
        if self.order_evidence is not None:
            od = self.order_evidence.to_dataset()
            ds = xr.merge([ds, od.rename({k: f"order_{k}" for k in od.data_vars})],
                          combine_attrs="drop_conflicts")
        ds["family_source"] = ("family", np.asarray([f.source for f in self.families],
                                                    dtype=object),
                               {"units": "1", "long_name": "bearing or member of the fault"})
        ds["family_kind"] = ("family", np.asarray([f.kind for f in self.families],
                                                  dtype=object),
                             {"units": "1", "long_name": "catalogue family"})
        ds["family_order"] = ("family", np.asarray([f.order for f in self.families]),
                              {"units": "1", "long_name": "fundamental in orders of the "
                               "reference shaft"})
        ds.attrs.update(domain=self.domain, mean_speed_rpm=float(self.speed_rpm),
                        min_bandwidth_hz=float(self.min_bandwidth or 0.0),
                        notes=" | ".join(self.notes))
        return cf_dataset(ds, title="fault lines in the envelope and order spectra",
                          producer="gearvib.fault_lines.check_fault_lines")

    def plot(self, **kwargs: Any) -> Figure:
        """The envelope spectrum with the families (:meth:`LineEvidence.plot`)."""
        return self.envelope_evidence.plot(**kwargs)


def _explaining(known: Sequence[LineFamily], scale: float, axis: np.ndarray,
                power: np.ndarray, harmonics: int
                ) -> tuple[list[tuple[str, np.ndarray]], list[str]]:
    """The lines of the known families (orders) that may explain lines on an axis ``scale``
    times the orders, as ``(name, positions)`` for :func:`analysis.line_evidence.line_evidence`.

    A known family takes part when its windows cover at most :data:`KNOWN_MAX_COVER` of the
    axis and it is present (:func:`analysis.lines.check_lines`: its fundamental and another
    of its first :data:`KNOWN_HARMONICS` harmonics found); of its harmonics, only those whose
    line is at most :data:`KNOWN_MARGIN_DB` above the strongest of its first harmonics are
    offered (a shaft's modulation is strongest at its low harmonics: a line far stronger than
    them at the 13th harmonic of a planet is something else). Also returns the names of the
    families left out as too dense."""
    spacing, top = float(axis[1] - axis[0]), float(axis[-1])
    cover = 2.0 * float(claim_tolerance(harmonics, spacing))
    kept: list[tuple[str, np.ndarray]] = []
    dense: list[str] = []
    for k in known:
        f = k.fundamental * scale
        if cover > KNOWN_MAX_COVER * f:
            dense.append(k.name)
            continue
        if 2 * f > top:
            continue
        c = check_lines(axis, power, LineFamily(k.name, f, int(top / f)))
        low = c.harmonic <= KNOWN_HARMONICS
        if not (c.found[c.harmonic == 1].any() and np.count_nonzero(c.found & low) >= 2):
            continue
        ceiling = float(np.nanmax(np.where(c.found & low, c.prominence_db, np.nan)))
        ok = ~(c.prominence_db > ceiling + KNOWN_MARGIN_DB)  # NaN (outside): kept
        kept.append((k.name, np.sort(c.expected[ok])))
    return kept, dense


COMB_DIVISORS = (2, 3, 4)
"""A family found in the envelope spectrum is *explained by a comb* when the comb's
fundamental ``f_1 / k`` (``k`` one of these) and the lines ``j f_1 / k`` between the family's
harmonics (``j`` not a multiple of ``k``, up to its highest harmonic) are found as well, at
least two and two thirds of them: its lines are then every ``k``-th line of impacts at
``f_1 / k`` from another source."""


_ORDINAL = {2: "2nd", 3: "3rd", 4: "4th"}


def _combs(ev: LineEvidence, axis: np.ndarray, power: np.ndarray, units: str
           ) -> list[tuple[str, np.ndarray]]:
    """Combs of another source whose every ``k``-th line a found family sits on
    (:data:`COMB_DIVISORS`), as ``(name, positions)`` known lines."""
    spacing, top = float(axis[1] - axis[0]), float(axis[-1])
    out: list[tuple[str, np.ndarray]] = []
    for c, st in zip(ev.checks, ev.status, strict=True):
        if st not in ("detected", "possible"):
            continue
        first = (c.harmonic == 1) & (c.sideband == 0)
        f1 = float(c.position[first][0])
        h_max = int(c.harmonic[c.sideband == 0].max())
        for k in COMB_DIVISORS:
            sub = f1 / k
            n = k * h_max
            if sub < 4 * spacing or n * sub > top:
                continue
            cc = check_lines(axis, power, LineFamily("comb", sub, n))
            between = (cc.harmonic % k) != 0
            found = int(np.count_nonzero(cc.found & between))
            if cc.found[0] and found >= max(2, int(np.ceil(2 * np.count_nonzero(between)
                                                           / 3))):
                unit = " Hz" if units == "Hz" else ""
                out.append((f"a comb at {sub:.4g}{unit} (every {_ORDINAL[k]} line: another source)",
                            sub * np.arange(1, int(top / sub) + 1)))
                break
    return out


def _band_of(band: Any) -> Any:
    if band is None:
        return None
    if isinstance(band, tuple | list) and len(band) == 2:
        return (float(band[0]), float(band[1]))
    return band


def check_fault_lines(measurement: Measurement, families: Sequence[FaultFamily], *,
                      known: Sequence[LineFamily] = (), channel: str | None = None,
                      band: Any = None, min_bandwidth: float | None = None,
                      order_spectrum: OrderSpectrum | bool = True,
                      max_chance: float = MAX_CHANCE, min_harmonics: int = 2) -> FaultLines:
    """Check every fault family at its own position in the envelope and order spectra.

    Parameters
    ----------
    measurement : Measurement
        The record and its reference speed (:func:`analysis.measurement.load_measurement`).
    families : sequence of FaultFamily
        From :func:`catalogue_families` (orders of the measurement's reference shaft).
    known : sequence of LineFamily
        Known lines in orders (:func:`known_families`: shaft and mesh harmonics).
    channel : str, optional
        Vibration channel (default the measurement's first).
    band : (float, float) or Band, optional
        Band to demodulate [Hz]; default the fast kurtogram's choice among the bands at
        least ``min_bandwidth`` wide.
    min_bandwidth : float, optional
        Narrowest band [Hz] the kurtogram may choose; default :data:`MIN_BANDWIDTH_FACTOR`
        times the highest line checked at the top speed, at most ``fs / 2``.
    order_spectrum : OrderSpectrum or bool
        The order spectrum of the raw signal to check the families in as well; ``True``
        (default): computed here at the envelope spectrum's resolution (in orders), Hann
        window, up to 1.3 times the highest line checked; ``False``: not checked.
    max_chance : float
        Largest chance of a coincidence for a family to be reported detected.
    min_harmonics : int
        Harmonics found (the fundamental among them) for a family to count as found
        (default 2). With 3, fewer false detections on random envelope lines (one strong
        line in a fundamental's window brings its own second harmonic: the squared envelope
        of a modulation at ``f`` holds ``2 f``), but in a dense envelope spectrum (the
        shaft-modulation lattice of an inner-race fault) a chance-level coincidence of any one
        of the three lines costs the detection (``docs/measurements.md``).

    Returns
    -------
    FaultLines

    Raises
    ------
    ValueError
        No families; a band or ``min_bandwidth`` the envelope functions refuse.
    """
    from analysis.measurement import Measurement

    require_instance(measurement, Measurement, "measurement")
    fams = check_items(families, FaultFamily, "families")
    if not fams:
        raise ValueError("families: give at least one fault family (catalogue_families)")
    known = check_items(known, LineFamily, "known")
    check_text(channel, "channel", optional=True)
    if min_bandwidth is not None:
        min_bandwidth = check_real(min_bandwidth, "min_bandwidth", low=0.0, low_open=True)
    if not isinstance(order_spectrum, bool):
        from analysis.orders import OrderSpectrum

        require_instance(order_spectrum, OrderSpectrum, "order_spectrum")
    max_chance = check_real(max_chance, "max_chance", low=0.0, high=1.0)
    min_harmonics = check_count(min_harmonics, "min_harmonics", low=1, high=MAX_HARMONICS)
    x = measurement.channel(channel)
    fs = measurement.fs
    rpm = np.asarray(measurement.speed_rpm.values, dtype=float)
    mean_rpm = float(np.mean(rpm))
    top_hz = float(np.max(rpm)) / 60.0
    highest = max(f.harmonics * f.order + f.sidebands * f.sideband_order for f in fams)
    notes: list[str] = []
    if band is None and min_bandwidth is None:
        min_bandwidth = min(MIN_BANDWIDTH_FACTOR * highest * top_hz, 0.5 * fs)
    band = _band_of(band)
    stated = measurement.source.get("reference_channel") is None
    common: dict[str, Any] = {
        "band": band, "min_bandwidth": None if band is not None else min_bandwidth,
        "name": str(x.name)}
    if stated:  # a stated constant speed: the envelope spectrum in Hz
        env: Any = envelope_spectrum(x, **common)
        keep = env.frequency <= env.band.width
        scale, axis, units = mean_rpm / 60.0, env.frequency[keep], "Hz"
        power = env.power()[keep]
        what = "squared envelope spectrum"
    else:
        ref: dict[str, Any] = ({"angle": measurement.angle.values}
                               if measurement.angle is not None else {"rpm": rpm})
        env = envelope_order_spectrum(np.asarray(x.values, dtype=float), fs, **ref,
                                      units=str(x.attrs.get("units", "1")), **common)
        keep = env.order <= env.order_limit
        scale, axis, units = 1.0, env.order[keep], "1"
        power = env.power()[keep]
        what = "squared envelope order spectrum"
    line_fams = [f.line_family(scale) for f in fams]
    h_top = max(f.harmonics for f in fams)
    kn, dense = _explaining(known, scale, axis, power, h_top)
    if dense:
        notes.append("known lines too dense to explain a line in the envelope spectrum (their "
                     f"windows cover more than {100 * KNOWN_MAX_COVER:g} % of the axis): "
                     + ", ".join(dense))
    b = env.band
    ev_name = f"{x.name}: {what} of {b.low:.5g}-{b.high:.5g} Hz"
    env_ev = line_evidence(axis, power, line_fams, known=kn, axis_units=units,
                           max_chance=max_chance, min_harmonics=min_harmonics, name=ev_name)
    combs = _combs(env_ev, axis, power, units)
    if combs:  # a family on every k-th line of a comb of another source: explained by it
        env_ev = line_evidence(axis, power, line_fams, known=[*kn, *combs], axis_units=units,
                               max_chance=max_chance, min_harmonics=min_harmonics,
                               name=ev_name)
    outside = [f.name for f, s in zip(fams, env_ev.status, strict=True) if s == "outside"]
    if outside:
        notes.append(f"above the demodulated band's width ({b.width:.4g} Hz) or the spectrum: "
                     + ", ".join(outside))
    order_ev = None
    computed: OrderSpectrum | None = (None if isinstance(order_spectrum, bool)
                                      else order_spectrum)
    if order_spectrum is True:
        from analysis.orders import order_spectrum as compute

        res = (env.resolution_hz / (mean_rpm / 60.0) if stated else env.resolution_orders)
        nyq = 0.95 * 0.5 * fs / top_hz
        ref = ({"angle": measurement.angle.values} if measurement.angle is not None
               else {"rpm": rpm})
        try:
            computed = compute(np.asarray(x.values, dtype=float), fs, **ref,
                                     window="hann", amplitude="peak", resolution=res,
                                     max_order=min(nyq, 1.3 * highest + 2.0),
                                     units=str(x.attrs.get("units", "1")), name=str(x.name))
        except ValueError as exc:
            notes.append(f"order spectrum not checked: {exc}")
    if computed is not None:
        o_axis = np.asarray(computed.order, dtype=float)
        o_pow = np.square(np.asarray(computed.values, dtype=float)) \
            if computed.amplitude in ("peak", "rms") else \
            np.asarray(computed.values, dtype=float)
        kept, _ = _explaining(known, 1.0, o_axis, o_pow, h_top)
        kn_o: list[Any] = list(kept)
        # the families the envelope detected explain their lattice here too (an inner-race
        # fault's |h BPFI + k f_r| holds BPFO = |BPFI - Z f_r|)
        for c, st in zip(env_ev.checks, env_ev.status, strict=True):
            if st == "detected":
                kn_o.append((c.family.name,
                             explained_positions(c, float(o_axis[-1]) * scale) / scale))
        order_ev = line_evidence(o_axis, o_pow, [f.line_family(1.0) for f in fams],
                                 known=kn_o, axis_units="1", max_chance=max_chance,
                                 min_harmonics=min_harmonics,
                                 name=f"{x.name}: order spectrum")
    return FaultLines(families=fams, envelope=env, envelope_evidence=env_ev,
                      order_evidence=order_ev, order_spectrum=computed,
                      domain="frequency" if stated else "order",
                      speed_rpm=mean_rpm,
                      min_bandwidth=(None if band is not None or min_bandwidth is None
                                     else float(min_bandwidth)),
                      notes=tuple(notes))
