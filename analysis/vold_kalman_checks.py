"""Input checks and speed references of :mod:`analysis.vold_kalman`.

Numbers that refuse bools and strings (``TypeError`` naming the parameter), positions in a
list of orders, the speed references of one or several shafts as angles and speeds, and the
memory of a result, computed before anything as long as the record is allocated.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

from analysis.checks import require_instance, require_int, require_size
from analysis.inputs import Signal, reference_input
from analysis.speed import from_angle, from_rpm, from_tacho

__all__ = [
    "elements",
    "per_order",
    "positions",
    "real_number",
    "real_numbers",
    "reference_lengths",
    "result_bytes",
    "shaft_list",
    "shaft_positions",
    "speed_references",
]


def real_number(value: Any, name: str) -> float:
    """A real number (not a bool, not a string), as float."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} = {value!r} must be a real number, not {type(value).__name__}")
    v = float(value)
    if not np.isfinite(v):
        raise ValueError(f"{name} = {value!r} is not admissible: must be finite")
    return v


def real_numbers(values: Any, name: str) -> np.ndarray:
    """A number or a sequence of numbers as a 1-D float array (bools and strings refused)."""
    if isinstance(values, str | bytes):
        raise TypeError(f"{name} = {values!r} must be numbers, not a string")
    arr = np.asarray(values, dtype=object) if not isinstance(values, np.ndarray) else values
    if arr.dtype == object or arr.dtype.kind in "bUSV":
        flat = np.ravel(arr) if arr.ndim else [arr.item()]
        return np.array([real_number(v, name) for v in flat], dtype=float)
    if not np.issubdtype(arr.dtype, np.number) or np.iscomplexobj(arr):
        raise TypeError(f"{name} must be real numbers; got dtype {arr.dtype}")
    out = np.asarray(arr, dtype=float).ravel()
    if not np.all(np.isfinite(out)):
        raise ValueError(f"{name} = {values!r} is not admissible: must be finite")
    return out


def per_order(values: np.ndarray, m: int, name: str) -> np.ndarray:
    """One value per order: ``values`` of one element repeated ``m`` times, or ``m`` values."""
    require_instance(values, np.ndarray, name)
    if values.ndim != 1:
        raise ValueError(f"{name} must be 1-D (one value, or one per order); got shape "
                         f"{values.shape}")
    m = require_int(m, "m", 1)
    if values.size == 1:
        require_size(8.0 * m, f"{m} values per order", "m")
        return np.full(m, values[0])
    if values.size != m:
        raise ValueError(f"{name}: {values.size} values for {m} orders; give one or one per order")
    return values


def elements(values: Any) -> list[Any]:
    """The elements of a scalar, a sequence or an array, as given (bools stay bools)."""
    if isinstance(values, list | tuple):
        return list(values)
    if np.ndim(values) == 0:
        return [values.item() if isinstance(values, np.ndarray) else values]
    arr = np.asarray(values)
    return [bool(v) for v in arr.ravel()] if arr.dtype == bool else list(arr.ravel())


def positions(which: Any, m: int, name: str) -> list[int]:
    """Sorted positions in a list of ``m`` orders (all for ``None``); integers only."""
    if which is None:
        return list(range(m))
    out = []
    for v in elements(which):
        if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
            raise TypeError(f"{name} = {which!r}: positions in orders (integers) are needed")
        if not 0 <= int(v) < m:
            raise ValueError(f"{name} = {which!r}: a position must be in [0, {m})")
        out.append(int(v))
    return sorted(set(out))


def shaft_list(ref: Any, n: int) -> list[Any]:
    """The references of one or several shafts as a list (one entry per shaft)."""
    if isinstance(ref, list | tuple):
        if not ref:
            raise ValueError("an empty list of speed references was given")
        return list(ref)
    if hasattr(ref, "dims"):  # DataArray: one shaft
        return [ref]
    arr = np.asarray(ref)
    if arr.ndim == 2:
        if arr.shape[1] == n:
            return list(arr)
        if arr.shape[0] == n:
            return list(arr.T)
        raise ValueError(
            f"sample-count mismatch: speed reference of shape {arr.shape} for {n} samples; "
            "give (shafts, samples) or (samples, shafts)"
        )
    return [ref]


def reference_lengths(ref: Any) -> tuple[int, ...]:
    """Sample counts of a speed reference (they single out the time axis of ``x``): the
    length of a 1-D reference or of the list's entries, the longer side of a 2-D array."""
    if ref is None:
        return ()
    if isinstance(ref, list | tuple):
        return tuple(int(np.shape(r)[-1]) for r in ref if np.ndim(r) == 1)
    shape = np.shape(ref)
    return (int(max(shape)),) if len(shape) in (1, 2) else ()


