"""Parametric-instability tools: Floquet analysis, Mathieu-type theory, peak labels, run-up maps.

Generic API on plain arrays and callables (no dependency on :mod:`gearvib`):

* :func:`floquet` -- monodromy and multipliers of ``M q'' + C q' + K(t) q = 0``;
* :func:`instability_candidates`, :class:`MeshPhasingRule`, :func:`first_order_widths`,
  :func:`rectangular_wave_harmonics` -- theory (centres, selection rules, widths);
* :func:`stability_chart` -- Floquet over a mesh-frequency grid (Ince-Strutt charts);
* :func:`runup_growth` -- how much an unstable band can grow while a run-up crosses it;
* :func:`label_peaks` -- identify spectral peaks with theory and catalogue lines (tolerance,
  coincidence odds, unexplained peaks);
* :func:`detect_resonances` -- find and classify the rises of a run-up map (forced resonance,
  parametric instability, unexplained).
"""

from analysis.instability.chart import StabilityChart, stability_chart
from analysis.instability.floquet import (
    FloquetResult,
    PiecewiseConstant,
    PiecewiseSmooth,
    floquet,
)
from analysis.instability.growth import GrowthTable, UnstableBand, runup_growth, unstable_bands
from analysis.instability.labels import PeakLabels, PeakMatch, label_peaks, theory_lines
from analysis.instability.resonances import (
    FORCED,
    PARAMETRIC,
    UNEXPLAINED,
    Crossing,
    Resonances,
    detect_resonances,
    merge_mesh_frequencies,
)
from analysis.instability.theory import (
    Candidates,
    FirstOrderWidths,
    MeshPhasingRule,
    first_order_widths,
    instability_candidates,
    natural_frequencies,
    rectangular_wave_harmonics,
    rectangular_wave_pieces,
)

__all__ = [
    "FORCED",
    "PARAMETRIC",
    "UNEXPLAINED",
    "Candidates",
    "Crossing",
    "FirstOrderWidths",
    "FloquetResult",
    "GrowthTable",
    "MeshPhasingRule",
    "PeakLabels",
    "PeakMatch",
    "PiecewiseConstant",
    "PiecewiseSmooth",
    "Resonances",
    "StabilityChart",
    "UnstableBand",
    "detect_resonances",
    "first_order_widths",
    "floquet",
    "instability_candidates",
    "label_peaks",
    "merge_mesh_frequencies",
    "natural_frequencies",
    "rectangular_wave_harmonics",
    "rectangular_wave_pieces",
    "runup_growth",
    "stability_chart",
    "theory_lines",
    "unstable_bands",
]
