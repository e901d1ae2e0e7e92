"""Parametric-instability tools: Floquet analysis, Mathieu-type theory, peak labels, run-up maps.

Generic API on plain arrays and callables (no dependency on :mod:`gearvib`):

* :func:`floquet` -- monodromy and multipliers of ``M q'' + C q' + K(t) q = 0``;
* :func:`instability_candidates`, :class:`MeshPhasingRule`, :func:`first_order_widths`,
  :func:`rectangular_wave_harmonics` -- theory (centres, selection rules, widths);
* :func:`stability_chart` -- Floquet over a mesh-frequency grid (Ince-Strutt charts);
* :func:`label_peaks` -- label spectral peaks with natural-frequency combinations;
* :func:`detect_resonances` -- find and classify spots in an rpm-frequency map.
"""

from analysis.instability.chart import StabilityChart, stability_chart
from analysis.instability.floquet import FloquetResult, PiecewiseConstant, floquet
from analysis.instability.labels import PeakLabels, PeakMatch, label_peaks
from analysis.instability.resonances import Resonances, detect_resonances
from analysis.instability.theory import (
    Candidates,
    FirstOrderWidths,
    MeshPhasingRule,
    first_order_widths,
    instability_candidates,
    rectangular_wave_harmonics,
    rectangular_wave_pieces,
)

__all__ = [
    "Candidates",
    "FirstOrderWidths",
    "FloquetResult",
    "MeshPhasingRule",
    "PeakLabels",
    "PeakMatch",
    "PiecewiseConstant",
    "Resonances",
    "StabilityChart",
    "detect_resonances",
    "first_order_widths",
    "floquet",
    "instability_candidates",
    "label_peaks",
    "rectangular_wave_harmonics",
    "rectangular_wave_pieces",
    "stability_chart",
]