def speed_references(
    sig: Signal,
    rpm: Any,
    angle: Any,
    tacho: Any,
    pulses_per_rev: Any,
    missing_teeth: Any,
    time: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, str]:
    """Angles and speeds ``(shaft, time)`` of the speed references, and their description."""
    require_instance(sig, Signal, "sig")
    given = [k for k, v in (("rpm", rpm), ("angle", angle), ("tacho", tacho)) if v is not None]
    if len(given) > 1:
        raise ValueError(f"give one speed reference (rpm=, angle= or tacho=), not {given}")
    n = sig.n
    angles, speeds, labels = [], [], []
    if tacho is not None:
        for v in pulses_per_rev if isinstance(pulses_per_rev, list | tuple) else [pulses_per_rev]:
            if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
                raise TypeError(f"pulses_per_rev = {pulses_per_rev!r} must be integers >= 1")
        pulses = shaft_list(tacho, n)
        ppr = list(pulses_per_rev) if isinstance(pulses_per_rev, list | tuple) else None
        for i, p in enumerate(pulses):
            arr = np.asarray(p)
            if arr.ndim != 1 or arr.size != n:
                raise ValueError(
                    f"sample-count mismatch (x: {n}, tacho[{i}]: {arr.size}); a tacho must be "
                    "1-D, sampled with x"
                )
            if not np.issubdtype(arr.dtype, np.number) or arr.dtype == bool:
                raise TypeError(f"tacho[{i}] must be real numbers; got dtype {arr.dtype}")
            per = ppr[i] if ppr is not None else pulses_per_rev
            ref = from_tacho(
                arr, sig.fs, per, missing_teeth=missing_teeth, output_time=time - time[0]
            )
            angles.append(ref.angle)
            speeds.append(ref.rpm)
            labels.append(f"tacho {i} ({per} pulses/rev)")
        return np.array(angles), np.array(speeds), ", ".join(labels)
    kind = "rpm" if rpm is not None else ("angle" if angle is not None else None)
    items = shaft_list(rpm if rpm is not None else angle, n) if kind else [None]
    for i, item in enumerate(items):
        given_ref = reference_input(
            item if kind == "rpm" else None,
            item if kind == "angle" else None,
            n,
            required=True,
            signal=sig if kind is None else None,
        )
        assert given_ref is not None  # required=True raises instead of returning None
        values = np.asarray(given_ref.values, dtype=float)
        label = given_ref.label if len(items) == 1 else f"{given_ref.label} (shaft {i})"
        if given_ref.kind == "rpm":
            if float(values.min()) < 0.0:
                j = int(np.argmin(values))
                raise ValueError(
                    f"rpm must be >= 0 (rotation in one direction); rpm[{j}] = {values[j]:.6g}"
                    f"{'' if len(items) == 1 else f' of shaft {i}'}. Negate a reference of "
                    "reverse rotation"
                )
            sr = from_rpm(time, values)
        else:
            sr = from_angle(time, values)
        angles.append(sr.angle)
        speeds.append(sr.rpm)
        labels.append(label)
    return np.array(angles), np.array(speeds), ", ".join(labels)


def result_bytes(nch: int, m: int, n: int, shafts: int) -> int:
    """Bytes of the result arrays (envelopes, waveforms, residual, angles and speeds, time),
    of the float copy of the input and of the temporaries of the speed references and of
    the waveforms (about six arrays of ``n``)."""
    return 8 * n * (nch * m * 3 + nch * 2 + shafts * 2 + m + 7)


def shaft_positions(shafts: Any, m: int, n_shafts: int) -> list[int]:
    """Speed reference of each of ``m`` orders: one integer for all, or one per order, each
    in ``[0, n_shafts)``."""
    items = [shafts] * m if np.ndim(shafts) == 0 else elements(shafts)
    if len(items) != m:
        raise ValueError(f"shafts: {len(items)} values for {m} orders; give one per order")
    out = []
    for v in items:
        if isinstance(v, bool | np.bool_) or not isinstance(v, numbers.Integral):
            raise TypeError(f"shafts = {shafts!r}: integers (speed reference indices) needed")
        if not 0 <= int(v) < n_shafts:
            raise ValueError(
                f"shafts = {shafts!r}: an index must be in [0, {n_shafts}) ({n_shafts} speed "
                "reference(s) given)"
            )
        out.append(int(v))
    return out
