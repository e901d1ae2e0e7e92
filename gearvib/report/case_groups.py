"""Mesh-frequency groups of a run: the meshes that share a mesh frequency, with their central gears.

Every gear-set type is described by its mesh-frequency groups (:class:`MeshGroup`: one for a
simple or Ravigneaux set, one per stage of a two-stage set, one per planet toothing of a
Wolfrom set), each with its central gears and their meshes. :func:`model_groups` reads them
from a rebuilt model, :func:`stored_groups` from what a run file stores when the model cannot
be rebuilt, :func:`auto_orders` chooses the mesh orders drawn per group, and
:func:`is_paper_set` recognises the paper's example.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from gearvib.model import AssembledModel

__all__ = ["AUTO_ORDERS", "MeshGroup", "auto_orders", "is_paper_set", "model_groups",
           "stored_groups"]


AUTO_ORDERS = (7, 20)
"""``orders = 0``: per mesh frequency, enough mesh orders to reach the highest natural frequency
in the map at the top speed, at least 7 and at most 20."""


@dataclass(frozen=True)
class MeshGroup:
    """Meshes that share one mesh frequency, with their central gears.

    Attributes
    ----------
    name : str
        ``"mesh"`` for a set with one mesh frequency, else e.g. ``"stage 2"``, ``"ring2"``.
    frequency_per_rpm : float
        Mesh frequency per input speed [Hz per min^-1].
    meshes : tuple of str
        Every mesh of the group.
    centrals : tuple of (str, tuple of str)
        Each central gear (sun, ring, ...) with its meshes, in the order of the meshes; meshes
        between two planets belong to none.
    orders : int
        Mesh orders ``1..orders`` drawn and used for the resonance classification.
    """

    name: str
    frequency_per_rpm: float
    meshes: tuple[str, ...]
    centrals: tuple[tuple[str, tuple[str, ...]], ...]
    orders: int = 7

    @property
    def order(self) -> float:
        """Mesh cycles per input revolution."""
        return 60.0 * self.frequency_per_rpm

    @property
    def short(self) -> str:
        """Short name for plot labels (``"stage 2"`` -> ``"s2"``)."""
        return f"s{self.name[6:]}" if self.name.startswith("stage ") else self.name

    def tag(self, several: bool) -> str:
        """``" [stage 2]"`` when the set has several mesh frequencies, else ``""``."""
        return f" [{self.name}]" if several else ""


def _stage_name(prefix: str) -> str:
    """``"s1"`` (two-stage) and ``"stage1"`` (multi-stage) -> ``"stage 1"``."""
    for head in ("stage", "s"):
        if prefix.startswith(head) and prefix[len(head):].isdigit():
            return f"stage {prefix[len(head):]}"
    return prefix


def _central_of(mesh: str, planets: set[str] | None = None) -> str | None:
    """The central gear of a mesh (``"s1.sun-planet2"`` -> ``"s1.sun"``), None for a mesh
    between two planets."""
    head = mesh.split("-", 1)[0]
    if planets is not None:
        return None if head in planets else head
    return None if head.rsplit(".", 1)[-1].startswith("planet") else head


def _with_centrals(name: str, f: float, meshes: Sequence[str], planets: set[str] | None,
                   gear1: dict[str, str] | None = None) -> MeshGroup:
    centrals: dict[str, list[str]] = {}
    for m in meshes:
        c = (gear1 or {}).get(m) if gear1 else None
        c = c if c and (planets is None or c not in planets) else _central_of(m, planets)
        if c is not None:
            centrals.setdefault(c, []).append(m)
    return MeshGroup(name, float(f), tuple(meshes),
                     tuple((c, tuple(ms)) for c, ms in centrals.items()))


def model_groups(model: AssembledModel) -> list[MeshGroup]:
    """Mesh-frequency groups of a gear-set model, with the central gear of every mesh.

    Parameters
    ----------
    model : AssembledModel
        The gear set (:meth:`~gearvib.model.AssembledModel.mesh_frequency_groups`).

    Returns
    -------
    list of MeshGroup
        Reference group first, ``orders`` at its default.
    """
    planets = {str(p["name"]) for p in model.meta.get("planets", [])}
    gear1 = {str(d.get("name")): str(d.get("gear1")) for d in model.meta.get("meshes", [])
             if isinstance(d, dict) and d.get("gear1")}
    return [_with_centrals(g.name, g.frequency_per_rpm, g.mesh_names, planets or None, gear1)
            for g in model.mesh_frequency_groups()]


def stored_groups(ds: xr.Dataset) -> list[MeshGroup]:
    """Mesh-frequency groups from ``mesh_frequency(mesh, time)`` [Hz per min^-1].

    Reads also the single ``mesh_frequency(time)`` of runs written before every mesh had its
    own. Groups are named like :meth:`gearvib.model.AssembledModel.mesh_frequency_groups`
    (stage prefix or numbered).

    Parameters
    ----------
    ds : xarray.Dataset
        The run (``mesh_frequency``, ``input_speed``, ``mesh``).

    Returns
    -------
    list of MeshGroup

    Raises
    ------
    ValueError
        The run has no speed > 0 or no mesh with a mesh frequency.
    """
    fm = np.asarray(ds["mesh_frequency"].values, dtype=float)
    sp = np.abs(np.asarray(ds["input_speed"].values, dtype=float))
    ok = sp > 0.05 * sp.max()
    if not ok.any():
        raise ValueError("the run has no speed > 0: cannot derive the mesh frequency per speed")
    meshes_all = [str(m) for m in ds["mesh"].values]
    if fm.ndim == 1:
        return [_with_centrals("mesh", float(np.median(fm[ok] / sp[ok])), meshes_all, None)]
    meshes = [str(m) for m in ds["mesh_frequency"]["mesh"].values]
    per_mesh = np.median(fm[:, ok] / sp[ok], axis=1)
    groups: list[tuple[float, list[str]]] = []
    for name, f in zip(meshes, per_mesh, strict=True):
        if not (np.isfinite(f) and f > 0):
            continue
        for g in groups:
            if abs(f - g[0]) <= 1e-6 * max(f, g[0]):
                g[1].append(name)
                break
        else:
            groups.append((float(f), [name]))
    if not groups:
        raise ValueError("the run has no mesh with a mesh frequency")
    if len(groups) == 1:
        return [_with_centrals("mesh", groups[0][0], groups[0][1], None)]
    heads = [{m.split(".", 1)[0] for m in g[1]} for g in groups]
    if all(len(h) == 1 and all("." in m for m in g[1]) for h, g in zip(heads, groups,
                                                                      strict=True)) \
            and len({next(iter(h)) for h in heads}) == len(groups):
        names = [_stage_name(next(iter(h))) for h in heads]
    else:
        names = [f"f_mesh,{i + 1}" for i in range(len(groups))]
    return [_with_centrals(n, g[0], g[1], None) for n, g in zip(names, groups, strict=True)]


def auto_orders(groups: list[MeshGroup], fn: np.ndarray, fmax: float, top_rpm: float,
                setting: int) -> list[MeshGroup]:
    """Mesh orders per group.

    Parameters
    ----------
    groups : list of MeshGroup
        The groups.
    fn : ndarray
        Natural frequencies [Hz].
    fmax : float
        Upper frequency of the map [Hz].
    top_rpm : float
        Top input speed [min^-1].
    setting : int
        ``[analysis] orders``: this many orders, or (0) enough to reach the highest natural
        frequency below ``fmax`` at the top speed, within :data:`AUTO_ORDERS`.

    Returns
    -------
    list of MeshGroup
        The groups with their ``orders``.
    """
    out = []
    for g in groups:
        if setting > 0:
            k = setting
        else:
            inside = fn[fn <= fmax]
            f_top = float(inside.max()) if inside.size else fmax
            need = math.ceil(f_top / max(g.frequency_per_rpm * top_rpm, 1e-300))
            k = int(np.clip(need, *AUTO_ORDERS))
        out.append(MeshGroup(g.name, g.frequency_per_rpm, g.meshes, g.centrals, k))
    return out


def is_paper_set(model: AssembledModel | None, gs: dict) -> bool:
    """The paper's example: a simple set, z_s = 33, z_r = -114, three planets.

    Parameters
    ----------
    model : AssembledModel or None
        The rebuilt gear set.
    gs : dict
        Its description (``type``).

    Returns
    -------
    bool
    """
    if model is None or str(gs.get("type", "simple")) != "simple":
        return False
    z = {int(m["z1"]) for m in model.meta.get("meshes", []) if m.get("z1") is not None}
    return z == {33, -114} and len(model.meta.get("planets", [])) == 3

