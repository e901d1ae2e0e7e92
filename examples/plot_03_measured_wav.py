"""
A measured WAV file: order spectrum and envelope
================================================

Recorders often store an accelerometer and a tacho as the two channels of a WAV file. WAV holds
no engineering units, so the user states the calibration of each channel when reading it.
This example first writes such a file (a gearbox shaft with a 23-tooth pinion speeding up from
1200 to 1800 min⁻¹ and an outer-race defect in its SKF 6205 bearing), then reads it as a
measurement from the bench would be read, and shows the order spectrum and the squared
envelope order spectrum, in which the defect's lines stand out.
"""

# %%
# Write the record: 3 s at 20 kHz, 16-bit PCM. Channel 1 is the accelerometer (±100 m s⁻²
# full scale): the mesh order 23 and its second harmonic, the ringing of a 3.2 kHz housing
# resonance struck at every passage of a ball over the defect (BPFO = 3.5848 orders, with 1 %
# jitter) and white noise. Channel 2 is a once-per-revolution tacho pulse (±10 V full scale).
import wave
from pathlib import Path
from tempfile import mkdtemp

import numpy as np

fs, duration = 20_000, 3.0
t = np.arange(int(fs * duration)) / fs
rpm = 1200.0 + 600.0 * t / duration  # shaft speed [min-1]
phi = 2 * np.pi * np.cumsum(rpm / 60.0) / fs  # shaft angle [rad]
rng = np.random.default_rng(1)

acc = 2.0 * np.sin(23 * phi) + 0.8 * np.sin(46 * phi + 0.3)
bpfo = 3.5848  # ball pass frequency, outer race [orders of the shaft]
n_hits = int(phi[-1] / (2 * np.pi) * bpfo) - 1
hits = 2 * np.pi / bpfo * (np.arange(1, n_hits + 1) + 0.01 * rng.standard_normal(n_hits))
ring = np.arange(int(0.005 * fs)) / fs  # 5 ms of ringing after each hit
burst = 6.0 * np.exp(-ring / 0.8e-3) * np.sin(2 * np.pi * 3200.0 * ring)
for k in np.searchsorted(phi, hits):
    n = min(burst.size, t.size - k)
    acc[k:k + n] += burst[:n]
acc += 0.5 * rng.standard_normal(t.size)
tacho = np.where(np.mod(phi, 2 * np.pi) < 0.3, 5.0, 0.0)  # [V]

full_scale = np.array([100.0, 10.0])  # m s-2 and V at full scale
counts = np.round(np.column_stack([acc, tacho]) / full_scale * 32767).astype("<i2")
path = Path(mkdtemp()) / "bench_runup.wav"
with wave.open(str(path), "wb") as w:
    w.setnchannels(2)
    w.setsampwidth(2)
    w.setframerate(fs)
    w.writeframes(counts.tobytes())

# %%
# Read it as a measurement: the reader takes the channel names, the calibration (unit per
# count of a 16-bit integer file) and the units; ``tacho="tacho"`` makes the pulse channel the
# speed reference (one pulse per revolution).
from analysis.measurement import load_measurement

m = load_measurement(path, tacho="tacho", pulses_per_rev=1,
                     reader_options={"channel_names": ["acc", "tacho"],
                                     "calibration": list(full_scale / 32767),
                                     "unit": ["m s-2", "V"]})
print(m.reference)
print(f"{m.fs:.0f} Hz, speed {float(m.speed_rpm.min()):.0f} to "
      f"{float(m.speed_rpm.max()):.0f} min-1")
x = m.channel("acc")

# %%
# The order spectrum: the record resampled to constant angle increments of the shaft, so the
# mesh orders 23 and 46 stay sharp lines although the speed rises by half. The defect shows
# only as faint ripples at multiples of BPFO, some 30 dB below the mesh orders; the resonance
# it strikes lies far above, at orders 107 to 160.
from matplotlib.figure import Figure

from analysis.orders import order_spectrum

spec = order_spectrum(x, m.fs, angle=m.angle.values, max_order=60.0)
fig_orders = Figure(figsize=(8.0, 3.8), layout="constrained")
spec.plot(ax=fig_orders.add_subplot())

# %%
# The squared envelope order spectrum of the band the fast kurtogram finds most impulsive
# (it holds the 3.2 kHz resonance): the defect's passages are now strong lines at BPFO and
# its harmonics, marked with the bearing's families; nothing stands at the inner-race
# frequency BPFI. The band must be at least twice as wide as
# the highest line looked for (the squared envelope of a band ``B`` wide holds frequencies
# below ``B`` only): 25 orders at up to 30 revolutions per second need 1.5 kHz.
from analysis.envelope_orders import envelope_order_spectrum
from analysis.lines import bearing_families

env = envelope_order_spectrum(x, m.fs, angle=m.angle.values, max_order=25.0,
                              min_bandwidth=1500.0)
print(f"demodulated band {env.band.low:.0f}-{env.band.high:.0f} Hz")
fig_envelope = env.plot(families=bearing_families(bpfo=bpfo, bpfi=5.4152, harmonics=6))
