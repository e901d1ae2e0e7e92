"""Input checks shared by the readers, spectra, order and instability tools.

Each check raises :class:`ValueError` whose message names the parameter (or channel) and what is
admissible, so that a user looking at a measured file knows what to fix.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

__all__ = [
    "renamed",
    "require_block_size",
    "require_choice",
    "require_colormap",
    "require_finite",
    "require_finite_blocks",
    "require_instance",
    "require_int",
    "require_mass_matrix",
    "require_monotonic",
    "require_positive",
    "require_real",
    "require_real_array",
    "require_same_length",
    "require_size",
    "require_square",
    "sample_rate",
    "shown",
    "time_or_rate",
    "uniform_rate",
]

#: Default ``block_size`` of the block-wise order analysis (samples per block).
BLOCK_SAMPLES = 1 << 15
_SMALL_BYTES = 1 << 20


def _real_values(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as an array of real numbers (its own dtype): a ragged nesting is a
    :class:`ValueError`, bool, str, complex or object values a :class:`TypeError`."""
    try:
        arr = np.asarray(values)
    except ValueError:  # a ragged nesting
        raise ValueError(f"{name} must be a rectangular array of real numbers") from None
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers; got dtype {arr.dtype}")
    return arr


def require_finite(values: ArrayLike, name: str) -> np.ndarray:
    """Return ``values`` as a float array; raise if it is empty or holds NaN/inf.

    Parameters
    ----------
    values : array_like
        Samples of a channel or a parameter.
    name : str
        Name used in the error message.

    Raises
    ------
    TypeError
        Not real numbers (bool, str, complex or object values: no silent conversion).
    ValueError
        Empty, or NaN/inf.
    """
    arr = _real_values(values, name)
    arr = arr.astype(float, copy=False)
    if arr.size == 0:
        raise ValueError(f"{name}: channel is empty (needs at least one sample)")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad.ravel())[0])
        raise ValueError(
            f"{name}: {int(bad.sum())} non-finite value(s) (NaN or inf), first at flat index "
            f"{first}; only finite values are admissible"
        )
    return arr


def shown(value: Any) -> str:
    """``repr`` of a value on one line, cut to 40 characters (an error message shows it)."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 40 else text[:37] + "..."


def require_positive(value: float, name: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float; raise unless it is finite and > 0 (or >= 0).

    A bool, a string or bytes is not a number (:class:`TypeError`); an integer too large for
    a float is refused like an infinite value.
    """
    if isinstance(value, bool | np.bool_ | str | bytes):
        raise TypeError(f"{name} = {shown(value)} is not admissible: must be a real number "
                        f"(got {type(value).__name__})")
    try:
        v = float(value)
    except OverflowError:
        v = math.inf
    ok = np.isfinite(v) and (v >= 0.0 if allow_zero else v > 0.0)
    if not ok:
        bound = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} = {shown(value)} is not admissible: must be finite and "
                         f"{bound}")
    return v


def require_real(value: Any, name: str) -> float:
    """Return ``value`` as float; raise unless it is one finite real number.

    A bool, a string or an array is not a number here (:class:`TypeError`, naming ``name``);
    NaN and inf raise :class:`ValueError`.
    """
    if isinstance(value, bool | np.bool_ | str | bytes) or not isinstance(
        value, int | float | np.integer | np.floating
    ):
        raise TypeError(
            f"{name} = {shown(value)} is not admissible: must be a real number "
            f"(got {type(value).__name__})"
        )
    try:
        v = float(value)
    except OverflowError:  # an integer of hundreds of digits
        v = math.inf
    if not np.isfinite(v):
        raise ValueError(f"{name} = {shown(value)} is not admissible: must be finite")
    return v


