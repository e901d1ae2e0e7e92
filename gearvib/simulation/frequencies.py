"""Natural frequencies of the system of a run (for the step choice and the drive coupling)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import scipy.linalg

from gearvib.checks import check_array, check_instance, check_matrix
from gearvib.modal import rigid_body_mask
from gearvib.model import AssembledModel

__all__ = ["check_mass", "elastic_frequencies", "stiffest_matrix", "undamped_frequencies"]


def check_mass(mass: Any) -> np.ndarray:
    """A mass matrix: finite, square, symmetric, positive definite (:func:`check_matrix`)."""
    m = check_matrix(mass, "mass")
    if not np.allclose(m, m.T, rtol=1e-10, atol=1e-14 * float(np.abs(m).max(initial=0.0))):
        raise ValueError("mass must be symmetric")
    try:
        np.linalg.cholesky(m)
    except np.linalg.LinAlgError:
        raise ValueError("mass must be positive definite (all eigenvalues > 0)") from None
    return m


def undamped_frequencies(mass: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Undamped natural frequencies [Hz] of ``(M, K)``, rigid-body modes included (0)."""
    mass = check_mass(mass)
    stiffness = check_matrix(stiffness, "stiffness", mass.shape[0])
    w2 = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.clip(w2, 0.0, None)) / (2.0 * math.pi)


def elastic_frequencies(freqs: np.ndarray, mass: np.ndarray | None = None,
                        stiffness: np.ndarray | None = None) -> np.ndarray:
    """``freqs`` (ascending, from :func:`undamped_frequencies`) without the rigid-body modes.

    With ``mass`` and ``stiffness`` the test is scale-aware (:func:`gearvib.modal.rigid_body_mask`:
    a mode whose ``omega^2`` is rounding against its own stiffness scale is rigid); without
    them a mode below 1e-6 of the highest frequency is rigid (adequate unless a support is many
    orders stiffer than the meshes).
    """
    freqs = check_array(freqs, "freqs", ndim=1, min_size=0, max_abs=1e100)
    if freqs.size and freqs.min() < 0:
        raise ValueError("freqs must be >= 0 [Hz]")
    if (mass is None) != (stiffness is None):
        raise ValueError("give both mass and stiffness, or neither")
    if freqs.size == 0:
        return freqs
    if mass is not None and stiffness is not None:
        mass = check_mass(mass)
        stiffness = check_matrix(stiffness, "stiffness", mass.shape[0])
        if freqs.size != mass.shape[0]:
            raise ValueError(f"freqs must hold one frequency per mode ({mass.shape[0]}); got "
                             f"{freqs.size}")
        _, phi = scipy.linalg.eigh(stiffness, mass)
        return freqs[~rigid_body_mask(stiffness, phi)]
    return freqs[freqs > 1e-6 * freqs.max()]


def stiffest_matrix(model: AssembledModel, torque_sign: float = 1.0) -> np.ndarray:
    """Constant stiffness plus every loaded flank at its stiffest (both flanks if j < 0;
    :meth:`AssembledModel.mesh_contacts`)."""
    check_instance(model, AssembledModel, "model")
    contacts = model.mesh_contacts(torque_sign)
    return model.stiffness + contacts.stiffness_matrix(contacts.peak)
