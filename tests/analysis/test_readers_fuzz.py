"""Property-based fuzz suite over every reader format (hypothesis).

Each test draws a valid file of one format from random data and options
(:mod:`tests.analysis.reader_samples`), then one mutation: none, byte flips, truncation at a
random offset, a corrupted header field (an aligned 1/2/4/8-byte field set to 0, all ones,
the largest signed value or random bytes), bytes inserted or deleted, or random bytes instead
of the file. Properties:

* only a :class:`~analysis.readers.ReaderError` may be raised (any other exception fails);
* an unmutated file reads back with the values it was written with, at its sample rate;
* a truncated file is either refused or read as a prefix of the original (a cut exactly at a
  boundary the format cannot tell from the end: a line, a UFF dataset, a TDMS segment, a MAT
  variable) -- never with changed samples.

The number of examples per format is ``GEARVIB_FUZZ_EXAMPLES`` (default 100, about 10 s in
all). A long campaign, e.g. ``GEARVIB_FUZZ_EXAMPLES=10000``, runs with fresh random examples
each time; with ``GEARVIB_FUZZ_REPORT=<file.json>`` the counts (tries, accepted, clear
errors) per format are written there. Segmentation faults cannot be caught in-process: the
subprocess byte-flip campaign (:mod:`tests.analysis.readers_campaign`) covers them, and
:func:`test_mat_byte_flips_never_crash` runs part of it here.

The module lowers the address-space limit to the current size plus 3 GiB while it runs, so
that a regression in a memory guard shows as an error here instead of exhausting the machine.
"""

from __future__ import annotations

import collections
import json
import os
import struct
import sys
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from analysis.readers import ReaderError, read
from tests import fuzz_guard
from tests.analysis import reader_samples as samples

DEFAULT_EXAMPLES = 100
EXAMPLES = int(os.environ.get("GEARVIB_FUZZ_EXAMPLES", DEFAULT_EXAMPLES))
REPORT = os.environ.get("GEARVIB_FUZZ_REPORT")
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    database=None,
    derandomize=EXAMPLES <= DEFAULT_EXAMPLES,  # the CI run is reproducible
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
COUNTS: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)


@pytest.fixture(scope="module", autouse=True)
def bounded_memory() -> Iterator[None]:
    """Address-space limit: current size + 3 GiB (Linux); restored afterwards."""
    try:
        vm = fuzz_guard.process_size()
    except (OSError, ValueError):
        yield
        return
    with fuzz_guard.address_space_limit(vm + 3 * 2**30):
        yield


@pytest.fixture(scope="module")
def workdir() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="gearvib-fuzz-") as tmp:
        yield Path(tmp)
    if REPORT:
        old = json.loads(Path(REPORT).read_text()) if Path(REPORT).exists() else {}
        old.update({k: dict(v) for k, v in COUNTS.items()})
        Path(REPORT).write_text(json.dumps(old, indent=2, sort_keys=True))
    if COUNTS:
        summary = {k: dict(v) for k, v in COUNTS.items()}
        print(f"\nreader fuzz counts: {summary}", file=sys.stderr)


# ----------------------------------------------------------------------------------------------
# mutations
# ----------------------------------------------------------------------------------------------


def _field_value(width: int, kind: str, raw: int, big: bool) -> bytes:
    if kind == "zero":
        return b"\0" * width
    if kind == "ones":
        return b"\xff" * width
    value = 2 ** (8 * width - 1) - 1 if kind == "max_signed" else raw % 2 ** (8 * width)
    return value.to_bytes(width, "big" if big else "little")


def mutations(size: int) -> st.SearchStrategy[tuple]:
    """Mutations of a file of ``size`` bytes, as tagged tuples."""
    offset = st.integers(0, size - 1)
    header = st.integers(0, min(size, 512) - 1)
    return st.one_of(
        st.just(("none",)),
        st.tuples(
            st.just("flip"),
            st.lists(
                st.tuples(st.one_of(header, offset), st.integers(1, 255)), min_size=1, max_size=8
            ),
        ),
        st.tuples(st.just("truncate"), offset),
        st.tuples(
            st.just("field"),
            st.one_of(header, offset),
            st.sampled_from([1, 2, 4, 8]),
            st.sampled_from(["zero", "ones", "max_signed", "random"]),
            st.integers(0, 2**64 - 1),
            st.booleans(),
        ),
        st.tuples(
            st.just("splice"), st.integers(0, size), st.integers(0, 16), st.binary(max_size=16)
        ),
        st.tuples(st.just("garbage"), st.binary(max_size=min(2 * size, 2048))),
    )


