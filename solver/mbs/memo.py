"""Analyses that depend on a model alone, solved once per model and kept in the process.

A study's worker runs many points of one body that differ only in the run (speed, duration):
the step bound of the explicit integrator (`solver.mbs.stability.stability_limit`), the modal
analysis (`solver.mbs.modes.modal_analysis`) and the simulated free decay
(`solver.mbs.ringdown.ring_down`) read the model and the load only, and each costs tens of
milliseconds, about as much as a short dynamic run. They are kept here by a digest of what
they read (`model_digest`: the model's arrays, its tooth counts and base radii, dampers
included) and their arguments, so that a model changed in place, or another model with the
same arrays, is never confused with or mistaken for a kept one (a shelf of
`solver.store.STORE`). The caller gets a copy.
"""
from __future__ import annotations

import copy

import numpy as np

from solver.store import STORE, digest

KEEP = 64           # results kept (a point asks for a few per model: bounds, modes, a decay)
KEPT = STORE.shelf("model-only analyses", KEEP)


def model_digest(model) -> str:
    """Digest of everything the model-only analyses read: the parameter arrays (gear, pair,
    law, springs, tooth compliance), the tooth counts and the base radii."""
    return digest(*(np.asarray(a, dtype=float) for a in (
        model.gear_par, model.pair_par, model.law_par, model.k_phi, model.tooth_compliance,
        np.array([*model.teeth, *model.base_radii], float))))


def kept(name: str, model, args: tuple, compute):
    """``compute()``, solved once per (name, `model_digest`, args) and kept (the last KEEP);
    the caller gets a deep copy of the kept result. An exception is not kept."""
    return copy.deepcopy(KEPT.kept((name, model_digest(model), args), compute))


def forget() -> None:
    """Drop the kept results of this shelf (benchmarks that time an analysis from scratch;
    `solver.store.STORE.clear` drops every shelf)."""
    KEPT.clear()
