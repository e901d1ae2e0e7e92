"""Mesh phases of an assembled gear set, as written into a run's attributes and read back.

Every mesh starts at its mesh position at assembly ``s_0`` (paper eq. (3); computed from the
tooth geometry by :mod:`gearvib.assembly`). The phase that matters for the planet phasing is
the *relative* phase of a mesh against the first planet's mesh of the same kind (the same
central gear and planet toothing, or the same pair of planet groups): planet ``n`` lags planet
1 by ``gamma_n = (s_0,1 - s_0,n) mod 1`` mesh cycles, which for a central gear with signed tooth
number ``z`` and planet angles ``psi`` is ``frac(z (psi_n - psi_1) / 2 pi)``
(:func:`gearvib.geometry.mesh_phases`; Parker & Lin 2004, J. Mech. Des. 126(2):365-370).

A run stores the table as the attribute ``mesh_phases_json`` (:func:`mesh_phase_table`);
:func:`run_mesh_phases` reads it back from a Dataset or a file's attributes.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from typing import Any

from gearvib.checks import check_instance
from gearvib.model import AssembledModel

__all__ = ["ATTRIBUTE", "mesh_phase_table", "run_mesh_phases"]

ATTRIBUTE = "mesh_phases_json"
"""Name of the run attribute that holds the table."""

_DIGITS = re.compile(r"\d+$")


def _rounded(x: float) -> float:
    """``x`` in [0, 1) with values within 1e-12 of a whole cycle taken as 0."""
    v = float(x) % 1.0
    return 0.0 if min(v, 1.0 - v) < 1e-12 else v


def mesh_phase_table(model: AssembledModel) -> dict[str, dict[str, Any]]:
    """The phases of every mesh of an assembled model.

    Parameters
    ----------
    model : AssembledModel
        Built by :func:`gearvib.assembly.assemble` (its ``meta`` names the gears and planets).

    Returns
    -------
    dict
        ``{mesh name: {"gear", "planet", "carrier", "planet_angle_deg", "mesh_position",
        "relative_phase", "reference_mesh"}}`` in mesh order: the mesh's gears (``gear`` the
        central gear or first planet), the planet's carrier and angle on it [deg], the mesh
        position at assembly ``s_0`` [cycles, 0..1) and the lag behind ``reference_mesh``, the
        first mesh of the same kind, ``(s_0,ref - s_0) mod 1`` [cycles].

    Notes
    -----
    Meshes of one kind: the same central gear and the same tooth numbers (sun-planet,
    ring-planet, a stepped planet's second toothing), or planet-planet meshes between the same
    planet groups (planet names without their number) and tooth numbers.
    """
    check_instance(model, AssembledModel, "model")
    planets = {str(p["name"]): p for p in model.meta.get("planets", [])}
    out: dict[str, dict[str, Any]] = {}
    first: dict[tuple, tuple[str, float]] = {}
    for k, m in enumerate(model.meta.get("meshes", [])):
        g1, g2 = str(m["gear1"]), str(m["gear2"])
        p = planets.get(g2, {})
        kind = (g1 if g1 not in planets else "planet:" + _DIGITS.sub("", g1),
                _DIGITS.sub("", g2), m.get("z1"), m.get("z2"), p.get("carrier"))
        s0 = _rounded(model.mesh_position_offsets[k])
        ref, s_ref = first.setdefault(kind, (str(m["name"]), s0))
        out[str(m["name"])] = {
            "gear": g1, "planet": g2, "carrier": str(p.get("carrier", "")),
            "planet_angle_deg": float(p.get("angle_deg", math.nan)),
            "mesh_position": s0, "relative_phase": _rounded(s_ref - s0),
            "reference_mesh": ref,
        }
    return out


def run_mesh_phases(attrs: Any) -> dict[str, dict[str, Any]]:
    """The mesh-phase table of a run (:func:`mesh_phase_table`) read back.

    Parameters
    ----------
    attrs : xarray.Dataset or mapping
        A run Dataset (:func:`gearvib.io.read_run`) or its attributes.

    Raises
    ------
    ValueError
        When the run has no ``mesh_phases_json`` attribute (written before gearvib stored
        it) or it is not a table of meshes.
    """
    table = attrs.attrs if hasattr(attrs, "attrs") else attrs
    if not isinstance(table, Mapping) or ATTRIBUTE not in table:
        raise ValueError(f"the run has no {ATTRIBUTE} attribute (written by an older gearvib); "
                         "rebuild the model from its config_json to get the mesh phases")
    try:
        out = json.loads(str(table[ATTRIBUTE]))
    except json.JSONDecodeError as exc:
        raise ValueError(f"{ATTRIBUTE} is not valid JSON: {exc}") from None
    if not isinstance(out, dict) or not all(isinstance(v, dict) for v in out.values()):
        raise ValueError(f"{ATTRIBUTE} is not a table of meshes")
    return out
