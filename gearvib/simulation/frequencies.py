"""Natural frequencies of the system of a run (for the step choice and the drive coupling)."""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from gearvib.modal import rigid_body_mask
from gearvib.model import AssembledModel

__all__ = ["elastic_frequencies", "stiffest_matrix", "undamped_frequencies"]


def undamped_frequencies(mass: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Undamped natural frequencies [Hz] of ``(M, K)``, rigid-body modes included (0)."""
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
    if freqs.size == 0:
        return freqs
    if mass is not None and stiffness is not None:
        _, phi = scipy.linalg.eigh(stiffness, mass)
        return freqs[~rigid_body_mask(stiffness, phi)]
    return freqs[freqs > 1e-6 * freqs.max()]


def stiffest_matrix(model: AssembledModel, torque_sign: float = 1.0) -> np.ndarray:
    """Constant stiffness plus every loaded flank at its stiffest (both flanks if j < 0;
    :meth:`AssembledModel.mesh_contacts`)."""
    contacts = model.mesh_contacts(torque_sign)
    return model.stiffness + contacts.stiffness_matrix(contacts.peak)