def apply(data: bytes, mutation: tuple) -> bytes:
    """The mutated file."""
    kind = mutation[0]
    if kind == "none":
        return data
    if kind == "flip":
        b = bytearray(data)
        for off, mask in mutation[1]:
            b[off] ^= mask
        return bytes(b)
    if kind == "truncate":
        return data[: mutation[1]]
    if kind == "field":
        _, off, width, value_kind, raw, big = mutation
        off -= off % width
        value = _field_value(width, value_kind, raw, big)
        return data[:off] + value[: len(data) - off] + data[off + width :]
    if kind == "splice":
        _, off, delete, insert = mutation
        return data[:off] + insert + data[off + delete :]
    return mutation[1]


# ----------------------------------------------------------------------------------------------
# the property
# ----------------------------------------------------------------------------------------------


def check(fmt: str, sample: samples.Sample, mutation: tuple, workdir: Path) -> None:
    """Read the mutated file; assert the properties of the module docstring; count."""
    counts = COUNTS[fmt]
    counts["tries"] += 1
    # a new name each time: netCDF-C keeps some corrupt netCDF-4 files open after refusing
    # them, and HDF5 would then serve a later file of the same inode from that stale handle
    path = workdir / f"case{counts['tries']}{sample.suffix}"
    path.write_bytes(apply(sample.data, mutation))
    try:
        ds = read(path, **sample.options)
    except ReaderError as exc:
        path.unlink()
        counts["clear errors"] += 1
        assert mutation[0] != "none", f"a valid file was refused: {exc}"
        assert str(path) in str(exc) or path.name in str(exc), f"file not named: {exc}"
        return
    except BaseException:
        counts["anything else"] += 1
        raise
    path.unlink()
    counts["accepted"] += 1
    if mutation[0] == "none":
        assert ds.attrs["sample_rate_hz"] == pytest.approx(sample.fs, rel=1e-12)
        assert set(sample.expected) <= set(ds.data_vars)
        for name, values in sample.expected.items():
            np.testing.assert_allclose(ds[name].values, values, rtol=sample.rtol, atol=sample.atol)
    elif mutation[0] == "truncate":
        for name, values in sample.expected.items():
            if name in ds.data_vars:
                got = ds[name].values
                assert got.size <= values.size, f"{name}: more samples after a cut"
                np.testing.assert_allclose(
                    got, values[: got.size], rtol=sample.rtol, atol=sample.atol
                )


def _values(seed: int, n_channels: int, n: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1.0, 1.0, (n_channels, n))


def fuzz_format(fmt: str, build: Callable[[st.DrawFn], samples.Sample]) -> Callable:
    """A hypothesis test of one format: ``build`` draws a valid sample."""

    @FUZZ
    @given(data=st.data())
    def test(data: st.DataObject, workdir: Path) -> None:
        sample = build(data.draw)
        mutation = data.draw(mutations(len(sample.data)), label="mutation")
        check(fmt, sample, mutation, workdir)

    test.__name__ = f"test_fuzz_{fmt}"
    test.__doc__ = f"{fmt}: only ReaderError, valid files round-trip, cuts give prefixes."
    return test


def _common(draw: st.DrawFn, max_n: int = 64) -> tuple[int, int, int]:
    return (
        draw(st.integers(0, 2**32 - 1), label="seed"),
        draw(st.integers(1, 3)),
        draw(st.integers(2, max_n)),
    )