def require_real_array(
    values: Any, name: str, *, ndim: int | None = None, min_size: int = 1,
    max_abs: float | None = None, finite: bool = True,
) -> np.ndarray:
    """Return ``values`` as a finite float64 array, checked before any arithmetic on it.

    Parameters
    ----------
    values : array_like
        The argument.
    name : str
        Name of the parameter in messages.
    ndim : int, optional
        Required number of dimensions.
    min_size : int
        Fewest values admissible (an empty array has none).
    max_abs : float, optional
        Largest magnitude admissible (products or powers of larger values would overflow).
    finite : bool
        Refuse NaN and inf (a pass over the values); ``False`` leaves them to the caller.

    Raises
    ------
    TypeError
        Not real numbers: bool, complex, str or object dtype (no silent conversion).
    ValueError
        Wrong number of dimensions, too few values, NaN/inf, or a magnitude above
        ``max_abs``.
    """
    arr = _real_values(values, name)
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array; got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} needs at least {min_size} value(s); got {arr.size}")
    arr = arr.astype(np.float64, copy=False)
    if not arr.size or not (finite or max_abs is not None):
        return arr
    # the extremes in two passes without a temporary array (NaN and inf propagate to them);
    # the position of a bad value is searched for on failure only
    hi, lo = float(arr.max()), float(arr.min())
    if finite and not (np.isfinite(hi) and np.isfinite(lo)):
        first = int(np.flatnonzero(~np.isfinite(arr.ravel()))[0])
        raise ValueError(f"{name}: non-finite value (NaN or inf) at flat index {first}; only "
                         "finite values are admissible")
    if max_abs is not None and not max(hi, -lo) <= max_abs:
        first = int(np.flatnonzero(~(np.abs(arr.ravel()) <= max_abs))[0])
        raise ValueError(f"{name}: a magnitude above {max_abs:g} at flat index {first}; "
                         f"admissible: |value| <= {max_abs:g} (check the units)")
    return arr


def require_size(nbytes: float, what: str, parameters: str) -> None:
    """Raise unless ``nbytes`` (computed from the arguments) fit into the usable memory.

    Called *before* an allocation whose size follows from the arguments (a record's length,
    ``fs``, ``nfft``, ``samples_per_rev``, the number of orders ...), so that an absurd value
    gives a :class:`ValueError` naming ``parameters`` instead of a :class:`MemoryError`, a
    swapping machine or a killed process.

    Parameters
    ----------
    nbytes : float
        Bytes the call is about to allocate (may be astronomically large, or inf).
    what : str
        What needs them, for the message (``"the map (12 x 4096 x 2049 float64)"``).
    parameters : str
        The arguments that set the size, for the message (``"nfft"``, ``"rpm, fs"``).

    Notes
    -----
    The limit is :func:`analysis.readers.integrity.memory_budget`: 80 % of the smallest of
    the free memory, the cgroup limit and the address-space limit (``RLIMIT_AS``), the same
    rule the readers apply to a file's declared sizes. Sizes up to 1 MiB pass unchecked.
    """
    if nbytes <= _SMALL_BYTES:  # no system calls for the small buffers of block loops
        return
    from analysis.readers.integrity import format_bytes, memory_budget

    budget = memory_budget()
    if not nbytes <= budget:  # also catches NaN
        shown = format_bytes(nbytes) if np.isfinite(nbytes) else "unbounded memory"
        raise ValueError(
            f"{parameters}: {what} needs {shown}, more than the {format_bytes(budget)} this "
            "process can use; admissible: values giving a result that fits into memory "
            "(check their units)"
        )


def require_monotonic(values: ArrayLike, name: str, *, strict: bool = True) -> np.ndarray:
    """Raise unless ``values`` increase (strictly by default) along the last axis."""
    arr = require_finite(values, name)
    d = np.diff(arr, axis=-1)
    bad = d <= 0 if strict else d < 0
    if bad.any():
        i = int(np.flatnonzero(bad.ravel())[0])
        kind = "strictly increasing" if strict else "non-decreasing"
        raise ValueError(f"{name} must be {kind}; it is not between samples {i} and {i + 1}")
    return arr


def require_same_length(arrays: Sequence[np.ndarray], names: Sequence[str]) -> int:
    """Raise unless all arrays have the same length along their last axis."""
    shapes = [np.shape(a) for a in arrays]
    for a, shape in zip(names, shapes, strict=True):
        if not shape:
            raise ValueError(f"{a} must be an array with a time axis; got a scalar")
    lengths = [shape[-1] for shape in shapes]
    if not lengths:
        raise ValueError("require_same_length: no arrays given")
    if len(set(lengths)) > 1:
        desc = ", ".join(f"{n}: {k}" for n, k in zip(names, lengths, strict=True))
        raise ValueError(f"sample-count mismatch ({desc}); channels must have equal length")
    return lengths[0]


