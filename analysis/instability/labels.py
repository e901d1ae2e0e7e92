"""Label spectral peaks with theory and catalogue lines, in the paper's list style.

``label_peaks`` produces lists such as ``"620 Hz ≈ f2/2"``, ``"1650 Hz ≈ (f2 + f3)/2"`` or
``"1280 Hz ≈ 2 f_mesh ≈ f2"``, but only for candidates inside a window derived from the
spectral resolution and the uncertainties of the natural frequencies and the speed; every match
states the chance that it is a coincidence, and a peak that nothing explains is reported as
unexplained. The machinery is :func:`analysis.identification.identify_peaks`; this module adds
the theory candidates of :mod:`analysis.instability.theory` (with the planetary selection rules).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from analysis.checks import require_instance, require_positive
from analysis.identification import (
    CandidateLines,
    LineMatch,
    PeakIdentification,
    catalogue_lines,
    identify_peaks,
    mesh_lines,
    modal_lines,
    ratio_expression,
)
from analysis.instability.theory import Candidates, natural_frequencies

__all__ = ["PeakLabels", "PeakMatch", "label_peaks", "theory_lines"]

PeakLabels = PeakIdentification
"""Result of :func:`label_peaks` (an :class:`analysis.identification.PeakIdentification`)."""

PeakMatch = LineMatch
"""One candidate explanation (an :class:`analysis.identification.LineMatch`)."""


def theory_lines(candidates: Candidates, *, names: Sequence[str] | None = None,
                 uncertainty: float = 0.01, natural: bool = True, allowed_only: bool = True,
                 repeat_rtol: float = 1e-6) -> CandidateLines:
    """Candidate lines from theory candidates (``2 f_i / n``, ``(f_i + f_j) / n``).

    Parameters
    ----------
    candidates : Candidates
        From :func:`analysis.instability.instability_candidates` (with selection rules).
    names : sequence of str, optional
        Mode names (default ``f1, f2, ...``), one per natural frequency of the candidates.
    uncertainty : float
        Relative uncertainty of the natural frequencies.
    natural : bool
        Add the natural frequencies themselves (family ``"natural"``).
    allowed_only : bool
        Leave out candidates a selection rule suppresses.
    repeat_rtol : float
        Natural frequencies equal within this tolerance are one degenerate cluster
        (written ``f3 ≈ f4``), as in the candidates.

    Returns
    -------
    CandidateLines
        Families ``natural``, ``principal``, ``sum`` (and ``difference`` if listed).
    """
    require_instance(candidates, Candidates, "candidates")
    u = require_positive(uncertainty, "uncertainty", allow_zero=True)
    fn = np.asarray(candidates.natural_frequencies_hz, dtype=float)
    labels = list(names) if names is not None else [f"f{i + 1}" for i in range(fn.size)]
    if len(labels) != fn.size:
        raise ValueError(f"names has {len(labels)} entries; the candidates have {fn.size} "
                         "natural frequencies")
    rtol = require_positive(repeat_rtol, "repeat_rtol", allow_zero=True)
    cluster = {i: [j for j in range(fn.size) if abs(fn[j] - fn[i]) <= rtol * fn[i]]
               for i in range(fn.size)}
    rows: list[tuple[float, str, str]] = []
    for r in range(len(candidates)):
        if allowed_only and not candidates.allowed[r]:
            continue
        kind, n = str(candidates.kind[r]), int(candidates.n[r])
        ci, cj = cluster[int(candidates.mode_i[r])], cluster[int(candidates.mode_j[r])]
        if kind == "principal":
            if n == 2:
                continue  # the principal region n = 2 sits at f_i: the natural line
            expr = " ≈ ".join(ratio_expression(2, n, labels[i]) for i in ci)
        else:
            op = "-" if kind == "difference" else "+"
            parts = [f"{labels[j]} {op} {labels[i]}" if op == "-" else
                     f"{labels[min(i, j)]} + {labels[max(i, j)]}" for i in ci for j in cj]
            expr = " ≈ ".join(p if n == 1 else f"({p})/{n}" for p in parts)
        rows.append((float(candidates.f_mesh_hz[r]), kind, expr))
    if natural:
        seen: set[int] = set()
        for i in range(fn.size):
            if i not in seen:
                seen.update(cluster[i])
                rows.append((float(fn[cluster[i]].mean()), "natural",
                             " ≈ ".join(labels[j] for j in cluster[i])))
    n_rows = len(rows)
    return CandidateLines(value=np.asarray([r[0] for r in rows], dtype=float),
                          family=np.asarray([r[1] for r in rows], dtype=object),
                          expression=np.asarray([r[2] for r in rows], dtype=object),
                          uncertainty=np.full(n_rows, u),
                          locked=np.full(n_rows, "frequency", dtype=object))


def label_peaks(
    peak_frequencies_hz: Any,
    natural_frequencies_hz: Any,
    *,
    resolution_hz: float | None = None,
    peak_widths_hz: Any = None,
    mesh_frequency_hz: float | None = None,
    catalogue: Any = None,
    speed_rpm: float | None = None,
    candidates: Candidates | None = None,
    n_max: int = 4,
    natural_uncertainty: float = 0.01,
    speed_uncertainty: float = 1e-3,
    tolerance: float | None = None,
    names: Sequence[str] | None = None,
    repeat_rtol: float = 1e-6,
    band: tuple[float, float] | None = None,
) -> PeakLabels:
    """Identify spectral peaks with natural-frequency combinations and kinematic lines.

    Parameters
    ----------
    peak_frequencies_hz : array_like
        Peak frequencies [Hz] (> 0).
    natural_frequencies_hz : array_like
        Natural frequencies [Hz] (> 0).
    resolution_hz : float, optional
        Resolution of the spectrum [Hz]: the peak-position uncertainty is half of it (or the
        -3 dB half-width in ``peak_widths_hz`` if larger). Required unless ``tolerance``.
    peak_widths_hz : array_like, optional
        -3 dB half-width of every peak [Hz] (broad run-up humps are uncertain by that much).
    mesh_frequency_hz : float, optional
        Mesh frequency of a constant-speed spectrum: adds ``m f_mesh`` (without a catalogue).
    catalogue : KinematicCatalogue, optional
        Kinematic catalogue; its visible lines at ``speed_rpm`` are candidates too.
    speed_rpm : float, optional
        Reference speed of the catalogue [min-1] (default: the catalogue's).
    candidates : Candidates, optional
        Theory candidates with selection rules (:func:`instability_candidates`); when given
        they replace the plain ``2 f_i / n`` and ``(f_i + f_j) / n`` lists (suppressed
        candidates are left out).
    n_max : int
        Largest ``n`` of ``2 f_i / n`` and ``(f_i + f_j) / n``.
    natural_uncertainty : float
        Relative uncertainty of the natural frequencies (model vs. reality).
    speed_uncertainty : float
        Relative uncertainty of the speed (catalogue and mesh lines).
    tolerance : float, optional
        Fixed relative window ``|p - v| <= tolerance v`` instead of the derived one.
    names : sequence of str, optional
        Mode names (default ``f1, f2, ...``).
    repeat_rtol : float
        Natural frequencies equal within this relative tolerance form a degenerate pair
        (``f3 ≈ f4``).
    band : (float, float), optional
        Band of the coincidence statistics [Hz].

    Returns
    -------
    PeakLabels
        ``.labels`` in the paper's style, ``.matches`` ranked, ``.coincidence`` per peak,
        ``.coverage`` of the band (the rate at which random peaks get a label).
    """
    fn = natural_frequencies(natural_frequencies_hz)
    if tolerance is not None:
        tol = require_positive(tolerance, "tolerance")
        if tol >= 0.5:
            raise ValueError(f"tolerance = {tolerance!r} is not admissible: must be < 0.5 "
                             "(relative)")
        u_fn = u_sp = tol
        res, factor = 1e-9, 1e-9
    else:
        if resolution_hz is None:
            raise ValueError("give resolution_hz (the spectrum's resolution [Hz]) or an "
                             "explicit relative tolerance")
        res, factor = require_positive(resolution_hz, "resolution_hz"), 0.5
        u_fn = require_positive(natural_uncertainty, "natural_uncertainty", allow_zero=True)
        u_sp = require_positive(speed_uncertainty, "speed_uncertainty", allow_zero=True)
    if candidates is not None:
        lines = [theory_lines(candidates, names=names, uncertainty=u_fn,
                              repeat_rtol=repeat_rtol)]
    else:
        lines = [modal_lines(fn, names=names, n_max=n_max, uncertainty=u_fn,
                             repeat_rtol=repeat_rtol)]
    if catalogue is not None:
        lines.append(catalogue_lines(catalogue, speed_rpm=speed_rpm,
                                     speed_uncertainty=u_sp))
    elif mesh_frequency_hz:
        lines.append(mesh_lines(require_positive(mesh_frequency_hz, "mesh_frequency_hz"),
                                harmonics=7, uncertainty=u_sp))
    return identify_peaks(peak_frequencies_hz, lines, resolution=res, resolution_factor=factor,
                          peak_widths=peak_widths_hz if tolerance is None else None, band=band)
