"""Figure of the tooth-fault impact evidence (:mod:`analysis.diagnosis_impacts`).

Plotting only, like :mod:`analysis.plots`: :func:`impact_figure` takes an
:class:`analysis.diagnosis_impacts.ImpactCheck` and returns a :class:`matplotlib.figure.Figure`
built without pyplot.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from analysis.checks import require_instance

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from analysis.diagnosis_impacts import ImpactCheck

__all__ = ["impact_figure"]

_COLOURS = ("C3", "C2", "C1", "C4", "C5", "C6", "C8", "C9")


def _db(ratio: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore"):
        return 10.0 * np.log10(np.maximum(ratio, 1e-6))


def impact_figure(check: ImpactCheck, *, harmonics: int = 10,
                  figsize: tuple[float, float] = (9.0, 6.4)) -> Figure:
    """The squared envelope order spectrum and the band above the mesh harmonics.

    Top: the envelope's power over its local mean noise [dB] (grey) up to ``harmonics`` times
    the highest envelope family's order, each envelope family's harmonics marked (stems,
    labelled with the family and its chance; the dotted line is 6 dB). Bottom: the order
    spectrum above the mesh band over its noise [dB] (grey), each synchronous family's comb
    lines in colour.

    Parameters
    ----------
    check : ImpactCheck
        The result.
    harmonics : int
        Harmonics of the envelope families shown.
    figsize : (float, float)
        Figure size [in].
    """
    from matplotlib.figure import Figure

    require_instance(check, "analysis.diagnosis_impacts.ImpactCheck", "check")
    fig = Figure(figsize=figsize, layout="constrained")
    ax_e, ax_s = fig.subplots(2, 1)
    env = [e for e in check.evidence if e.method == "envelope"]
    syn = [e for e in check.evidence if e.method == "synchronous"]
    top = max((harmonics * e.fundamental for e in env), default=float(check.envelope_order[-1]))
    top = min(1.05 * top, float(check.envelope_order[-1]))
    keep = check.envelope_order <= top
    ax_e.plot(check.envelope_order[keep], _db(check.envelope_ratio[keep]), lw=0.5,
              color="0.6")
    step = float(check.envelope_order[1] - check.envelope_order[0])
    for j, e in enumerate(env):
        colour = _COLOURS[j % len(_COLOURS)]
        label = f"{e.family} (chance {e.chance:.2g}{', detected' if e.detected else ''})"
        k = np.arange(1, harmonics + 1)
        pos = k * e.fundamental
        pos = pos[pos <= top]
        idx = np.rint(pos / step).astype(np.int64)
        ax_e.vlines(pos, -15.0, _db(check.envelope_ratio[idx]), color=colour, lw=1.2,
                    alpha=0.8)
        ax_e.plot(pos, _db(check.envelope_ratio[idx]), "o", ms=4, color=colour, label=label)
    if env:
        ax_e.legend(fontsize=8, loc="upper right")
    ax_e.axhline(10.0 * math.log10(4.0), color="0.3", lw=0.7, ls=":")
    ax_e.set_xlim(0.0, top)
    ax_e.set_ylim(-15.0, None)
    ax_e.set_xlabel("order of the reference shaft [-]")
    ax_e.set_ylabel("power over noise [dB]")
    ax_e.set_title(f"{check.name}: squared envelope order spectrum without the mesh lattice "
                   f"(±{check.span:g} orders), {check.revolutions} revolutions", fontsize=10)
    ax_e.grid(True, alpha=0.3)
    lo, hi = check.band
    if check.order.size:
        ax_s.plot(check.order, _db(check.order_ratio), ".", ms=1.0, color="0.7")
        for j, e in enumerate(syn):
            colour = _COLOURS[(j + len(env)) % len(_COLOURS)]
            on = np.abs(check.order / e.fundamental - np.rint(check.order / e.fundamental)) \
                * e.fundamental < 0.5 / check.revolutions
            ax_s.plot(check.order[on], _db(check.order_ratio[on]), "o", ms=2.5, color=colour,
                      label=f"{e.family} comb (chance {e.chance:.2g}"
                            f"{', detected' if e.detected else ''})")
        if syn:
            ax_s.legend(fontsize=8, loc="upper right")
        ax_s.set_xlim(lo, hi)
        ax_s.set_ylim(-15.0, None)
    else:
        ax_s.text(0.5, 0.5, "no band above the mesh harmonics (they reach the sample rate's "
                  "limit)", transform=ax_s.transAxes, ha="center", va="center", fontsize=9)
    ax_s.set_xlabel("order of the reference shaft [-]")
    ax_s.set_ylabel("power over noise [dB]")
    ax_s.set_title(f"order spectrum above the mesh band (orders {lo:.0f}-{hi:.0f})",
                   fontsize=10)
    ax_s.grid(True, alpha=0.3)
    return fig
