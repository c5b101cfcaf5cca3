"""Analyses that depend on a model alone, solved once per model and kept in the process.

A study's worker runs many points of one body that differ only in the run (speed, duration):
the step bound of the explicit integrator (`solver.mbs.stability.stability_limit`), the modal
analysis (`solver.mbs.modes.modal_analysis`) and the simulated free decay
(`solver.mbs.ringdown.ring_down`) read the model and the load only, and each costs tens of
milliseconds, about as much as a short dynamic run. They are kept here by a digest of what
they read (`model_digest`: the model's arrays, its tooth counts and base radii, dampers
included) and their arguments, so that a model changed in place, or another model with the
same arrays, is never confused with or mistaken for a kept one. The caller gets a copy.
"""
from __future__ import annotations

import copy
import hashlib
from collections import OrderedDict

import numpy as np

_KEPT: OrderedDict = OrderedDict()
KEEP = 64           # results kept (a point asks for a few per model: bounds, modes, a decay)


def model_digest(model) -> str:
    """Digest of everything the model-only analyses read: the parameter arrays (gear, pair,
    law, springs, tooth compliance), the tooth counts and the base radii."""
    h = hashlib.blake2b(digest_size=16)
    for a in (model.gear_par, model.pair_par, model.law_par, model.k_phi, model.tooth_compliance,
              np.array([*model.teeth, *model.base_radii], float)):
        a = np.ascontiguousarray(a, dtype=float)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def kept(name: str, model, args: tuple, compute):
    """``compute()``, solved once per (name, `model_digest`, args) and kept (the last KEEP);
    the caller gets a deep copy of the kept result. An exception is not kept."""
    key = (name, model_digest(model), args)
    if key in _KEPT:
        _KEPT.move_to_end(key)
    else:
        _KEPT[key] = compute()
        while len(_KEPT) > KEEP:
            _KEPT.popitem(last=False)
    return copy.deepcopy(_KEPT[key])


def forget() -> None:
    """Drop every kept result (tests, benchmarks that time an analysis from scratch)."""
    _KEPT.clear()
