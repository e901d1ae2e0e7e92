"""
A run-up of the paper's planetary gear set
==========================================

Simulate the three-planet set of the paper (case 1: planets at 0, 120 and 240 degrees) through a
run-up at constant input torque and look at the tooth forces: their spectrogram over speed shows
the mesh orders as rays and the resonances they cross.
"""

# %%
# Build the model from a preset and look at its natural frequencies.
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.modal import modal_analysis

model = assemble(load_gearset("paper-case1"))
print(modal_analysis(model).table())

# %%
# Simulate 0 -> 4000 min-1 in 0.5 s at the paper's 60 N m and keep the result as an
# :class:`xarray.Dataset` (CF conventions: every variable has its units).
from gearvib.simulate import SpeedRamp, simulate

ramp = SpeedRamp(0.0, 4000.0, 0.5, input_torque=60.0)
result = simulate(model, ramp, progress=False)
ds = result.to_dataset()
force = ds.normal_force.sel(mesh="sun-planet1", flank="left")
print(force.attrs["units"], float(force.max()))

# %%
# The rpm-frequency map of the sun-planet force: orders are rays through the origin,
# natural frequencies are vertical lines where the rays light up.
from analysis.maps import rpm_frequency_map

fs = 1.0 / float(ds.time[1] - ds.time[0])  # the output sample rate [Hz]
fmap = rpm_frequency_map(force.values, fs=fs, rpm=ds.input_speed.values)
fig = fmap.plot()
