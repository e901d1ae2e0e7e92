"""Spectra of the tooth forces of a run with labelled peaks (paper Figure 8).

:func:`force_spectrum` computes the spectrum of one tooth force over the whole run-up, picks its
strongest humps and labels them with natural-frequency combinations (:class:`ForceSpectrum`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from analysis.identification import peak_half_widths
from analysis.instability import Candidates, PeakLabels, label_peaks
from analysis.spectrum import Peaks, Spectrum, find_peaks, spectrum, to_db
from gearvib.report.case_run import signed_force
from gearvib.report.study import AnalysisSettings

__all__ = ["ForceSpectrum", "force_spectrum"]


@dataclass(frozen=True)
class ForceSpectrum:
    """Spectrum of one tooth force over the whole run-up with labelled peaks (Figure 8).

    Attributes
    ----------
    mesh : str
        Mesh name.
    spectrum : Spectrum
        Peak-scaled, Welch-averaged spectrum of the dynamic part of the force.
    peaks : Peaks
        The strongest peaks.
    labels : PeakLabels
        Theory labels of the peaks (natural-frequency combinations).
    group : str
        Mesh-frequency group of the mesh.
    """

    mesh: str
    spectrum: Spectrum
    peaks: Peaks
    labels: PeakLabels
    group: str = "mesh"

    def short_label(self, i: int, max_matches: int = 2) -> str:
        """The label of peak ``i`` with at most ``max_matches`` expressions (``"(+3 more)"``).

        Expressions of repeated modes (``"(f3 + f5)/4 ≈ (f4 + f5)/4"``) keep their first form.
        """
        lab = self.labels
        head = f"{self.peaks.frequency[i]:.0f} Hz"
        if i >= len(lab) or not lab.matches[i]:
            return f"{head}: unexplained"
        ms = lab.matches[i]
        exprs = [m.expression.split(" ≈ ")[0] for m in ms[:max_matches]]
        extra = len(ms) - max_matches
        more = f" (+{extra} more)" if extra > 0 else ""
        if lab.status[i] == "ambiguous":
            return (f"{head}: ambiguous ({', '.join(exprs)}{more} within ± "
                    f"{ms[0].tolerance:.3g}; chance match {100 * ms[0].coincidence:.0f} %)")
        return " ≈ ".join([head, *exprs]) + more


def force_spectrum(ds: xr.Dataset, mesh: str, group: str, fs: float, fmax: float,
                   settings: AnalysisSettings, fn: np.ndarray, names: list[str],
                   candidates: Candidates) -> ForceSpectrum:
    """Spectrum of one tooth force over the run-up, its strongest humps and their labels.

    Parameters
    ----------
    ds : xarray.Dataset
        The run.
    mesh, group : str
        The mesh and its mesh-frequency group.
    fs : float
        Sample rate [Hz].
    fmax : float
        Upper frequency of the peaks [Hz].
    settings : AnalysisSettings
        ``map_resolution_hz`` (segment length: a quarter of it), ``spectrum_peaks``,
        ``tolerance``.
    fn : ndarray
        Natural frequencies [Hz] the peaks are labelled with.
    names : list of str
        Their names.
    candidates : Candidates
        Theory candidates (:func:`analysis.instability.label_peaks`).

    Returns
    -------
    ForceSpectrum
        Peak-scaled Hann spectrum (50 % overlap) of the dynamic part of the force; every peak
        is uncertain by its -3 dB half-width.
    """
    seg = int(min(ds.sizes["time"], round(fs / max(settings.map_resolution_hz / 4, 1.0))))
    x = signed_force(ds, mesh)
    sp = spectrum(x - x.mean(), fs, window="hann", amplitude="peak", segment_length=seg,
                  overlap=0.5, units="N", name=f"tooth force {mesh}")
    band = sp.frequency <= fmax
    floor = float(np.median(sp.values[band])) if band.any() else 0.0
    # humps of the run-up spectrum, not the ripple of the mesh harmonics sweeping by
    pk = find_peaks(sp, prominence_db=3.0, max_peaks=4 * settings.spectrum_peaks,
                    min_distance_hz=max(3 * sp.bin_spacing_hz, fmax / 40.0),
                    threshold=2 * floor)
    keep = (pk.frequency > 0.5 * settings.map_resolution_hz) & (pk.frequency <= fmax)
    order = np.argsort(pk.amplitude[keep])[::-1][: settings.spectrum_peaks]
    sel = np.sort(np.flatnonzero(keep)[order])
    pk = Peaks(pk.frequency[sel], pk.amplitude[sel], pk.bin_frequency[sel],
               pk.bin_value[sel], pk.scaling, pk.units, pk.window)
    if len(pk) and fn.size:
        # a run-up spectrum has broad humps: each peak is uncertain by its -3 dB half-width
        widths = peak_half_widths(sp.frequency, to_db(sp.values, sp.amplitude), pk.frequency)
        labels = label_peaks(pk.frequency, fn, resolution_hz=sp.enbw_hz,
                             peak_widths_hz=widths, candidates=candidates, names=names,
                             natural_uncertainty=settings.tolerance,
                             band=(0.5 * settings.map_resolution_hz, fmax))
    else:
        labels = PeakLabels(peaks=np.zeros(0), matches=(), coincidence=np.zeros(0),
                            peak_uncertainty=np.zeros(0))
    return ForceSpectrum(mesh, sp, pk, labels, group)

