"""
Order cuts and a waterfall of a run-up
======================================

The first pages of an NVH run-up report: the level of each mesh order over speed (order
cuts) with the overall level, and a waterfall of spectra. Here the run-up is simulated with a
virtual accelerometer on the housing, so the example runs anywhere; a measured channel with its
tacho is analysed the same way (see the next example and :doc:`/measurements`).
``gearvib report`` makes the whole report (HTML and PDF) from the same functions
(:doc:`/reports`).
"""

# %%
# The paper's three-planet set with an accelerometer on the ring gear's housing (one housing
# mode at 3 kHz), run up from 0 to 4000 min⁻¹ in one second at 60 N m. The sun is driven
# through the torsional spring-damper of the preset's ``[simulation]`` table
# (``drive_stiffness``, ``drive_damping``; ``gearvib simulate`` uses it too): the preset's light
# mesh damping was chosen with it, and without its damping the set is parametrically unstable
# in several speed bands (:doc:`/simulator`).
from gearvib.assembly import assemble
from gearvib.config import load_gearset
from gearvib.sensors import HousingMode, HousingSensor
from gearvib.simulate import DriveCoupling, SpeedRamp, simulate

sensor = HousingSensor("top", 90.0, housing_modes=(HousingMode(3000.0, 0.02, 1.0),))
model = assemble(load_gearset("paper-case1")).with_sensors([sensor])
ramp = SpeedRamp(0.0, 4000.0, 1.0, input_torque=60.0,
                 coupling=DriveCoupling(3728.14, 9.4104))  # [N m/rad], [N m s/rad]
ds = simulate(model, ramp, progress=False).to_dataset()
acc = ds.sensor_acceleration.sel(sensor="top")
print(acc.attrs["units"], acc.sizes)

# %%
# The mesh frequency is an order of the input shaft: ``mesh_frequency_per_rpm`` Hz per
# min⁻¹ is 60 times that many cycles per revolution. Cut the first three mesh orders. The
# input shaft's angle, stored with the run, is the speed reference (a tacho's angle for a
# measurement); the model's natural frequencies are passed along to name the resonances the
# orders cross.
from analysis.runup_levels import runup_levels

mesh_order = 60.0 * model.mesh_frequency_per_rpm
levels = runup_levels(
    acc, angle=ds.input_angle.values,
    orders=[mesh_order, 2 * mesh_order, 3 * mesh_order],
    order_names=["1x mesh", "2x mesh", "3x mesh"],
    natural_frequencies_hz=ds.natural_frequency.values,
    natural_names=[f"f{i + 2}" for i in range(ds.sizes["mode"])],  # f1: the rigid-body mode
    name="housing acceleration 'top'",
)
print(f"mesh order {mesh_order:.2f}, resolution {levels.resolution:.3g} orders, "
      f"{levels.revolutions:.1f} revolutions")

# %%
# Order cuts in dB re 1 m s⁻² over the input speed, with the overall level of the whole
# band; the numbered circles are the strongest resonances of the cuts.
fig_cuts = levels.plot("cuts", marks=3)

# %%
# The resonances, strongest first, with the natural frequency of the gear set whose critical
# speed the order crosses there. The two strongest are the sensor's 3 kHz housing mode, which
# is not a mode of the gear set ("none"): the report names such a rise "a resonance of no
# natural frequency of the model".
p = levels.peaks
for i in range(min(3, len(p))):
    crossed = f"{p.mode[i]} ({p.mode_frequency_hz[i]:.0f} Hz)" if p.mode[i] else "none"
    print(f"{i + 1}. {p.name[i]} at {p.rpm[i]:.0f} min-1, {p.frequency_hz[i]:.0f} Hz, "
          f"{p.level_db[i]:.1f} dB, rise {p.rise_db[i]:.1f} dB; natural frequency: {crossed}")

# %%
# The waterfall: spectra at evenly spaced speeds, each drawn on its speed. The mesh orders
# are the dashed rays, the natural frequencies the dotted vertical lines.
fig_waterfall = levels.plot("waterfall", frequency_max=6000.0)

# %%
# Every number of the figures is in one CF Dataset, ready for ``to_netcdf``.
print(levels.to_dataset())
