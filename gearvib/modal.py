"""Modal analysis of the mean-stiffness system: natural frequencies, classified mode shapes.

Modes are classified as in Lin & Parker (1999) for planetary gears:

* ``rigid-body``: zero frequency (a free member, e.g. the input without a drive), decided
  scale-aware by :func:`rigid_body_mask`;
* ``rotational``: the central members only rotate (no translation);
* ``translational``: the central members only translate (no rotation);
* ``planet``: the central members and carriers are at rest, only planets move;
* ``other``: anything else (e.g. unequally spaced planets, where the pure families mix).

A mode's *multiplicity* is the number of modes sharing its frequency (relative tolerance
``1e-7``): with N equally spaced planets the translational modes come in pairs and the planet
modes N - 3 times (N - 1 in a purely torsional model).

The mean system is that of the flanks in contact at the mean load
(:meth:`AssembledModel.mesh_contacts`): the left flank on its line of action, the right flank
on the mirror-image line where the static load puts it on the back flank (Ravigneaux
planet-planet and ring meshes, Wolfrom ring-2 meshes), both flanks (``k_L + k_R``, each on its
own line) for a negative backlash.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from gearvib.checks import check_instance, check_real
from gearvib.kinematics import MAX_SPEED_RPM
from gearvib.model import FLANK_NAMES, AssembledModel

if TYPE_CHECKING:
    import xarray as xr

__all__ = ["RIGID_BODY_RTOL", "ModalResult", "modal_analysis", "rigid_body_mask"]

_REL_ENERGY = 1e-6
_REL_FREQ = 1e-7
RIGID_BODY_RTOL = 1e-10
"""A mode is rigid-body when its strain energy ``|phi^H K phi|`` is below this fraction of
``phi^H |K| phi`` (the same quadratic form with every entry of ``K`` taken positive): the
energy then cancels to rounding. An elastic element more than 1e10 times softer than the
stiffest element its mode strains would be mistaken for a rigid-body motion."""


def rigid_body_mask(stiffness: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """Scale-aware test for rigid-body modes.

    A relative threshold on the frequency (e.g. 1e-6 of the highest) fails when one support is
    many orders of magnitude stiffer than the meshes: a support of 1e16 N/m raises the highest
    frequency so far that a real mode at a few hundred hertz falls below it. Here every mode is
    measured against its own stiffness scale: the strain energy ``phi^H K phi`` of a rigid-body
    motion cancels to rounding between the terms of ``|phi|^T |K| |phi|`` (the elements it
    moves without straining them), that of an elastic mode does not. The energy is evaluated
    from the mode shape (a Rayleigh quotient, accurate to the rounding of that mode's own
    terms), not taken from the eigenvalue, whose absolute error grows with the stiffest element
    of the whole system.

    Parameters
    ----------
    stiffness : ndarray, shape (n, n)
        ``K`` of the eigenproblem (with ``-Omega^2 K_Omega`` for a rotating frame).
    shapes : ndarray, shape (n, n_mode)
        Mode shapes (real or complex), any normalisation.

    Returns
    -------
    ndarray of bool, shape (n_mode,)
        True where ``|phi^H K phi| <= RIGID_BODY_RTOL |phi|^T |K| |phi|``.
    """
    k = np.asarray(stiffness)
    phi = np.asarray(shapes)
    energy = np.abs(np.real(np.einsum("im,ij,jm->m", phi.conj(), k, phi)))
    scale = np.einsum("im,ij,jm->m", np.abs(phi), np.abs(k), np.abs(phi))
    return energy <= RIGID_BODY_RTOL * scale


@dataclass(frozen=True)
class ModalResult:
    """Natural frequencies and mode shapes of the mean system.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (n_mode,)
        Natural frequencies [Hz], ascending.
    shapes : ndarray, shape (n_dof, n_mode)
        Mass-normalised mode shapes (complex magnitudes for the gyroscopic case).
    kinds : tuple of str
        Classification of every mode (see module docstring).
    multiplicity : tuple of int
        Number of modes at the same frequency.
    mesh_energy : ndarray, shape (n_mode, n_mesh)
        Fraction of the modal strain energy in each mesh.
    bearing_energy : ndarray, shape (n_mode, n_bearing)
        Fraction of the modal strain energy in each elastic bearing direction.
    dof_names, mesh_names, bearing_names : tuple of str
        Labels of the axes.
    carrier_speed_rpm : float
        Carrier speed of the analysis [min^-1] (gyroscopic and centripetal terms if nonzero).
    loaded_flanks : tuple of str
        Flank of every mesh in the mean system: ``"left"``, ``"right"`` or ``"both"``
        (:meth:`AssembledModel.loaded_flanks`).
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    kinds: tuple[str, ...]
    multiplicity: tuple[int, ...]
    mesh_energy: np.ndarray
    bearing_energy: np.ndarray
    dof_names: tuple[str, ...]
    mesh_names: tuple[str, ...]
    bearing_names: tuple[str, ...]
    carrier_speed_rpm: float = 0.0
    loaded_flanks: tuple[str, ...] = ()

    @property
    def n_modes(self) -> int:
        """Number of modes."""
        return len(self.frequencies_hz)

    def elastic(self) -> np.ndarray:
        """Frequencies of the modes that are not rigid-body modes [Hz]."""
        keep = np.array([k != "rigid-body" for k in self.kinds], dtype=bool)
        return self.frequencies_hz[keep]

    def to_dict(self) -> dict:
        """``{"modes": [{"frequency_hz", "kind", "multiplicity"}, ...]}``, one entry per mode."""
        return {"modes": [
            {"frequency_hz": float(f), "kind": k, "multiplicity": int(m)}
            for f, k, m in zip(self.frequencies_hz, self.kinds, self.multiplicity, strict=True)
        ]}

    def to_json(self) -> str:
        """JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict(), indent=2)

    def table(self) -> str:
        """A plain-text table of the modes."""
        lines = [f"{'mode':>4}  {'f [Hz]':>10}  {'kind':<14} {'mult':>4}  dominant mesh"]
        for i, (f, k, m) in enumerate(zip(self.frequencies_hz, self.kinds, self.multiplicity,
                                          strict=True), start=1):
            dom = ""
            if self.mesh_energy.shape[1] and self.mesh_energy[i - 1].max() > 1e-6:
                j = int(np.argmax(self.mesh_energy[i - 1]))
                dom = f"{self.mesh_names[j]} ({100 * self.mesh_energy[i - 1, j]:.0f} %)"
            lines.append(f"{i:>4}  {f:>10.2f}  {k:<14} {m:>4}  {dom}")
        return "\n".join(lines)

    def to_dataset(self) -> xr.Dataset:
        """The modes as a CF-annotated Dataset."""
        import xarray as xr  # on use: `gearvib modes` does not need it

        from analysis.cf import cf_dataset

        mode = np.arange(1, self.n_modes + 1)
        ds = xr.Dataset(
            {
                "natural_frequency": ("mode", self.frequencies_hz,
                                      {"units": "Hz", "long_name": "natural frequency"}),
                "mode_kind": ("mode", np.array(self.kinds, dtype=str),
                              {"long_name": "mode classification"}),
                "multiplicity": ("mode", np.array(self.multiplicity, dtype=np.int32),
                                 {"units": "1", "long_name": "modes at the same frequency"}),
                "mode_shape": (("dof", "mode"), np.abs(self.shapes) if np.iscomplexobj(
                    self.shapes) else self.shapes,
                               {"units": "1", "long_name": "mass-normalised mode shape"}),
                "mesh_energy_fraction": (("mode", "mesh"), self.mesh_energy,
                                         {"units": "1",
                                          "long_name": "modal strain energy fraction in mesh"}),
                "bearing_energy_fraction": (("mode", "bearing"), self.bearing_energy,
                                            {"units": "1", "long_name":
                                             "modal strain energy fraction in bearing"}),
            },
            coords={
                "mode": ("mode", mode, {"long_name": "mode number", "units": "1"}),
                "dof": ("dof", list(self.dof_names), {"long_name": "coordinate"}),
                "mesh": ("mesh", list(self.mesh_names), {"long_name": "tooth contact"}),
                "bearing": ("bearing", list(self.bearing_names),
                            {"long_name": "bearing direction"}),
            },
            attrs={"carrier_speed_rpm": float(self.carrier_speed_rpm)},
        )
        if len(self.loaded_flanks) == len(self.mesh_names):
            ds["loaded_flank"] = ("mesh", np.array(self.loaded_flanks, dtype=str),
                                  {"long_name": "flank in contact in the mean system "
                                   "(left, right or both)"})
        return cf_dataset(
            ds, title="natural frequencies and mode shapes",
            producer="gearvib.modal.modal_analysis"
        )


def _classify(model: AssembledModel, phi: np.ndarray, rigid: bool) -> str:
    if rigid:
        return "rigid-body"
    m_diag = np.real(np.diag(model.mass))
    energy = m_diag * np.abs(phi) ** 2
    total = energy.sum()
    central_rot = central_trans = 0.0
    for i, name in enumerate(model.dof_names):
        body, comp = name.rsplit(".", 1)
        role = _role(model, body)
        if role == "planet":
            continue
        if comp == "theta":
            central_rot += energy[i]
        elif comp in ("x", "y"):
            central_trans += energy[i]
    # carrier-coupled masses (absolute planet eta) make M non-diagonal only through constraints;
    # use the kinetic energy of the full quadratic form as the total
    total = float(np.real(np.conj(phi) @ model.mass @ phi)) or total
    tol = _REL_ENERGY * total
    if central_rot <= tol and central_trans <= tol:
        return "planet"
    if central_trans <= tol:
        return "rotational"
    if central_rot <= tol:
        return "translational"
    return "other"


def _role(model: AssembledModel, body: str) -> str:
    for b in model.meta.get("bodies", []):
        if b["name"] == body:
            return b["role"]
    return "planet" if body.startswith("planet") else "central"


def _multiplicity(freqs: np.ndarray) -> list[int]:
    out = []
    for f in freqs:
        tol = _REL_FREQ * max(abs(f), 1e-9) + 1e-9
        out.append(int(np.sum(np.abs(freqs - f) <= tol)))
    return out


def modal_analysis(model: AssembledModel, *, carrier_speed_rpm: float = 0.0,
                   stiffness_scale: float = 1.0, torque_sign: float = 1.0) -> ModalResult:
    """Natural frequencies and mode shapes of the mean-stiffness system.

    The mean system holds the flanks in contact at the mean load (see the module docstring):
    ``K + sum_c k_c u_c u_c^T`` over the contacts of :meth:`AssembledModel.mesh_contacts`.

    Parameters
    ----------
    model : AssembledModel
        The assembled gear set.
    carrier_speed_rpm : float
        Carrier speed [min^-1]; when nonzero the gyroscopic (``Omega G``) and centripetal
        (``-Omega^2 K_Omega``) terms of Lin & Parker (1999) are included (frame rotating at the
        constant speed ``Omega``) and a quadratic eigenproblem is solved. The simulator refers
        the terms to the carrier's actual angle instead
        (:meth:`AssembledModel.carrier_frame_operators`): modes without carrier rotation agree
        exactly, the others to second order (0.1 % at 3000 min^-1 on ``paper-case1-elastic``).
    stiffness_scale : float
        Factor on every mesh stiffness (for sensitivity studies), 1e-12 .. 1e12.
    torque_sign : float
        Sense of the mean load: +1 the input drives forward (default), -1 reversed (coast,
        every flank swapped).

    Returns
    -------
    ModalResult
    """
    check_instance(model, AssembledModel, "model")
    carrier_speed_rpm = check_real(carrier_speed_rpm, "carrier_speed_rpm", low=-MAX_SPEED_RPM,
                                   high=MAX_SPEED_RPM)
    stiffness_scale = check_real(stiffness_scale, "stiffness_scale", low=1e-12, high=1e12)
    contacts = model.mesh_contacts(torque_sign)
    k_contact = contacts.mean_stiffness() * stiffness_scale
    k = model.stiffness + contacts.stiffness_matrix(k_contact)
    m = model.mass
    omega_c = carrier_speed_rpm * 2 * math.pi / 60.0
    if omega_c == 0.0:
        w2, phi = scipy.linalg.eigh(k, m)
        rigid = rigid_body_mask(k, phi)
        w2 = np.where(rigid, 0.0, w2)
        if (w2 < 0).any():
            raise ValueError("mean stiffness matrix is not positive semi-definite "
                             f"(eigenvalue {w2.min():.3g}); check for negative stiffness")
        freqs = np.sqrt(w2) / (2 * math.pi)
    else:
        n = m.shape[0]
        kk = k - omega_c**2 * model.centripetal
        a = np.block([[np.zeros((n, n)), np.eye(n)],
                      [-np.linalg.solve(m, kk), -np.linalg.solve(m, omega_c * model.gyroscopic)]])
        lam, vec = np.linalg.eig(a)
        # one eigenvalue of every oscillating pair (imag > 0); of the non-oscillating ones (a
        # rigid-body mode gives a double zero) only as many as the pairs leave to make n
        tol = 1e-9 * max(float(np.abs(lam).max()), 1.0)
        osc = np.flatnonzero(lam.imag > tol)
        flat = np.flatnonzero(np.abs(lam.imag) <= tol)
        flat = flat[np.argsort(-lam[flat].real, kind="stable")][: max(n - osc.size, 0)]
        idx = np.concatenate([flat, osc])
        lam, vec = lam[idx], vec[:n, idx]
        order = np.argsort(np.abs(lam.imag), kind="stable")
        lam, vec = lam[order], vec[:, order]
        freqs = np.abs(lam.imag) / (2 * math.pi)
        norms = np.sqrt(np.real(np.einsum("im,ij,jm->m", vec.conj(), m, vec)))
        phi = vec / norms
        # rigid-body: a non-oscillating eigenvalue (at speed the centripetal terms strain the
        # absolute planet coordinates of the rigid rotation slightly), or no strain energy
        rigid = (np.abs(lam.imag) <= tol) | rigid_body_mask(kk, phi)
        freqs = np.where(rigid, 0.0, freqs)
    kinds = tuple(_classify(model, phi[:, i], bool(rigid[i])) for i in range(len(freqs)))
    mult = tuple(_multiplicity(freqs))

    defl = contacts.vectors @ phi
    u_mesh = contacts.per_mesh((0.5 * k_contact[:, None] * np.abs(defl) ** 2).T).T
    u_b = 0.5 * model.bearing_stiffness[:, None] * np.abs(model.bearing_vectors @ phi) ** 2
    total = 0.5 * np.real(np.einsum("im,ij,jm->m", phi.conj(), k, phi))
    with np.errstate(invalid="ignore", divide="ignore"):
        mesh_frac = np.where(total > 0, u_mesh / total, 0.0).T
        bear_frac = np.where(total > 0, u_b / total, 0.0).T
    return ModalResult(
        frequencies_hz=freqs,
        shapes=phi,
        kinds=kinds,
        multiplicity=mult,
        mesh_energy=np.nan_to_num(mesh_frac),
        bearing_energy=np.nan_to_num(bear_frac),
        dof_names=model.dof_names,
        mesh_names=model.mesh_names,
        bearing_names=model.bearing_names,
        carrier_speed_rpm=float(carrier_speed_rpm),
        loaded_flanks=tuple(FLANK_NAMES[int(f)] for f in contacts.flanks),
    )
