"""
A design sweep on a Dask cluster
================================

A sweep runs one gear set many times with keys of its description varied and summarises every
run into one file, ``sweep.nc`` (:doc:`/sweeps`). The cases can run in this process, on a
local process pool or on any :class:`concurrent.futures.Executor`, such as a Dask cluster's:
the results are the same bit for bit.

Here the sun-mesh damping of the paper's gear set is swept over two values while it runs up
through a resonance, on a one-worker Dask ``LocalCluster`` (on a real cluster, connect a
:class:`distributed.Client` to the scheduler's address instead; ``gearvib sweep study.toml
--scheduler tcp://host:8786`` does the same from the command line).
"""

# %%
# The sweep: two cases of a short run-up through 2600-3100 min⁻¹, where the second mesh
# order crosses the planet mode f3 = f4; the first three mesh orders of the tooth forces are
# summarised besides the dynamic factor.
from gearvib.sweep import Parameter, SummarySettings, Sweep

sweep = Sweep(base="paper-case1",
              parameters=[Parameter("meshes.sun.damping_ratio", [0.005, 0.03])],
              simulation={"speed_start_rpm": 2600.0, "speed_end_rpm": 3100.0,
                          "duration": 0.2},
              summary=SummarySettings(orders=(1, 2, 3), order_resolution=0.25))

# %%
# Run it on the cluster: ``client.get_executor()`` is the executor the cases go to. The
# workers write the run files and ``run_sweep`` combines their summaries into ``sweep.nc``.
from pathlib import Path
from tempfile import mkdtemp

from distributed import Client, LocalCluster

from gearvib.sweep import run_sweep

out = Path(mkdtemp()) / "damping"
with LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                  dashboard_address=None) as cluster, Client(cluster) as client:
    result = run_sweep(sweep, out, executor=client.get_executor(), progress=False,
                       report=False)
print(f"simulated cases {result.simulated}; files: {sorted(p.name for p in out.iterdir())}")

# %%
# ``sweep.nc`` opens in plain xarray; every swept parameter is a coordinate along ``case``.
import xarray as xr

ds = xr.open_dataset(out / "sweep.nc")
print(ds.dynamic_factor.to_pandas())

# %%
# The dynamic factor K_v (largest tooth force over the static one) of every mesh, and the
# highest level of each mesh order of the tooth force, for the two damping ratios.
import numpy as np
from matplotlib.figure import Figure

fig = Figure(figsize=(9.0, 3.8), layout="constrained")
ax_kv, ax_ord = fig.subplots(1, 2)
zeta = ds.meshes_sun_damping_ratio.values
x = np.arange(ds.sizes["mesh"])
for i, z in enumerate(zeta):
    ax_kv.bar(x + (i - 0.5) * 0.4, ds.dynamic_factor.isel(case=i), width=0.4,
              label=f"sun-mesh damping ratio {z:g}")
    level = ds.normal_force_order_level.isel(case=i).sel(mesh="sun-planet1")
    ax_ord.plot(ds.order, level, "o-", label=f"damping ratio {z:g}")
ax_kv.set_xticks(x, ds.mesh.values, rotation=30, ha="right", fontsize=8)
ax_kv.set_ylabel("dynamic factor K_v [1]")
ax_kv.set_ylim(1.0, None)
ax_kv.set_title("largest over static tooth force", fontsize=9)
ax_kv.legend(fontsize=8)
ax_ord.set_xlabel("mesh order [1]")
ax_ord.set_ylabel(f"sun-planet1 normal force, max rms [{level.attrs.get('units', 'N')}]")
ax_ord.set_xticks(ds.order.values)
ax_ord.set_title("order levels of the sun-planet 1 tooth force", fontsize=9)
ax_ord.legend(fontsize=8)
