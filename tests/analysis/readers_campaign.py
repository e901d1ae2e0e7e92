"""Byte-flip crash campaign over the readers, each read in a worker subprocess.

A hypothesis fuzz run inside pytest cannot survive a segmentation fault; this campaign can: a
worker process reads one mutated file after the other and reports each outcome, and when it
dies (a signal) or hangs (no answer within ``--timeout`` seconds) the parent records the
mutation it was reading and starts a new worker after it. Workers run with an address-space
limit (``--memory-gb``) so that a runaway allocation ends as ``MemoryError`` in the worker, not
in the machine's OOM killer.

Every byte of each base file is mutated in the ways ``--hows`` lists (``xff``: invert all
bits, ``x01``/``x80``: flip the lowest/highest bit, ``00``/``ff``: set the byte). Base files
(written here, from random data): MAT v5 uncompressed and compressed with doubles, singles,
int16, logical, complex, char, struct, cell, sparse and empty variables; MAT v4; MAT v7.3;
WAV; CSV; netCDF-3 and netCDF-4; UFF 58 and 58b; TDMS.

Run from the repository root::

    python -m tests.analysis.readers_campaign mat          # the MAT files, all five mutations
    python -m tests.analysis.readers_campaign all --hows xff

(``--scipy``: the MAT files through ``scipy.io.loadmat`` alone, without the structure check),
and it prints, per file, the number of mutations and of each outcome: ``accepted`` (read into
a Dataset), ``ReaderError`` (a clear error), anything else (other exceptions, ``crash:<signal>``,
``hang``), which must be zero. ``tests/analysis/test_readers_fuzz.py`` runs a small part of it.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import select
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

HOWS = ("xff", "x01", "x80", "00", "ff")


def mutate(data: bytes, offset: int, how: str) -> bytes:
    """``data`` with the byte at ``offset`` changed as ``how`` says."""
    b = bytearray(data)
    if how == "xff":
        b[offset] ^= 0xFF
    elif how == "x01":
        b[offset] ^= 0x01
    elif how == "x80":
        b[offset] ^= 0x80
    elif how == "00":
        b[offset] = 0x00
    elif how == "ff":
        b[offset] = 0xFF
    else:
        raise ValueError(f"how = {how!r}: admissible are {HOWS}")
    return bytes(b)


# ----------------------------------------------------------------------------------------------
# base files
# ----------------------------------------------------------------------------------------------


def _mat_content(n: int, rng: np.random.Generator) -> dict[str, object]:
    from scipy.sparse import csc_matrix

    return {
        "acc": rng.standard_normal(n),
        "mat": rng.standard_normal((n, 2)).astype(np.float32),
        "cnt": rng.integers(-1000, 1000, n).astype(np.int16),
        "flag": rng.integers(0, 2, n).astype(bool),
        "fs": 1000.0,
        "name": "sensor",
        "units": {"acc": "m/s2", "mat": "g"},
        "cel": np.array([np.ones(3), "ab"], dtype=object),
        "z": np.array([1 + 2j, 3 - 1j]),
        "sp": csc_matrix(np.eye(4)),
        "emp": np.zeros((0, 3)),
    }


def write_base_files(folder: Path, kinds: set[str]) -> dict[str, tuple[Path, str]]:
    """Write the base files of the chosen kinds; name -> (path, reader kind)."""
    from scipy.io import savemat

    from analysis.readers import ChannelData, build_dataset, write_csv, write_netcdf, write_wav

    rng = np.random.default_rng(11)
    out: dict[str, tuple[Path, str]] = {}
    if "mat" in kinds:
        content = _mat_content(24, rng)
        for comp in (False, True):
            name = f"v5_{'compressed' if comp else 'plain'}.mat"
            savemat(folder / name, content, do_compression=comp)
            out[name] = (folder / name, "mat")
        small = {"acc": np.linspace(-1.0, 1.0, 16), "fs": 100.0}
        savemat(folder / "v5_small.mat", small, do_compression=False)
        out["v5_small.mat"] = (folder / "v5_small.mat", "mat")
        savemat(folder / "v4.mat", {"acc": rng.standard_normal(24), "fs": 1000.0}, format="4")
        out["v4.mat"] = (folder / "v4.mat", "mat")
        try:
            from tests.analysis.test_readers_mat73 import savemat73

            savemat73(folder / "v73.mat", {"acc": rng.standard_normal(24), "fs": 1000.0})
            out["v73.mat"] = (folder / "v73.mat", "mat")
        except ImportError:
            pass
    ds = build_dataset(
        [ChannelData("a", rng.standard_normal(32), "m s-2"), ChannelData("b", np.arange(32.0))],
        1000.0,
        source_format="campaign",
    )
    if "wav" in kinds:
        write_wav(ds, folder / "f32.wav")
        write_wav(ds, folder / "i16.wav", dtype="int16")
        out["f32.wav"] = (folder / "f32.wav", "wav")
        out["i16.wav"] = (folder / "i16.wav", "wav")
    if "csv" in kinds:
        write_csv(ds, folder / "w.csv")
        out["w.csv"] = (folder / "w.csv", "csv")
    if "netcdf" in kinds:
        write_netcdf(ds, folder / "n4.nc")
        ds.to_netcdf(
            folder / "n3.nc",
            format="NETCDF3_CLASSIC",
            encoding={v: {"_FillValue": None} for v in ds.variables},
        )
        out["n4.nc"] = (folder / "n4.nc", "netcdf")
        out["n3.nc"] = (folder / "n3.nc", "netcdf")
    if "uff" in kinds:
        from tests.analysis.reader_samples import uff_bytes

        for binary in (0, 1):
            name = f"uff58{'b' if binary else ''}.uff"
            (folder / name).write_bytes(uff_bytes(rng.standard_normal((2, 24)), 1e-3, binary))
            out[name] = (folder / name, "uff")
    if "tdms" in kinds:
        from tests.analysis.reader_samples import tdms_bytes

        (folder / "t.tdms").write_bytes(tdms_bytes(rng.standard_normal((2, 24)), 1e-3))
        out["t.tdms"] = (folder / "t.tdms", "tdms")
    return out


# ----------------------------------------------------------------------------------------------
# worker and parent
# ----------------------------------------------------------------------------------------------


def _reader(kind: str) -> Callable[[Path], object]:
    from analysis import readers

    if kind == "scipy-mat":  # scipy.io.loadmat alone: the crashes the structure check prevents
        from scipy.io import loadmat

        return lambda path: loadmat(path, squeeze_me=True, chars_as_strings=True)

    options = {"mat": {"fs": 1.0}, "csv": {"time_column": 0}}.get(kind, {})
    fn = {
        "mat": readers.read_mat,
        "wav": readers.read_wav,
        "csv": readers.read_csv,
        "netcdf": readers.read_netcdf,
        "uff": readers.read_uff,
        "tdms": readers.read_tdms,
    }[kind]
    return lambda path: fn(path, **options)


def _worker(path: str, kind: str, start: int, hows: list[str], memory_gb: float) -> None:
    import resource

    from analysis.readers import ReaderError

    limit = int(memory_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    read = _reader(kind)
    data = Path(path).read_bytes()
    cases = [(off, how) for off in range(len(data)) for how in hows]
    with tempfile.TemporaryDirectory() as tmp:
        target = Path(tmp) / f"case{Path(path).suffix}"
        for i in range(start, len(cases)):
            changed = mutate(data, *cases[i])
            if changed == data:
                print(f"R {i} unchanged", flush=True)
                continue
            target.write_bytes(changed)
            print(f"S {i}", flush=True)
            try:
                read(target)
                outcome = "accepted"
            except ReaderError:
                outcome = "ReaderError"
            except Exception as exc:  # anything else is a finding
                outcome = f"{type(exc).__module__}.{type(exc).__name__}"
            print(f"R {i} {outcome}", flush=True)


def campaign(
    path: Path, kind: str, hows: list[str], *, timeout: float = 60.0, memory_gb: float = 6.0
) -> tuple[collections.Counter[str], list[tuple[int, str, str]]]:
    """Run every mutation of ``path``; return outcome counts and findings
    ``(offset, how, outcome)`` for anything but accepted/ReaderError/unchanged."""
    n_cases = path.stat().st_size * len(hows)
    counts: collections.Counter[str] = collections.Counter()
    findings: list[tuple[int, str, str]] = []
    start = 0
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    while start < n_cases:
        cmd = [
            sys.executable,
            "-m",
            "tests.analysis.readers_campaign",
            "--worker",
            str(path),
            kind,
            str(start),
            ",".join(hows),
            str(memory_gb),
        ]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env)
        assert proc.stdout is not None
        current: int | None = None
        hung = False
        while True:
            ready, _, _ = select.select([proc.stdout], [], [], timeout)
            if not ready:
                hung = True
                proc.kill()
                break
            line = proc.stdout.readline()
            if not line:
                break
            tag, index, *rest = line.split()
            if tag == "S":
                current = int(index)
            else:
                counts[rest[0]] += 1
                current, start = None, int(index) + 1
        code = proc.wait()
        if current is not None:
            outcome = "hang" if hung else f"crash:{-code if code < 0 else code}"
            counts[outcome] += 1
            off, how = divmod(current, len(hows))
            findings.append((off, hows[how], outcome))
            start = current + 1
        elif code != 0:
            raise RuntimeError(f"worker for {path} failed with exit code {code}")
    for key in list(counts):
        if key not in ("accepted", "ReaderError", "unchanged") and not key.startswith(
            ("crash", "hang")
        ):
            findings.append((-1, "", key))
    return counts, findings


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "kinds", nargs="*", default=["mat"], help="mat, wav, csv, netcdf, uff, tdms or all"
    )
    parser.add_argument("--hows", default=",".join(HOWS))
    parser.add_argument("--timeout", type=float, default=60.0)
    parser.add_argument("--memory-gb", type=float, default=6.0)
    parser.add_argument("--json", help="write the counts to this file")
    parser.add_argument(
        "--scipy", action="store_true", help="MAT files through scipy.io.loadmat alone (before)"
    )
    parser.add_argument("--worker", nargs=5, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.worker:
        path, kind, start, hows, memory = args.worker
        _worker(path, kind, int(start), hows.split(","), float(memory))
        return 0
    kinds = (
        {"mat", "wav", "csv", "netcdf", "uff", "tdms"} if "all" in args.kinds else set(args.kinds)
    )
    hows = args.hows.split(",")
    report: dict[str, dict[str, int]] = {}
    bad = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, (path, kind) in write_base_files(Path(tmp), kinds).items():
            t0 = time.perf_counter()
            if args.scipy and kind == "mat":
                kind = "scipy-mat"
            counts, findings = campaign(
                path, kind, hows, timeout=args.timeout, memory_gb=args.memory_gb
            )
            report[name] = dict(counts)
            total = sum(counts.values())
            print(
                f"{name}: {path.stat().st_size} bytes, {total} mutations in "
                f"{time.perf_counter() - t0:.0f} s: {dict(counts)}",
                flush=True,
            )
            for finding in findings:
                print(f"  FINDING offset {finding[0]} {finding[1]}: {finding[2]}", flush=True)
            bad += len(findings)
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=2))
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
