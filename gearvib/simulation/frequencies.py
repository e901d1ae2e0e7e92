"""Natural frequencies of the system of a run (for the step choice and the drive coupling)."""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from gearvib.model import AssembledModel

__all__ = ["elastic_frequencies", "stiffest_matrix", "undamped_frequencies"]


def undamped_frequencies(mass: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Undamped natural frequencies [Hz] of ``(M, K)``, rigid-body modes included (0)."""
    w2 = scipy.linalg.eigh(stiffness, mass, eigvals_only=True)
    return np.sqrt(np.clip(w2, 0.0, None)) / (2.0 * math.pi)


def elastic_frequencies(freqs: np.ndarray) -> np.ndarray:
    """``freqs`` without the rigid-body modes (below 1e-6 of the highest frequency)."""
    if freqs.size == 0:
        return freqs
    return freqs[freqs > 1e-6 * freqs.max()]


def stiffest_matrix(model: AssembledModel) -> np.ndarray:
    """Constant stiffness plus every mesh at its stiffest (both flanks if j < 0)."""
    kmax = model.mesh_stiffness_tables.max(axis=1)
    both = np.asarray(model.mesh_backlash) < 0
    kmax = kmax + np.where(both, model.mesh_back_tables.max(axis=1), 0.0)
    return model.stiffness + model.mesh_stiffness_matrix(kmax)
