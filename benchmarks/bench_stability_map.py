"""``stability_map`` (speed x mesh damping ratio, 20 x 20) on 1 and on 2 local workers.

Issue 16 quotes 30 s on one core for a 20 x 20 map of ``paper-case1`` (before the midpoint
product of issue 15). This prints, for ``paper-case1`` (piecewise-constant stiffness: exact
exponentials) and the trapezoidal four-planet elastic set of the reports
(``reports/sets/four-planet-elastic-trapezoidal.toml``, 20 DOF, midpoint product at chart
accuracy), the time of a 20 x 20 map (speeds 500-4000 min-1, damping ratio 0-0.05 on every
mesh; boundaries not refined, then refined) with ``workers=1`` (this process) and
``workers=2`` (the sweeps' local process pool), their ratio, and whether the two charts are
identical (they must be, bit for bit). The models are built before the clock starts; 1 and 2
workers alternate ``--repeat`` times and the best of each counts. The load average is printed:
the ratio means little when other processes use the cores.

    python benchmarks/bench_stability_map.py
    python benchmarks/bench_stability_map.py --quick   # smoke run: paper-case1, 3 x 3, once
"""

from __future__ import annotations

import argparse
import copy
import os
import time
from pathlib import Path

import numpy as np

from gearvib.assembly import assemble
from gearvib.config import gearset_from_dict, load_config
from gearvib.stability import CHART_ACCURACY, stability_map

SETS = {
    "paper-case1": ("paper-case1", None),
    "four-planet-elastic-trapezoidal": (
        str(Path(__file__).resolve().parents[1] / "reports" / "sets"
            / "four-planet-elastic-trapezoidal.toml"), CHART_ACCURACY),
}


def _models(source: str, zetas: np.ndarray) -> dict:
    cfg, base = load_config(source)
    out = {}
    for z in zetas:
        c = copy.deepcopy(cfg)
        for mesh in c["meshes"].values():
            mesh["damping_ratio"] = float(z)
        out[float(z)] = assemble(gearset_from_dict(c, base=base))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="smoke run: paper-case1 only, a 3 x 3 map, not refined and refined, "
                         "once")
    ap.add_argument("--repeat", type=int, default=None,
                    help="alternate this many times (3; --quick: 1)")
    args = ap.parse_args()
    repeat = args.repeat or (1 if args.quick else 3)
    side = 3 if args.quick else 20
    speeds = np.linspace(500.0, 4000.0, side)
    zetas = np.linspace(0.0, 0.05, side)
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"{'gear set':<34s} {'refined':>7s} {'1 worker [s]':>13s} {'2 workers [s]':>14s} "
          f"{'ratio':>6s} {'identical':>9s} {'regions':>7s}")
    sets = {"paper-case1": SETS["paper-case1"]} if args.quick else SETS
    for name, (source, opts) in sets.items():
        models = _models(source, zetas)
        for refine in (False, True):
            charts: list = [None, None]
            times = [np.inf, np.inf]
            for _ in range(repeat):  # alternate, best of each
                for i, workers in enumerate((1, 2)):
                    t0 = time.perf_counter()
                    charts[i] = stability_map(models.__getitem__, speeds, zetas,
                                              parameter_name="mesh damping ratio",
                                              refine=refine, floquet_options=opts,
                                              workers=workers)
                    times[i] = min(times[i], time.perf_counter() - t0)
            same = (np.array_equal(charts[0].max_modulus, charts[1].max_modulus)
                    and charts[0].region_table == charts[1].region_table)
            print(f"{name:<34s} {refine!s:>7s} {times[0]:13.2f} {times[1]:14.2f} "
                  f"{times[0] / times[1]:6.2f} {same!s:>9s} "
                  f"{len(charts[0].region_table):7d}")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
