"""What a run file holds for its report: configuration, run settings, drive and tooth forces.

A run-up Dataset (:func:`gearvib.simulate.simulate`, :func:`gearvib.io.read_run`) carries the
configuration it was simulated with in its ``config_json`` attribute: :func:`run_config` parses
it, :func:`caller_config` returns what the caller of ``simulate`` passed (``gearset``, ``run``,
``case``, ``analysis``), :func:`rebuild_model` rebuilds the gear set from it,
:func:`run_settings` and :func:`run_description` state the run, :func:`run_drive` returns the
drive coupling a speed-driven run was simulated with, and :func:`signed_force` the signed
normal force of a mesh.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import xarray as xr

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict
from gearvib.model import AssembledModel
from gearvib.simulation.conditions import DriveCoupling

__all__ = ["RPM_MIN_FRACTION", "caller_config", "rebuild_model", "run_config",
           "run_description", "run_drive", "run_settings", "signed_force"]


RPM_MIN_FRACTION = 0.02
"""Order tracking needs a speed > 0: the first 2 % of a run's speed range are skipped
(rpm-order map, map features, stability chart, simulated stiffness)."""


def run_config(ds: xr.Dataset) -> dict:
    """The configuration stored with a run (its ``config_json`` attribute, parsed).

    Parameters
    ----------
    ds : xarray.Dataset
        The run.

    Returns
    -------
    dict
        ``{}`` when the attribute is missing or is not a JSON object.
    """
    text = ds.attrs.get("config_json", "")
    if not text:
        return {}
    try:
        cfg = json.loads(text)
    except (TypeError, ValueError):
        return {}
    return cfg if isinstance(cfg, dict) else {}


def caller_config(cfg: dict) -> dict:
    """The configuration the caller of ``simulate`` passed (``{"gearset", "run", "case"}``).

    Parameters
    ----------
    cfg : dict
        The stored configuration (:func:`run_config`).

    Returns
    -------
    dict
        Its ``"model"`` entry (``{}`` if missing).
    """
    inner = cfg.get("model", {})
    return inner if isinstance(inner, dict) else {}


def rebuild_model(caller: dict) -> tuple[AssembledModel | None, str]:
    """The gear set of a run, rebuilt from its stored description.

    Parameters
    ----------
    caller : dict
        The caller's configuration (:func:`caller_config`): ``gearset`` (the description) and
        ``gearset_dir`` (folder of relative paths in it).

    Returns
    -------
    model : AssembledModel or None
        The assembled gear set, None when it cannot be rebuilt.
    why : str
        Why it could not be rebuilt (``""`` when it was).
    """
    gs_cfg = caller.get("gearset")
    if not isinstance(gs_cfg, dict):
        return None, ("the run does not carry its gear-set description (config_json has no "
                      "'gearset' entry); mode types, stiffness tables and the stability chart "
                      "are not available")
    base = caller.get("gearset_dir")
    try:
        gs = gearset_from_dict(gs_cfg, base=Path(base) if base else None)
        return assemble(gs), ""
    except (ValueError, OSError) as exc:
        return None, f"the stored gear-set description could not be rebuilt: {exc}"


def run_settings(caller: dict, ds: xr.Dataset) -> dict:
    """The run's settings: drive, speed range, duration, torque or motor, output sample rate.

    Parameters
    ----------
    caller : dict
        The caller's configuration (:func:`caller_config`); its ``run`` entry is used when it
        states a duration.
    ds : xarray.Dataset
        The run: the speeds it starts at and reaches, its duration and ``fs_out``.

    Returns
    -------
    dict
        ``drive``, ``speed_start_rpm``, ``speed_end_rpm`` (what the run reached for a torque or
        motor drive) [min^-1], ``duration`` [s], ``fs_out`` [Hz] and whatever else the run
        entry states.
    """
    run = caller.get("run")
    sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    t = np.asarray(ds["time"].values, dtype=float)
    if isinstance(run, dict) and "duration" in run:
        out = dict(run)
    else:
        out = {"speed_start_rpm": float(sp[0]), "speed_end_rpm": float(sp[-1]),
               "duration": float(t[-1] - t[0])}
    out.setdefault("drive", "speed")
    out.setdefault("speed_start_rpm", float(sp[0]))
    if out.get("speed_end_rpm") is None or out["drive"] != "speed":
        out["speed_end_rpm"] = float(sp.max())  # what the run reached
    out.setdefault("fs_out", float(ds.attrs.get("fs_out", 0.0)))
    return out


def run_drive(ds: xr.Dataset) -> DriveCoupling | None:
    """The drive coupling a speed-driven run was simulated with.

    It is read from the file's attributes; a run written before the sensing attribute existed
    had its coupling on the input member.

    Parameters
    ----------
    ds : xarray.Dataset
        The run.

    Returns
    -------
    DriveCoupling or None
        None (the default coupling) for any other run.
    """
    attrs = ds.attrs
    if attrs.get("drive") != "speed" or "drive_coupling_stiffness" not in attrs:
        return None
    try:
        return DriveCoupling(float(attrs["drive_coupling_stiffness"]),
                             float(attrs["drive_coupling_damping"]),
                             str(attrs.get("drive_coupling_sensing", "input")))
    except (KeyError, TypeError, ValueError):
        return None


def run_description(run: dict, ds: xr.Dataset | None = None) -> str:
    """One line on the run after its drive: ``"speed ramp 0 → 4000 min⁻¹ in 1 s, input torque
    60 N m"``, ``"constant input torque 20 N m for 1 s from 0 min⁻¹ (reached 2873 min⁻¹)"``,
    ``"induction motor (Kloss: ...) for 2 s (reached 1455 min⁻¹)"``."""
    drive = str(run.get("drive", "speed"))
    reached = ""
    if ds is not None and "input_speed" in ds:
        sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
        reached = f" (reached {sp.max():.0f} min⁻¹)"
    dur = float(run.get("duration", math.nan))
    load = run.get("load_torque")
    load_text = ""
    if isinstance(load, list | tuple):
        terms = [t for t in (f"{load[0]:g}" if load[0] else "",
                             f"{load[1]:g} ω" if load[1] else "",
                             f"{load[2]:g} ω|ω|" if load[2] else "") if t]
        load_text = (f", load torque {' + '.join(terms) or '0'} N m"
                     + (" (ω output speed [rad/s])" if load[1] or load[2] else ""))
    elif load is not None and drive != "speed":
        load_text = f", load torque {float(load):g} N m"
    if drive == "torque":
        return (f"constant input torque {float(run['input_torque']):g} N m for {dur:g} s from "
                f"{float(run.get('speed_start_rpm', 0.0)):g} min⁻¹{load_text}{reached}")
    if drive == "motor":
        m = run.get("motor") or {}
        if "synchronous_rpm" in m:
            motor = (f"induction motor (Kloss: synchronous {m['synchronous_rpm']:g} min⁻¹, "
                     f"breakdown torque {m['breakdown_torque']:g} N m at slip "
                     f"{m['breakdown_slip']:g})")
        elif m:
            motor = (f"motor characteristic ({len(m.get('speed_rpm', []))} points, "
                     f"{min(m['torque']):g} to {max(m['torque']):g} N m)")
        else:
            motor = "motor"
        return (f"{motor} for {dur:g} s from {float(run.get('speed_start_rpm', 0.0)):g} "
                f"min⁻¹{load_text}{reached}")
    torque = run.get("input_torque")
    tail = (f", input torque {float(torque):g} N m" if torque is not None and
            math.isfinite(float(torque)) else
            (f", load torque {float(load):g} N m" if load is not None else ""))
    return (f"speed ramp {float(run['speed_start_rpm']):g} → {float(run['speed_end_rpm']):g} "
            f"min⁻¹ in {dur:g} s{tail}")


def signed_force(ds: xr.Dataset, mesh: str) -> np.ndarray:
    """Normal force of a mesh: drive (left) flank positive, back (right) flank negative [N].

    Parameters
    ----------
    ds : xarray.Dataset
        The run (``normal_force(mesh, flank, time)``).
    mesh : str
        Mesh name.

    Returns
    -------
    ndarray
        ``F_left - F_right`` over time [N].
    """
    f = ds["normal_force"].sel(mesh=mesh)
    return np.asarray(f.sel(flank="left").values - f.sel(flank="right").values, dtype=float)

