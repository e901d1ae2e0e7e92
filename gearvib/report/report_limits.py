"""Limits of a report checked before a run is simulated or analysed: the memory of its maps
(:func:`check_report_size`), the duration its maps need (:func:`check_report_duration`) and
the finest order-cut resolution the run admits (:func:`check_cut_resolution`).

Each raises :class:`gearvib.config.ConfigError` naming the quantity, the admissible value and
the option that changes it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from gearvib.config import ConfigError
from gearvib.memory import require_memory

if TYPE_CHECKING:
    from gearvib.report.study import AnalysisSettings

__all__ = ["MAP_COPIES", "MIN_MAP_FRAMES", "check_cut_resolution", "check_report_duration",
           "check_report_size"]

MIN_MAP_FRAMES = 8
"""A report needs at least this many frames of its rpm-frequency map (shorter runs are refused
before they are simulated: :func:`check_report_duration`)."""
MAP_COPIES = 4
"""Peak memory of a map as multiples of its frames x bins (map, dB, Dataset, image)."""


def check_report_size(n_samples: int, fs: float, settings: AnalysisSettings,
                      where: str = "the run") -> None:
    """Refuse maps whose frames would not fit into memory (before simulating or analysing).

    The rpm-frequency map of a run of ``n_samples`` at ``fs`` has ``(n - seg) // hop + 1``
    frames of ``seg // 2 + 1`` bins, with the Hann window ``seg = 1.5 fs / map_resolution_hz``
    and ``hop = seg (1 - map_overlap)`` (as :func:`analysis.frames.frame_layout`); the
    rpm-order map has about as many. An overlap near 1 or a fine resolution of a long run
    multiplies the frames.

    Raises
    ------
    gearvib.memory.RunSizeError
        Naming ``map_overlap`` and ``map_resolution_hz``, the frames and the memory needed.
    """
    n = max(int(n_samples), 1)
    seg_f = 1.5 * fs / settings.map_resolution_hz
    seg = max(4, min(n, round(seg_f) if math.isfinite(seg_f) else n))
    hop = max(1, round(seg * (1.0 - settings.map_overlap)))
    frames = (n - seg) // hop + 1
    bins = seg // 2 + 1
    need = 2 * MAP_COPIES * 8 * frames * bins  # rpm-frequency and rpm-order map
    require_memory(need, f"the maps of {where} ({frames} frames of {bins} bins: "
                   f"map_overlap = {settings.map_overlap:g}, map_resolution_hz = "
                   f"{settings.map_resolution_hz:g} over {n} samples at {fs:g} Hz)",
                   "lower [analysis].map_overlap (0.9 gives a smooth map) or coarsen "
                   "map_resolution_hz")


def check_cut_resolution(revolutions: float, settings: AnalysisSettings,
                         where: str = "the run") -> None:
    """Refuse an ``order_resolution`` finer than a run of ``revolutions`` admits (before it is
    simulated or analysed; :func:`analysis.runup_levels.finest_order_resolution`).

    Raises
    ------
    ConfigError
        Naming the resolution, the finest admissible and ``--order-resolution``.
    """
    from analysis.runup_levels import finest_order_resolution

    res = settings.order_resolution
    if not res:
        return
    finest = finest_order_resolution(revolutions)
    if res < finest:
        raise ConfigError(
            f"{where}: order_resolution = {res:g} orders needs a longer run: the input shaft "
            f"turns {revolutions:.4g} revolutions, admissible >= "
            f"{math.ceil(finest * 1000) / 1000:g} orders (--order-resolution; 0 for automatic)")


def _map_frames(n: int, fs: float, settings: AnalysisSettings) -> tuple[int, int, int]:
    """Frames, segment and hop [samples] of the report's rpm-frequency map."""
    seg_f = 1.5 * fs / settings.map_resolution_hz
    seg = max(4, round(seg_f) if math.isfinite(seg_f) else n)
    hop = max(1, round(seg * (1.0 - settings.map_overlap)))
    frames = (n - seg) // hop + 1 if n >= seg else 0
    return frames, seg, hop


def check_report_duration(n_samples: int, fs: float, settings: AnalysisSettings,
                          where: str = "the run") -> None:
    """Refuse a run too short for the report's maps, before it is simulated or analysed.

    The rpm-frequency map (Hann, ``1.5 fs / map_resolution_hz`` samples per frame, hop
    ``(1 - map_overlap)`` of a frame) needs :data:`MIN_MAP_FRAMES` frames; the resonance
    detection, the waterfall and the overall level read them.

    Raises
    ------
    ConfigError
        Naming the duration, the minimum and ``--duration``.
    """
    n = max(int(n_samples), 1)
    frames, seg, hop = _map_frames(n, fs, settings)
    if frames >= MIN_MAP_FRAMES:
        return
    need = (seg + (MIN_MAP_FRAMES - 1) * hop) / fs
    raise ConfigError(
        f"{where} lasts {(n - 1) / fs:.4g} s, too short for the report's maps: they need at least "
        f"{MIN_MAP_FRAMES} frames of {seg / fs:.4g} s (map_resolution_hz = "
        f"{settings.map_resolution_hz:g}, map_overlap = {settings.map_overlap:g}), a duration "
        f"of at least {math.ceil(need * 1000) / 1000:g} s (--duration)")
