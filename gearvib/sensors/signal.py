"""Virtual sensor signals of a run: the housing accelerometers and the tacho.

Transmission path (McFadden & Smith 1985; Inalpolat & Kahraman 2009). A sensor at angle
``theta_s`` on the housing member sees every planet's mesh force with that member weighted by
the angle between the planet and the sensor::

    p(t) = sum_n w(wrap(theta_c + psi_n - theta_h - theta_s)) (F_left,n + F_right,n)(t)
           + sum_b g_b (F_x,b cos(theta_s - theta_c) + F_y,b sin(theta_s - theta_c))

(``theta_c`` the carrier angle, ``psi_n`` the planet's angle on the carrier, ``theta_h`` the
housing member's own rotation, ``wrap`` to (-pi, pi]; the bearing terms project the radial
bearing force of central member ``b``, whose components are in the carrier frame, on the
sensor's radial direction). The housing member is a central gear (its meshes with planets)
or a carrier (the meshes of its planets: a parallel stage's housing, where the wheel's axis
sits at a fixed angle, so the weight is a constant gain); a sensor of a multi-stage gearbox
sums over every housing member it names. Windows, with ``W`` = ``width_deg``:

* ``hann``: ``w = (1 + cos(pi d / W)) / 2`` for ``|d| <= W``, else 0;
* ``rectangular``: ``w = 1`` for ``|d| <= W``, else 0;
* ``exponential``: ``w = exp(-|d| / W)``.

The acceleration is ``a = h * p`` with the housing accelerance ``H(f)`` (modes or measured),
applied by FFT on the output grid to the record zero-padded to twice its length (a linear
convolution; the part of ``p`` that is constant from the start, ``p(0)``, is taken as applied
for ever: ``a = H(0) p(0) + IFFT(H FFT(p - p(0)))``).

Computed after the integration from the stored forces at the output rate: they are low-pass
filtered (flat to 0.3 ``fs_out``, >= 80 dB from 0.5 ``fs_out``) and the window moves them by
carrier orders only, whose weights fall fast (Hann: as ``q^-3``), so the product aliases
nothing into the analysed band; the FFT applies the FRF exactly at every output frequency. In
the kernel it would cost work at every internal step and could not use a measured FRF.

Tacho: the pulse train of the simulated shaft angle ``theta`` (the member's actual rotation)
with ``P`` pulses per revolution: high (``level_v``) while ``frac(P theta / 2 pi) < duty``;
every edge is a linear ramp over two samples centred on its exact time, so a trigger that
interpolates the level crossing (``analysis.speed.from_tacho``) recovers it to rounding.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from gearvib.checks import check_array, check_instance, check_real, short
from gearvib.model import AssembledModel
from gearvib.sensors.apply import housing_meshes, members_of
from gearvib.sensors.description import HousingSensor, Tacho

__all__ = ["add_sensor_signals", "housing_response", "path_force", "tacho_signal",
           "window_weight"]


def window_weight(window: str, width_deg: float, delta: np.ndarray) -> np.ndarray:
    """Transmission-path weight at angles ``delta`` [rad] between planet and sensor."""
    if window not in ("hann", "rectangular", "exponential"):
        raise ValueError(f"window = {short(window)} is not admissible (admissible: hann, "
                         "exponential, rectangular)")
    width_deg = check_real(width_deg, "width_deg", low=1e-6, high=360.0)
    delta = check_array(delta, "delta", min_size=0, max_abs=1e9)
    # |delta| wrapped to 0..pi (nearest multiple of 2 pi removed)
    d = np.abs(delta - (2.0 * np.pi) * np.rint(delta * (0.5 / np.pi)))
    width = math.radians(width_deg)
    if window == "hann":
        w = np.zeros_like(d)
        inside = d <= width
        w[inside] = 0.5 * (1.0 + np.cos(d[inside] * (np.pi / width)))  # cos only where used
        return w
    if window == "rectangular":
        return (d <= width).astype(float)
    if window == "exponential":
        return np.exp(-d / width)
    raise ValueError(f"window = {short(window)} is not admissible")  # checked above


def _rotation(result, member: str) -> np.ndarray:
    if member in result.members:
        return result.rotation[result.members.index(member)]
    return np.zeros(result.time.size)  # held at rest


def path_force(result, model: AssembledModel, sensor: HousingSensor) -> np.ndarray:
    """The windowed force sum ``p(t)`` a sensor sees [N] (module docstring)."""
    check_instance(result, "gearvib.simulation.result.RunUpResult", "result")
    check_instance(model, AssembledModel, "model")
    check_instance(sensor, HousingSensor, "sensor")
    housing = sensor.member
    if housing is None:
        raise ValueError("sensor has no housing member: take it from the model's sensors "
                         "(add_sensors fills it in)")
    planets = {p["name"]: p for p in model.meta.get("planets", [])}
    meshes = model.meta["meshes"]
    theta_s = math.radians(sensor.angle_deg)
    p = np.zeros(result.time.size)
    for member in members_of(housing):
        _add_member_forces(p, result, model, sensor, member, planets, meshes, theta_s)
    for b, gain in sensor.bearings:
        fx = result.bearing_force[result.bearing_names.index(f"{b}.x")]
        fy = result.bearing_force[result.bearing_names.index(f"{b}.y")]
        carriers = {pl["carrier"] for pl in planets.values()}
        theta_c = _rotation(result, sorted(carriers)[0]) if carriers else 0.0
        rel = theta_s - theta_c
        p += gain * (fx * np.cos(rel) + fy * np.sin(rel))
    return p


def _add_member_forces(p: np.ndarray, result, model: AssembledModel, sensor: HousingSensor,
                       member: str, planets: dict, meshes: list, theta_s: float) -> None:
    """Add the windowed mesh forces that reach the sensor through ``member`` to ``p``.

    A mesh of a central gear is seen through that gear, a mesh of a planet on a carrier
    member (a parallel stage's housing) through the carrier; with ``theta_h`` the member's
    rotation, both follow the window of the planet's angle relative to the sensor.
    """
    theta_h = _rotation(result, member)
    wanted = set(members_of(sensor.member or member))
    for k in housing_meshes(model, member):
        planet = planets[meshes[k]["gear2"]]
        if member != meshes[k]["gear1"] and meshes[k]["gear1"] in wanted:
            continue  # seen through its central gear already
        theta_c = _rotation(result, planet["carrier"])
        delta = theta_c + math.radians(planet["angle_deg"]) - theta_h - theta_s
        force = result.normal_force[k, 0] + result.normal_force[k, 1]
        p += window_weight(sensor.window, sensor.width_deg, delta) * force


def housing_response(p: np.ndarray, fs: float, sensor: HousingSensor) -> np.ndarray:
    """Acceleration [m s-2] of the housing response to the path force ``p`` [N] sampled at
    ``fs`` (module docstring)."""
    p = check_array(p, "p", ndim=1, min_size=0, max_abs=1e100)
    fs = check_real(fs, "fs [Hz]", low=0.0, low_open=True, high=1e12)
    check_instance(sensor, HousingSensor, "sensor")
    n = p.size
    if n == 0:
        return p.copy()
    p0 = float(p[0])
    import scipy.fft  # on use: a run without housing sensors does not need it

    nfft = scipy.fft.next_fast_len(2 * n, real=True)
    spec = scipy.fft.rfft(p - p0, nfft)
    f = scipy.fft.rfftfreq(nfft, 1.0 / fs)
    h = sensor.accelerance(f)
    a = scipy.fft.irfft(h * spec, nfft)[:n]
    return a + float(np.real(h[0])) * p0


def tacho_signal(angle: np.ndarray, tacho: Tacho) -> np.ndarray:
    """Pulse train [V] of a shaft angle [rad] sampled on a uniform grid (module docstring).

    The state is high while ``frac(P theta / 2 pi) < duty``. Each edge is placed at its exact
    time (the angle interpolated linearly between the samples) and drawn as a linear ramp of
    two samples centred there, so a trigger that interpolates its level crossing between two
    samples finds the edge exactly (as a measured, anti-alias filtered edge).
    """
    check_instance(tacho, Tacho, "tacho")
    angle = check_array(angle, "angle", ndim=1, min_size=0, max_abs=1e12)
    x = angle * tacho.pulses_per_rev / (2.0 * math.pi)
    duty = tacho.duty
    state = ((x - np.floor(x)) < duty).astype(float)
    out = state.copy()
    if x.size >= 2:
        k = np.flatnonzero(state[1:] != state[:-1])
        a, b = x[k], x[k + 1]
        lo, hi = np.minimum(a, b), np.maximum(a, b)
        rising = np.floor(hi) - np.floor(lo)  # integers in (lo, hi]
        falling = np.floor(hi - duty) - np.floor(lo - duty)
        single = (rising + falling) == 1  # one edge in the interval: place it exactly
        level = np.where(rising == 1, np.floor(hi), np.floor(hi - duty) + duty)
        tau = (level - a) / np.where(b != a, b - a, 1.0)  # edge time, fraction of a sample
        step = state[k + 1] - state[k]
        k, tau, step = k[single], tau[single], step[single]
        out[k] += step * (0.5 - 0.5 * tau)
        out[k + 1] += step * (-0.5 * tau)
    return tacho.level_v * np.clip(out, 0.0, 1.0)


def add_sensor_signals(result, model: AssembledModel):
    """The run result with its sensors' signals (``model.sensors``) added.

    Every housing sensor gives a row of ``sensor_acceleration``; a tacho (or, when the model
    has housing sensors but no tacho, a default tacho with one pulse per revolution of the
    input member) gives ``tacho``.
    """
    check_instance(result, "gearvib.simulation.result.RunUpResult", "result")
    check_instance(model, AssembledModel, "model")
    fs = float(result.step.fs_out)
    acc = [s for s in model.sensors if isinstance(s, HousingSensor)]
    tachos = [s for s in model.sensors if isinstance(s, Tacho)]
    if acc and not tachos:
        tachos = [Tacho(member=model.input_member)]
    kw: dict = {}
    if acc:
        rows = [housing_response(path_force(result, model, s), fs, s) for s in acc]
        kw["sensor_names"] = tuple(s.name for s in acc)
        kw["sensor_acceleration"] = np.ascontiguousarray(np.array(rows))
        kw["sensor_info"] = tuple(s.to_dict() for s in acc)
    if tachos:
        t = tachos[0]
        member = t.member or model.input_member
        kw["tacho"] = tacho_signal(_rotation(result, member), t)
        kw["tacho_info"] = {**t.to_dict(), "member": member}
    return replace(result, **kw)
