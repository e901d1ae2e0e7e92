"""Order-analysis report of a measurement: :func:`build_measured_report` writes it.

A measurement (:class:`analysis.measurement.Measurement`: channels, reference-shaft speed,
provenance) is analysed like a simulated run, with what a measurement has: the spectrum of a
vibration channel with identified peaks, the order spectrum with the gear set's catalogue lines,
the rpm-frequency and rpm-order maps with the gear set's mesh orders and natural frequencies,
the order-locked rays and frequency-locked lines of the map, and the rises of the map classified
as forced resonances (a mesh order crossing a natural frequency). There are no simulated
forces, stiffness tables or Floquet charts in it.

Without a gear set the report keeps what needs none -- the maps, the spectra, the orders of the
reference shaft, the rays and vertical lines of the map -- and says what is missing. Rises are
then the crossings of the reference shaft's order rays with the vertical lines the map shows.

:func:`~gearvib.report.measured_analysis.analyse_measurement` computes every quantity once
into a :class:`~gearvib.report.measured_case.MeasuredCase`;
:func:`~gearvib.report.measured_sections.measured_sections` turns it into the report's sections
(the HTML and PDF writers of :mod:`gearvib.report`), and
:func:`gearvib.report.crosscheck.cross_check` checks the result as for a simulation. The pieces:
:mod:`~gearvib.report.measured_analysis` (the analysis), :mod:`~gearvib.report.measured_case`
(the content and its table rows), :mod:`~gearvib.report.measured_peaks` (peak selection,
candidate lines, peak tables), :mod:`~gearvib.report.measured_resonances` (rises of the map,
classified), :mod:`~gearvib.report.measured_figures` (figures),
:mod:`~gearvib.report.measured_sections` (sections), :mod:`~gearvib.report.measured_nvh` (NVH
and summary pages) and :mod:`~gearvib.report.bearings` (fault lines).

This module holds the build (:func:`build_measured_report`, :class:`MeasuredReportPaths`) and
:func:`is_simulated_run`. The names it defined before the split (:func:`analyse_measurement`,
:class:`MeasuredCase`, :func:`measured_sections`, :data:`MEASURED_SECTION_IDS`, the figures,
:data:`MAX_LABEL_CHANCE`, :data:`MIN_SPEED_RATIO`, ...) are re-exported from their homes, so
that ``from gearvib.report.measured import ...`` keeps working; new code imports them from
their homes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import xarray as xr

from analysis.measurement import Measurement, load_measurement
from analysis.readers import ReaderError
from analysis.readers.ncimage import open_image
from gearvib.io import atomic_write
from gearvib.report.document import FigureImages
from gearvib.report.html import render_html
from gearvib.report.measured_analysis import MIN_SPEED_RATIO, analyse_measurement
from gearvib.report.measured_case import MeasuredCase
from gearvib.report.measured_figures import (  # noqa: F401  (re-exported)
    order_map_figure,
    record_figure,
    sonogram_figure,
    spectra_figure,
)
from gearvib.report.measured_nvh import measured_levels, with_level_pages
from gearvib.report.measured_peaks import (  # noqa: F401  (re-exported)
    MAX_LABEL_CHANCE,
    PEAK_HEADER,
    PEAK_RANGE_DB,
)
from gearvib.report.measured_resonances import MAX_RAYS  # noqa: F401  (re-exported)
from gearvib.report.measured_sections import (  # noqa: F401  (TITLES re-exported)
    MEASURED_SECTION_IDS,
    TITLES,
    measured_sections,
)
from gearvib.report.pdf import write_pdf
from gearvib.report.runner import check_output_dir
from gearvib.report.study import AnalysisSettings

__all__ = [
    "MEASURED_SECTION_IDS",
    "MeasuredCase",
    "MeasuredReportPaths",
    "analyse_measurement",
    "build_measured_report",
    "is_simulated_run",
    "measured_sections",
]


@dataclass(frozen=True)
class MeasuredReportPaths:
    """Files of a measured report and its content."""

    html: Path
    pdf: Path
    pdf_pages: int
    sections: tuple[str, ...]
    case: MeasuredCase = field(repr=False)
    levels: Any = field(default=None, repr=False)  # gearvib.report.nvh.SignalLevels


def build_measured_report(source: Measurement | str | os.PathLike | xr.Dataset,
                          out_dir: str | os.PathLike, *, gearset: Any = None,
                          channel: str | None = None, reference: str | None = None,
                          settings: AnalysisSettings | None = None, title: str | None = None,
                          envelope_band: Any = None, min_bandwidth: float | None = None,
                          **speed: Any) -> MeasuredReportPaths:
    """Analyse a measurement and write ``report.html`` and ``report.pdf`` into ``out_dir``.

    Parameters
    ----------
    source : Measurement, path or Dataset
        The measurement (a path or Dataset is loaded with
        :func:`analysis.measurement.load_measurement` and the ``speed`` keywords:
        ``tacho``, ``pulses_per_rev``, ``speed``, ``angle``, ``rpm``, ``rpm_from``, ``fs``,
        ``time_column``, ``calibration``, ``units``).
    out_dir : path-like
        Output folder (created when the files are written).
    gearset, channel, reference, settings, envelope_band, min_bandwidth
        See :func:`analyse_measurement`.
    title : str, optional
        Report title.

    Returns
    -------
    MeasuredReportPaths
    """
    m = source if isinstance(source, Measurement) else load_measurement(
        source, channel=channel, **speed)
    out = check_output_dir(out_dir)
    mc = analyse_measurement(m, gearset=gearset, channel=channel, reference=reference,
                             settings=settings, envelope_band=envelope_band,
                             min_bandwidth=min_bandwidth)
    levels = measured_levels(mc, min_speed_ratio=MIN_SPEED_RATIO)  # order cuts, Campbell, ...
    sections = with_level_pages(measured_sections(mc), mc, levels)  # summary first
    title = title or (f"Order-analysis report of the measurement {mc.name}"
                      + (f" ({mc.gearset_name})" if mc.gearset_name else ""))
    subtitle = (f"Channel {mc.channel}; speed reference: {m.reference}; "
                + (f"machine {mc.gearset_name} (shafts and bearings)." if mc.rig is not None
                   else f"gear set {mc.gearset_name}." if mc.gearset_name else "no gear set."))
    images = FigureImages()
    text = render_html(sections, title=title, subtitle=subtitle, images=images)
    out.mkdir(parents=True, exist_ok=True)
    html_path, pdf_path = out / "report.html", out / "report.pdf"
    pages = atomic_write(pdf_path, lambda tmp: write_pdf(sections, tmp, title=title,
                                                    subtitle=subtitle, images=images))
    atomic_write(html_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return MeasuredReportPaths(html=html_path, pdf=pdf_path, pdf_pages=int(pages),
                               sections=tuple(s.id for s in sections), case=mc, levels=levels)


def is_simulated_run(path: str | os.PathLike) -> bool:
    """True for a netCDF file written by the simulator (it has ``normal_force``).

    Only the header is read (netCDF4 parses a header without loading data); a file whose
    header cannot be read counts as a run, so that the run reader reports what is wrong.
    """
    try:
        with open_image(path) as nc:  # not the file itself: see analysis.readers.ncimage
            return "normal_force" in nc.variables
    except (OSError, ReaderError):
        return Path(path).is_file() and Path(path).suffix in (".nc", ".nc4")
