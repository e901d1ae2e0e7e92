"""Checks of the numbers in a description: type, finiteness and admissible range.

Gear-set tables (:mod:`gearvib.config`), run settings (:mod:`gearvib.simulation.settings`),
study recipes (:mod:`gearvib.report.study`) and the fault and sensor descriptions
(:mod:`gearvib.faults.description`, :mod:`gearvib.sensors.description`) take numbers from TOML
files and from Python. :func:`check_number` and :func:`check_integer` apply one set of rules to
them: a bool or a string is not a number, an integer too large for a float is refused, so are NaN
and infinities, and the bounds are checked. A refused value raises the caller's error class with
a message that names the key, the value and what is admissible.

The messages of those layers have different wordings, which their tests and their users rely
on; a :class:`Wording` selects one (:data:`TABLE`, :data:`RUN`, :data:`RECIPE`, :data:`ITEM`).

The arguments of the Python API (constructors and functions a script calls) are checked with
:func:`check_real`, :func:`check_count`, :func:`check_text`, :func:`check_items`,
:func:`check_instance` and :func:`check_array` at the public boundary, before any work: numpy
scalars count as numbers there, a value shown in a message is cut to 40 characters
(:func:`short`), and the message names the parameter. :func:`check_instance` and
:func:`check_array` apply the rules and wording of :func:`analysis.checks.require_instance`
and :func:`analysis.checks.require_real_array`: the model and simulation layers do not import
the ``analysis`` package, whose import registers its xarray accessor and so imports xarray
(``gearvib modes`` and ``gearvib simulate`` stay without it).

Examples
--------
>>> check_number(0.5, "[simulation].duration", low=1e-6, wording=RUN)
0.5
>>> check_number(-1, "[[fault]] #1 (crack): depth", low=0.0, high=1.0, symbol="depth",
...              wording=ITEM)
Traceback (most recent call last):
...
ValueError: [[fault]] #1 (crack): depth = -1.0 is not admissible (admissible: 0 <= depth <= 1)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, SupportsFloat, cast

import numpy as np

__all__ = [
    "API",
    "ITEM",
    "NUMBER_TYPES",
    "RECIPE",
    "RUN",
    "TABLE",
    "Wording",
    "check_array",
    "check_config",
    "check_count",
    "check_frequencies",
    "check_instance",
    "check_integer",
    "check_items",
    "check_matrix",
    "check_number",
    "check_path",
    "check_real",
    "check_text",
    "check_vector",
    "cut",
    "short",
]

NUMBER_TYPES: tuple[type, ...] = (int, float, np.integer, np.floating)
"""What the Python API takes for a number (a bool, ``np.bool_``, str or bytes is none)."""


def short(value: Any, limit: int = 40) -> str:
    """``repr`` of a value on one line, shortened to ``limit`` characters for a one-line
    message."""
    text = repr(value)
    if "\n" in text:
        text = " ".join(text.split())
    return cut(text, limit)


def cut(text: str, limit: int = 40) -> str:
    """A name as a message shows it: whole, or its first ``limit - 3`` characters and
    ``...``."""
    return text if len(text) <= limit else text[:limit - 3] + "..."


@dataclass(frozen=True)
class Wording:
    """How a refused number is worded.

    Attributes
    ----------
    finite : str
        What a NaN or an infinity is told is admissible.
    nan_named : bool
        A NaN is refused as ``"<name> is NaN; admissible: <finite>"``.
    interval : bool
        A number's admissible range is written whole, around the quantity's ``symbol``
        (``0 <= depth <= 1``), instead of by the one bound it violates (``>= 0``).
    full : bool
        Refused values are shown whole (``repr``, up to 200 characters; an integer too large
        for a float by its first 20 digits and its number of digits) instead of shortened to
        40 characters.
    terse : bool
        ``"<name> = <value>; admissible: a number >= 0"`` instead of ``"<name> = <value> is not
        admissible (admissible: >= 0)"``, with the value as given; an integer is then refused
        with one message whatever is wrong.
    """

    finite: str = "a finite number"
    nan_named: bool = False
    interval: bool = False
    full: bool = False
    terse: bool = False

    def shown(self, value: Any) -> str:
        """The value as a message shows it."""
        return short(value, 200) if self.full else short(value)

    def refusal(self, name: str, shown: str, admissible: str) -> str:
        """The message refusing ``name = shown``."""
        if self.terse:
            return f"{name} = {shown}; admissible: {admissible}"
        return f"{name} = {shown} is not admissible (admissible: {admissible})"


TABLE = Wording(nan_named=True)
"""Gear-set tables (``[[body]]``, ``[[mesh]]``, ``[stages]`` ...): ``[mesh].phase is NaN``."""
RUN = Wording(finite="finite")
"""Run settings (``[simulation]``)."""
RECIPE = Wording(terse=True)
"""Study recipes (``[analysis]``, ``[run]``)."""
ITEM = Wording(finite="finite", interval=True, full=True)
"""``[[fault]]`` and ``[[sensor]]`` items."""
API = Wording(finite="finite")
"""Arguments of the Python API (:func:`check_real`)."""


def check_number(value: Any, name: str, *, low: float | None = None,
                 high: float | None = None, low_open: bool = False, high_open: bool = False,
                 magnitude: bool = False, symbol: str | None = None,
                 error: type[Exception] = ValueError, types: tuple[type, ...] = (int, float),
                 wording: Wording = TABLE) -> float:
    """Return ``value`` as a finite float in the admissible range; raise ``error`` otherwise.

    Parameters
    ----------
    value : Any
        The value as given (a bool is never a number).
    name : str
        The key as the message names it (``"[simulation].duration"``).
    low, high : float, optional
        Admissible bounds, ``low <= value <= high``.
    low_open, high_open : bool
        The bound itself is not admissible (``low < value``, ``value < high``).
    magnitude : bool
        ``high`` bounds ``|value|`` and is written ``|symbol| <= high``.
    symbol : str, optional
        The quantity in a written range (``depth`` of ``0 <= depth <= 1``).
    error : type
        The exception class raised.
    types : tuple of type
        The admissible types (numpy scalars only where the caller lists them).
    wording : Wording
        How the message is worded.

    Returns
    -------
    float
    """
    if isinstance(value, bool) or not isinstance(value, types):
        raise error(f"{name} must be a number, got {wording.shown(value)}")
    try:
        v = float(cast(SupportsFloat, value))  # one of the number types
    except OverflowError:  # an integer of hundreds of digits
        text = str(value)
        shown = f"{text[:20]}... ({len(text)} digits)" if wording.full else short(value)
        raise error(wording.refusal(name, shown, "a finite number")) from None
    if not math.isfinite(v):
        if wording.nan_named and math.isnan(v):
            raise error(f"{name} is NaN; admissible: {wording.finite}")
        shown = short(value) if wording.terse else repr(v)
        raise error(wording.refusal(name, shown, wording.finite))
    too_low = low is not None and (v < low or (low_open and v == low))
    size = abs(v) if magnitude else v
    too_high = high is not None and (size > high or (high_open and size == high))
    if not (too_low or too_high):
        return v
    lower = "<" if low_open else "<="
    upper = "<" if high_open else "<="
    if wording.interval:
        lo = "" if low is None else f"{low:g} {lower} "
        hi = "" if high is None else f" {upper} {high:g}"
        quantity = f"|{symbol}|" if magnitude else symbol
        admissible = f"{lo}{quantity}{hi}"
    elif too_low:
        admissible = f"{'>' if low_open else '>='} {low:g}"
    else:
        admissible = f"|{symbol}| {upper} {high:g}" if magnitude else f"{upper} {high:g}"
    if wording.terse:
        raise error(wording.refusal(name, repr(value), f"a number {admissible}"))
    raise error(wording.refusal(name, repr(v), admissible))


def check_integer(value: Any, name: str, *, low: int | None = None, high: int | None = None,
                  error: type[Exception] = ValueError, types: tuple[type, ...] = (int, float),
                  wording: Wording = TABLE) -> int:
    """Return ``value`` as an int in ``low .. high``; raise ``error`` otherwise.

    A float is an integer if it has no fraction (where ``types`` admits floats); the range is
    written by the bound that is violated (``>= 0``). Parameters as :func:`check_number`.

    Returns
    -------
    int
    """
    whole = not isinstance(value, bool) and isinstance(value, types) and not (
        isinstance(value, float) and not value.is_integer())
    if wording.terse:
        if not whole or (low is not None and value < low) or (high is not None and value > high):
            bounds = ([f">= {low}"] if low is not None else []) + (
                [f"<= {high}"] if high is not None else [])
            raise error(f"{name} = {short(value)}; admissible: an integer "
                        f"{' and '.join(bounds)}".rstrip())
        return int(value)
    if not whole:
        raise error(f"{name} must be an integer, got {wording.shown(value)}")
    v = int(value)
    if low is not None and v < low:
        raise error(wording.refusal(name, wording.shown(v), f">= {low}"))
    if high is not None and v > high:
        raise error(wording.refusal(name, wording.shown(v), f"<= {high}"))
    return v


def check_real(value: Any, name: str, *, low: float | None = None, high: float | None = None,
               low_open: bool = False, high_open: bool = False, allow_inf: bool = False,
               optional: bool = False, error: type[Exception] = ValueError) -> Any:
    """A number argument of the Python API as a float (:func:`check_number` with numpy
    scalars admitted and the :data:`API` wording).

    Parameters
    ----------
    value : Any
        The argument.
    name : str
        How the message names it (the parameter, e.g. ``"mass of body 'sun'"``).
    low, high, low_open, high_open
        Admissible range (as :func:`check_number`).
    allow_inf : bool
        ``+inf`` is admissible (a rigid stiffness, :data:`gearvib.structure.RIGID`).
    optional : bool
        ``None`` is admissible (returned as is).
    error : type
        Exception class raised.

    Returns
    -------
    float or None
    """
    if optional and value is None:
        return None
    if (allow_inf and isinstance(value, float | np.floating) and value == math.inf):
        return math.inf
    return check_number(value, name, low=low, high=high, low_open=low_open,
                        high_open=high_open, error=error, types=NUMBER_TYPES, wording=API)


def check_count(value: Any, name: str, *, low: int | None = None, high: int | None = None,
                optional: bool = False, error: type[Exception] = ValueError) -> Any:
    """An integer argument of the Python API in ``low .. high`` (an ``int`` or a numpy
    integer; a float, even a whole one, a bool or a string is refused), as an ``int``."""
    if optional and value is None:
        return None
    return check_integer(value, name, low=low, high=high, error=error,
                         types=(int, np.integer), wording=API)


def check_text(value: Any, name: str, *, optional: bool = False, empty: bool = False,
               error: type[Exception] = ValueError) -> Any:
    """A string argument (a name, a member, a kind): a ``str``, not empty unless ``empty``;
    ``None`` too if ``optional``."""
    if optional and value is None:
        return None
    if not isinstance(value, str):
        raise error(f"{name} must be a string, got {short(value)}")
    if not value and not empty:
        raise error(f"{name} must not be empty")
    return value


def check_items(values: Any, cls: type | str | tuple[type | str, ...], name: str, *,
                error: type[Exception] = TypeError) -> tuple:
    """A list or tuple whose items are all instances of ``cls`` (classes or dotted class
    names, as :func:`check_instance`), as a tuple.

    The message names the parameter, the item and the class expected (``bodies[2] must be a
    Body; got str``) instead of the ``AttributeError`` a wrong item would raise later.
    """
    if not isinstance(values, Sequence) or isinstance(values, str | bytes):
        raise error(f"{name} must be a list or tuple, got {short(values)}")
    classes = cls if isinstance(cls, tuple) else (cls,)
    expected = " or ".join(c.rsplit(".", 1)[-1] if isinstance(c, str) else c.__name__
                           for c in classes)
    for i, v in enumerate(values):
        dotted = {f"{c.__module__}.{c.__qualname__}" for c in type(v).__mro__}
        if not any((isinstance(c, str) and c in dotted) or (isinstance(c, type)
                                                            and isinstance(v, c))
                   for c in classes):
            raise error(f"{name}[{i}] must be a {expected}; got {type(v).__name__}")
    return tuple(values)


MAX_MATRIX = 10_000
"""Largest system matrix (rows) the Python API takes (eigenproblems are O(n^3))."""


def check_matrix(value: Any, name: str, n: int | None = None, *,
                 max_abs: float = 1e100) -> np.ndarray:
    """A finite square float matrix of at most :data:`MAX_MATRIX` rows (``n`` when given),
    whose entries are at most ``max_abs`` in magnitude (products stay finite)."""
    arr = check_array(value, name, ndim=2, max_abs=max_abs)
    if arr.shape[0] != arr.shape[1] or arr.shape[0] > MAX_MATRIX:
        raise ValueError(f"{name} must be a square (n, n) matrix, n <= {MAX_MATRIX}; got shape "
                         f"{arr.shape}")
    if n is not None and arr.shape[0] != n:
        raise ValueError(f"{name} must be ({n}, {n}); got shape {arr.shape}")
    return arr


def check_vector(value: Any, name: str, n: int, *, max_abs: float = 1e100) -> np.ndarray:
    """A finite float vector of ``n`` values of magnitude at most ``max_abs``."""
    arr = check_array(value, name, ndim=1, max_abs=max_abs)
    if arr.size != n:
        raise ValueError(f"{name} must hold {n} values; got {arr.size}")
    return arr


def check_config(config: Any, name: str = "config") -> Any:
    """A caller's configuration stored with a run: ``None``, a mapping, or the JSON text of
    one (parsed here, so that a run does not fail at its end)."""
    import json
    from collections.abc import Mapping

    if config is None or isinstance(config, Mapping):
        return config
    if not isinstance(config, str):
        raise TypeError(f"{name} must be a mapping or its JSON text; got "
                        f"{type(config).__name__}")
    try:
        value = json.loads(config)
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ValueError(f"{name} is not JSON text ({str(exc).splitlines()[0][:80]})") from None
    if not isinstance(value, dict):
        raise ValueError(f"{name} must be the JSON text of an object; got {short(value)}")
    return config


def check_frequencies(values: Any, name: str = "natural_frequencies") -> Any:
    """``None`` or a 1-D array of finite frequencies >= 0 [Hz] (at most 1e12 Hz each and
    :data:`MAX_MATRIX` of them)."""
    if values is None:
        return None
    arr = check_array(values, name, ndim=1, min_size=0, max_abs=1e12)
    if arr.size > MAX_MATRIX or (arr.size and arr.min() < 0):
        raise ValueError(f"{name} must be at most {MAX_MATRIX} frequencies >= 0 [Hz]")
    return arr


def check_path(value: Any, name: str) -> Path:
    """A file or folder name: a ``str`` or path-like, without NUL, at most 4096 characters
    and 255 per component (what POSIX file systems take); returned as a ``pathlib.Path``.

    The message shows the name cut to 200 characters (an ``OSError`` would echo it whole).
    """
    import os

    if not isinstance(value, str | os.PathLike):
        raise TypeError(f"{name} must be a path (str or path-like); got {type(value).__name__}")
    text = os.fspath(value)
    if not isinstance(text, str):
        raise TypeError(f"{name} must be a text path; got {type(text).__name__}")
    p = Path(text)
    if "\x00" in text or len(text) > 4096 or any(len(part) > 255 for part in p.parts):
        raise ValueError(f"{name} = {cut(repr(text), 200)} is not a usable file name (no NUL, "
                         "at most 4096 characters and 255 per part)")
    return p


def _class_name(cls: type) -> str:
    if cls.__module__ == "builtins":
        return cls.__qualname__
    return f"{cls.__module__}.{cls.__qualname__}"


def check_instance(value: Any, cls: type | str | tuple[type | str, ...], name: str) -> Any:
    """Return ``value``; raise :class:`TypeError` unless it is an instance of ``cls`` (a class,
    the dotted name of one -- for a module that must not import the class's module -- or a
    tuple of them): ``model must be a gearvib.model.AssembledModel; got GearSet``."""
    classes = cls if isinstance(cls, tuple) else (cls,)
    dotted = {f"{c.__module__}.{c.__qualname__}" for c in type(value).__mro__}
    for c in classes:
        if (isinstance(c, str) and c in dotted) or (isinstance(c, type) and isinstance(value, c)):
            return value
    expected = " or ".join(c if isinstance(c, str) else _class_name(c) for c in classes)
    article = "an" if expected[0] in "aeiouAEIOU" else "a"
    raise TypeError(f"{name} must be {article} {expected}; got {type(value).__name__}")


def check_array(values: Any, name: str, *, ndim: int | None = None, min_size: int = 1,
                max_abs: float | None = None, finite: bool = True) -> np.ndarray:
    """``values`` as a float64 array of real numbers, checked before any arithmetic on it.

    Parameters
    ----------
    values : array_like
        The argument.
    name : str
        Name of the parameter in messages.
    ndim : int, optional
        Required number of dimensions.
    min_size : int
        Fewest values admissible.
    max_abs : float, optional
        Largest magnitude admissible.
    finite : bool
        Refuse NaN and inf.

    Raises
    ------
    TypeError
        Not real numbers: bool, complex, str or object dtype (no silent conversion).
    ValueError
        A ragged nesting, wrong number of dimensions, too few values, NaN/inf, or a magnitude
        above ``max_abs``.
    """
    try:
        arr = np.asarray(values)
    except ValueError:  # a ragged nesting
        raise ValueError(f"{name} must be a rectangular array of real numbers") from None
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must hold real numbers; got dtype {arr.dtype}")
    if ndim is not None and arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array; got shape {arr.shape}")
    if arr.size < min_size:
        raise ValueError(f"{name} needs at least {min_size} value(s); got {arr.size}")
    arr = arr.astype(np.float64, copy=False)
    if not arr.size or not (finite or max_abs is not None):
        return arr
    hi, lo = float(arr.max()), float(arr.min())
    if finite and not (math.isfinite(hi) and math.isfinite(lo)):
        first = int(np.flatnonzero(~np.isfinite(arr.ravel()))[0])
        raise ValueError(f"{name}: non-finite value (NaN or inf) at flat index {first}; only "
                         "finite values are admissible")
    if max_abs is not None and not max(hi, -lo) <= max_abs:
        first = int(np.flatnonzero(~(np.abs(arr.ravel()) <= max_abs))[0])
        raise ValueError(f"{name}: a magnitude above {max_abs:g} at flat index {first}; "
                         f"admissible: |value| <= {max_abs:g} (check the units)")
    return arr