def _wav(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    coding = draw(
        st.sampled_from(
            [
                "pcm8",
                "pcm12",
                "pcm16",
                "pcm20in32",
                "pcm24",
                "pcm32",
                "pcm40",
                "pcm64",
                "float32",
                "float64",
            ]
        )
    )
    return samples.wav_sample(
        _values(seed, n_ch, n),
        draw(st.sampled_from([8000, 25600, 44100, 51200])),
        coding,
        draw(st.sampled_from(["RIFF", "RIFX", "RF64", "BW64"])),
        draw(st.booleans()),
        extra_chunk=draw(st.booleans()),
    )


def _csv(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    time_format = draw(st.sampled_from([None, "%.8f", "%.6e", "%.17g"]))
    delimiter = draw(st.sampled_from([",", ";", "\t", " "]))
    if delimiter == ";" and n_ch == 1 and time_format is None:
        delimiter = ","  # one column of decimal commas would read as two columns
    return samples.csv_sample(
        _values(seed, n_ch, n) * 10.0 ** draw(st.integers(-3, 3)),
        float(draw(st.sampled_from([1000, 25600, 51200]))),
        time_format=time_format,
        value_format=draw(st.sampled_from(["%.6e", "%.17g", "%.5f", "%.16e"])),
        delimiter=delimiter,
        header=draw(st.booleans()),
        comment=draw(st.booleans()),
    )


def _mat(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    values = _values(seed, n_ch, n)
    kind = draw(st.sampled_from(["v5", "v5z", "v4"]))
    if kind == "v4":
        return samples.mat4_sample(values, 1000.0)
    return samples.mat5_sample(values, 1000.0, compressed=kind == "v5z", extras=draw(st.booleans()))


def _mat73(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    return samples.mat73_sample(_values(seed, n_ch, n), 1000.0)


def _netcdf(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    return samples.netcdf_sample(
        _values(seed, n_ch, n), 1000.0, version=draw(st.sampled_from([3, 4]))
    )


def _uff(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    dt = draw(st.sampled_from([1e-3, 1 / 3200, 1 / 25600]))
    return samples.uff_sample(_values(seed, n_ch, n), dt, draw(st.sampled_from([0, 1])))


def _tdms(draw: st.DrawFn) -> samples.Sample:
    seed, n_ch, n = _common(draw)
    return samples.tdms_sample(_values(seed, n_ch, n), 1e-3, draw(st.integers(1, min(n, 3))))


test_fuzz_wav = fuzz_format("wav", _wav)
test_fuzz_csv = fuzz_format("csv", _csv)
test_fuzz_mat = fuzz_format("mat", _mat)
test_fuzz_mat73 = fuzz_format("mat73", _mat73)
test_fuzz_netcdf = fuzz_format("netcdf", _netcdf)
test_fuzz_uff = fuzz_format("uff", _uff)
test_fuzz_tdms = fuzz_format("tdms", _tdms)


def test_mutations_are_applied():
    """The mutation helpers do what they say (a fuzz suite whose mutations were no-ops
    would pass vacuously)."""
    data = bytes(range(16))
    assert apply(data, ("truncate", 5)) == data[:5]
    assert apply(data, ("flip", [(3, 0xFF)]))[3] == 3 ^ 0xFF
    assert apply(data, ("field", 6, 4, "ones", 0, False))[4:8] == b"\xff" * 4
    assert apply(data, ("field", 8, 8, "max_signed", 0, True))[8:] == struct.pack(">q", 2**63 - 1)
    assert apply(data, ("splice", 2, 3, b"ab")) == data[:2] + b"ab" + data[5:]
    assert apply(data, ("garbage", b"xyz")) == b"xyz"


# ----------------------------------------------------------------------------------------------
# the MAT segfault, in subprocesses
# ----------------------------------------------------------------------------------------------


def test_mat_byte_flips_never_crash(tmp_path):
    """Every byte of a small uncompressed MAT v5 file inverted, each read in a worker
    subprocess. scipy.io.loadmat alone dies with a segmentation fault on 4 of these 376 files
    (the array flags at byte 145, the data-type codes at 176, 360 and 361; 19 of the 1,880
    files of the full campaign); read_mat reads or refuses every one with a ReaderError."""
    from scipy.io import savemat

    from tests.analysis.readers_campaign import campaign

    path = tmp_path / "small.mat"
    savemat(path, {"acc": np.linspace(-1, 1, 16), "fs": 100.0}, do_compression=False)
    counts, findings = campaign(path, "mat", ["xff"], timeout=60.0, memory_gb=4.0)
    assert findings == []
    assert sum(counts.values()) == path.stat().st_size
    assert counts["accepted"] > 0 and counts["ReaderError"] > 0