def sample_rate(time: np.ndarray, *, name: str = "time", rtol: float = 1e-6) -> float:
    """Sample rate [Hz] of a uniformly sampled time axis.

    Raises if the axis has fewer than two samples, is not increasing, or is not uniform within
    ``rtol`` of the mean step (a sample-rate mismatch between channels shows up here).
    """
    t = require_monotonic(time, name)
    if t.size < 2:
        raise ValueError(f"{name}: needs at least two samples to define a sample rate")
    d = np.diff(t)
    dt = (t[-1] - t[0]) / (t.size - 1)
    dev = np.max(np.abs(d - dt))
    if dev > rtol * dt + 1e-12 * abs(t[-1]):
        raise ValueError(
            f"{name} is not uniformly sampled: step deviates by {dev:.3g} s from the mean "
            f"{dt:.6g} s (allowed {rtol:g} relative); resample the channel first"
        )
    return 1.0 / dt


_Choice = TypeVar("_Choice", bound=str)


def require_choice(value: Any, allowed: tuple[_Choice, ...], name: str) -> _Choice:
    """Return ``value``; raise unless it is one of ``allowed``."""
    if value not in allowed:
        raise ValueError(f"{name} = {value!r} is not admissible: must be one of {allowed}")
    return value


def require_int(value: Any, name: str, minimum: int) -> int:
    """Return ``value`` as int; raise unless it is an integer (not a bool) >= ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < minimum:
        raise ValueError(f"{name} = {value!r} is not admissible: must be an integer >= {minimum}")
    return int(value)


def _class_name(cls: type) -> str:
    """``module.Name`` of a class as users import it (``xarray.Dataset``, not its home)."""
    module = cls.__module__
    if module == "builtins":
        return cls.__qualname__
    top = module.split(".")[0]
    if top in ("xarray", "numpy", "concurrent"):
        public = {"numpy": "numpy", "xarray": "xarray", "concurrent": "concurrent.futures"}[top]
        return f"{public}.{cls.__qualname__}"
    return f"{module}.{cls.__qualname__}"


def require_instance(value: Any, cls: type | str | tuple[type | str, ...], name: str) -> Any:
    """Return ``value``; raise :class:`TypeError` unless it is an instance of ``cls``.

    The message names the parameter and the expected type, e.g. ``"spectrum must be an
    analysis.spectrum.Spectrum; got int"``, instead of the ``AttributeError`` a missing
    attribute would give deep inside the function.

    Parameters
    ----------
    value : object
        The argument.
    cls : type, str or tuple of them
        The admissible class(es); a dotted name (``"analysis.maps.Campbell"``) matches a
        value whose class or one of its bases has that module and name, for a module that
        must not import the class's module at run time (the figure modules).
    name : str
        Name of the parameter in the message.
    """
    classes = cls if isinstance(cls, tuple) else (cls,)
    if not classes or not all(isinstance(c, type | str) for c in classes):
        raise TypeError("require_instance: cls must be a class, a dotted class name or a "
                        "tuple of them")
    dotted = {f"{c.__module__}.{c.__qualname__}" for c in type(value).__mro__}
    for c in classes:
        if (isinstance(c, str) and c in dotted) or (isinstance(c, type) and isinstance(value, c)):
            return value
    expected = " or ".join(c if isinstance(c, str) else _class_name(c) for c in classes)
    article = "an" if expected[0] in "aeiouxAEIOUX" else "a"  # "an xarray.Dataset"
    raise TypeError(f"{name} must be {article} {expected}; got {type(value).__name__}")


def require_colormap(cmap: Any, name: str = "cmap") -> Any:
    """Return ``cmap``; raise unless it names a registered matplotlib colormap (or is one).

    matplotlib's own error lists every colormap on several lines; this one is one line.
    """
    from matplotlib import colormaps
    from matplotlib.colors import Colormap

    if isinstance(cmap, Colormap):
        return cmap
    if not isinstance(cmap, str):
        raise TypeError(f"{name} must be the name of a matplotlib colormap; got "
                        f"{type(cmap).__name__}")
    if cmap not in colormaps:
        shown = cmap if len(cmap) <= 40 else cmap[:40] + "..."
        raise ValueError(f"{name} = {shown!r} is not a matplotlib colormap (e.g. 'viridis', "
                         "'magma', 'gray'; see matplotlib.colormaps)")
    return cmap


def require_block_size(block_size: int | None) -> int:
    """Checked ``block_size`` of the block-wise order analysis (default :data:`BLOCK_SAMPLES`)."""
    if block_size is None:
        return BLOCK_SAMPLES
    if isinstance(block_size, bool) or not isinstance(block_size, int | np.integer):
        raise ValueError(f"block_size = {block_size!r} must be an integer >= 1")
    if block_size < 1:
        raise ValueError(f"block_size = {block_size!r} must be an integer >= 1")
    return int(block_size)


def uniform_rate(time: Any, name: str = "time", rtol: float = 1e-6) -> float:
    """Sample rate [Hz] of a uniform time axis, checked block-wise (bounded memory).

    Unlike :func:`sample_rate` it never converts the whole axis at once, so it suits
    memory-mapped or very long axes.

    Parameters
    ----------
    time : array_like
        Float seconds, or a decoded axis (``datetime64``/``timedelta64``, as
        ``xarray.open_dataset`` gives for CF time units), counted from its first sample.
    name : str
        Name of the axis in messages.
    rtol : float
        Admissible deviation of every step from the mean step, relative to the step.

    Notes
    -----
    Every step ``t[k+1] - t[k]`` must equal the mean step ``dt = (t[-1] - t[0]) / (n - 1)``
    within ``rtol * dt`` plus the resolution of the representation: ``1e-12 |t[-1]|`` for float
    seconds (the rounding of large values), two quanta of a decoded axis (its unit, 1 ns for
    ``datetime64[ns]``; a decoder rounds every sample to it, so a step of 1/51200 s =
    19531.25 ns is stored as 19531 or 19532 ns). A real gap or a second sample rate deviates
    by a fraction of the step, far above that.
    """
    t = np.asarray(time)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"{name}: needs a 1-D axis with at least two samples")
    decoded = t.dtype.kind in "mM"
    if not decoded and not np.issubdtype(t.dtype, np.number):
        raise ValueError(f"{name}: must be numeric seconds (units 's'), got dtype {t.dtype}")
    n = t.size
    if decoded:
        unit, count = np.datetime_data(t.dtype)
        # the stubs want a literal unit; datetime_data gives it as a str
        quantum = float(np.timedelta64(count, unit) / np.timedelta64(1, "s"))  # type: ignore[call-overload]
        origin = t[0]

        def seconds(seg: np.ndarray) -> np.ndarray:
            return np.asarray((seg - origin) / np.timedelta64(1, "s"), dtype=float)

        first, last = 0.0, float(seconds(t[-1:])[0])
        resolution = 2.0 * quantum
    else:

        def seconds(seg: np.ndarray) -> np.ndarray:
            return np.asarray(seg, dtype=float)

        first, last = float(t[0]), float(t[-1])
        resolution = 1e-12 * abs(last)
    dt = (last - first) / (n - 1)
    if not np.isfinite(dt) or dt <= 0:
        raise ValueError(f"{name} must be finite and strictly increasing")
    tol = rtol * dt + resolution
    block = 1 << 18
    for start in range(0, n - 1, block):
        seg = seconds(t[start : min(n, start + block + 1)])
        if not np.all(np.isfinite(seg)):
            raise ValueError(f"{name}: non-finite value near sample {start}")
        d = np.diff(seg)
        if np.any(d <= 0):
            i = start + int(np.flatnonzero(d <= 0)[0])
            raise ValueError(
                f"{name} must be strictly increasing; it is not between samples {i} and {i + 1}"
            )
        dev = float(np.max(np.abs(d - dt)))
        if dev > tol:
            raise ValueError(
                f"{name} is not uniformly sampled: step deviates by {dev:.3g} s from the mean "
                f"{dt:.6g} s (allowed {rtol:g} relative"
                + (f" plus {resolution:.3g} s, two quanta of its {t.dtype}" if decoded else "")
                + "); resample the channel first"
            )
    return 1.0 / dt


def require_finite_blocks(x: np.ndarray, name: str, bound: float | None = None) -> None:
    """Raise if ``x`` is empty or holds NaN/inf; works block-wise along the last axis.

    With ``bound``, a magnitude above it is refused too (its powers would overflow float64).
    The message names the channel (its index for a multi-channel array) and the time sample.
    """
    require_instance(x, np.ndarray, name)
    if x.ndim == 0:
        raise ValueError(f"{name} must be an array with a time axis; got a 0-d array")
    if x.dtype.kind not in "biufc":
        raise TypeError(f"{name} must hold real numbers; got dtype {x.dtype}")
    if x.size == 0:
        raise ValueError(f"{name}: channel is empty (needs at least one sample)")
    n = x.shape[-1]
    step = max(1, (1 << 20) // max(1, x.size // max(n, 1)))
    kind = np.dtype(x.dtype).kind
    if kind not in "fc" or bound is None or float(np.finfo(x.dtype).max) <= bound:
        bound = None  # integers and narrow floats never exceed it
    for start in range(0, n, step):
        blk = x[..., start : start + step]
        bad = ~np.isfinite(blk)
        if bound is not None and not bad.any():
            bad = np.abs(blk) > bound
            if not bad.any():
                continue
            what, hint = f"a magnitude above {bound:g}", "check its units and scaling"
        elif bad.any():
            what, hint = "non-finite value (NaN or inf)", "gap-fill or trim the channel first"
        else:
            continue
        where = np.argwhere(bad)[0]
        idx = start + int(where[-1])
        channel = f" of channel {tuple(int(i) for i in where[:-1])}" if x.ndim > 1 else ""
        raise ValueError(
            f"{name}: {what} at time sample {idx}{channel}; only finite values"
            f"{'' if bound is None else f' up to {bound:g}'} are admissible ({hint})"
        )


def renamed(
    new: Any, old: Any, new_name: str, old_name: str, function: str, stacklevel: int = 3
) -> Any:
    """Value of a renamed keyword: ``new``, or ``old`` with a :class:`FutureWarning`.

    The old name is accepted for one release; the warning is attributed to the caller of
    ``function`` (``stacklevel=3`` when ``function`` calls this directly).
    """
    if old is None:
        return new
    if new is not None:
        raise ValueError(f"{function}: give {new_name}= only ({old_name}= is its old name)")
    warnings.warn(
        f"{function}: {old_name}= is deprecated and will be removed in the next release; "
        f"use {new_name}=",
        FutureWarning,
        stacklevel=stacklevel,
    )
    return old


def time_or_rate(fs: Any, time: Any, function: str) -> tuple[Any, Any]:
    """``(fs, time)``, accepting the old call with the time axis as second argument.

    Every function now takes ``fs`` second (as MATLAB does); an array there is taken as
    ``time`` with a :class:`FutureWarning` for one release.
    """
    if fs is not None and np.ndim(fs) >= 1 and np.size(fs) > 1:
        if time is not None:
            raise ValueError(f"{function}: fs must be a number (Hz); the time axis goes to time=")
        warnings.warn(
            f"{function}: a time axis as the second argument is deprecated and will be an "
            "error in the next release; the second argument is fs (Hz): pass time=<axis>",
            FutureWarning,
            stacklevel=3,
        )
        return None, fs
    return fs, time


def require_square(a: Any, name: str, n: int | None = None) -> np.ndarray:
    """A finite square matrix (a scalar is 1 x 1), of size ``n`` when given."""
    arr = require_finite(a, name)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name} must be a square (n, n) matrix; got shape {arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(
            f"{name} has shape {arr.shape} but M is ({n}, {n}); all matrices must have the "
            "same size"
        )
    return arr


def require_mass_matrix(M: Any) -> np.ndarray:
    """The mass matrix ``M``: finite, square, symmetric and positive definite."""
    m = require_square(M, "M")
    if not np.allclose(m, m.T, rtol=1e-10, atol=1e-14 * np.abs(m).max()):
        raise ValueError("M must be symmetric (M == M.T within 1e-10 relative)")
    try:
        np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        raise ValueError("M must be positive definite (all eigenvalues > 0)") from None
    return m
