"""The FE cache: one object for everything the FE of a gear body produces and a run reuses.

On disk, under ``$LIGHTGEAR_CACHE/fe`` (default ``./.lightgear-cache/fe``), one file per result,
named by `FECache.key` of everything the result depends on:

* ``{key}.nc``: a tooth-stiffness map (NetCDF, ``k_fe`` [N·m/rad] per tooth, the settings as a
  JSON attribute) and the largest fillet stress of each tooth under the same load
  (``root_stress`` [Pa]; a file written before it was stored lacks it: the map is then
  recomputed when the stress is asked for);
* ``ltca-{key}.npz``: a body's bulk compliance (`solver.fe.flank_compliance.BodyCompliance`);
* ``fields-{key}.npz``: a body's FE fields under the load on a few teeth (mesh, displacement,
  von Mises stress: `solver.fe.body.BodyField`), for the renders of an archive (written by the
  run that made the archive while it held the factorised body, else by the first render).
* ``rim-{key}.npz``: the teeth and rim of one rim height condensed onto the web
  (`solver.fe.condense`: the condensed stiffness and the DOF positions it belongs to), and
  ``rim-{key}-{load set}.npz`` its products of a compliance load set.

In memory, on shelves of the process's one store (`solver.store.STORE`, which
`STORE.clear()` empties; the disk stays): the maps and compliances once read or computed (the
last `MAP_SLOTS` and `COMPLIANCE_SLOTS`), the last `BODY_SLOTS` factorised bodies (a reference
and the coupling fits of both gears reuse them), the last `RIM_SLOTS` condensed rims (every
body of one rim height reuses one) and the last `FIT_SLOTS` coupling fits. `FE_CACHE` is the
process-wide instance. A missing or unreadable file is recomputed; a read-only folder only
costs recomputation.
"""
from __future__ import annotations

import hashlib
import json
import os
import warnings
import zipfile
import zlib
from pathlib import Path

import numpy as np

from solver.store import STORE

BODY_SLOTS = 2      # factorised bodies kept: one per gear (each up to ~0.5 GB)
RIM_SLOTS = 2       # condensed teeth-and-rim blocks kept (each up to ~0.4 GB with its factors)
FIT_SLOTS = 16      # coupling fits kept (small: a few arrays of the tooth count)
MAP_SLOTS = 512     # tooth stiffness maps and fillet stresses kept (an array of the tooth count each)
COMPLIANCE_SLOTS = 16   # bulk compliances kept (a few MB each)
# what reading a damaged cache file raises: truncated or empty (zip, zlib, end of file), an
# array or a variable missing or of another shape, a NetCDF file HDF cannot read
UNREADABLE = (OSError, EOFError, zipfile.BadZipFile, zlib.error, KeyError, IndexError, ValueError, TypeError)


class FECache:
    """FE results in memory and on disk, keyed by the hash of their settings."""

    def __init__(self):
        self.stiffness = STORE.shelf("FE tooth stiffness maps", MAP_SLOTS)     # key -> [N·m/rad] per tooth
        self.root_stress = STORE.shelf("FE fillet stresses", MAP_SLOTS)        # key -> largest stress of each tooth [Pa]
        self.compliance = STORE.shelf("FE bulk compliances", COMPLIANCE_SLOTS)  # key -> BodyCompliance
        self.bodies = STORE.shelf("FE factorised bodies", BODY_SLOTS)          # body key -> factorised BodyModel
        self.fits = STORE.shelf("coupling fits", FIT_SLOTS)                    # fit key -> coupling fit
        self.rims = STORE.shelf("FE condensed rims", RIM_SLOTS)                # rim key -> `solver.fe.condense.RimBlock`

    @property
    def folder(self) -> Path:
        """The disk folder, read from ``$LIGHTGEAR_CACHE`` at each use."""
        return Path(os.environ.get("LIGHTGEAR_CACHE", ".lightgear-cache")) / "fe"

    @staticmethod
    def key(settings: dict) -> str:
        """20 hex digits of the SHA-256 of the settings as sorted JSON (numbers as floats)."""
        return hashlib.sha256(json.dumps(settings, sort_keys=True, default=float).encode()).hexdigest()[:20]

    def _read(self, held: dict, key: str, name: str, load):
        """The result of ``key`` from ``held``, else loaded from the file ``name`` by
        `read_file` (None when the file is missing or damaged: it is then recomputed and
        overwritten)."""
        if key not in held:
            value = self.read_file(name, load)
            if value is None:
                return None
            held[key] = value
        return held[key]

    def read_file(self, name: str, load):
        """``load(path)`` of the cache file ``name``, or None when it is missing, or damaged
        (truncated, empty, an array or a variable missing: every kind of file of the cache
        alike): a warning names the file, and the caller computes the result again and
        overwrites it."""
        path = self.folder / name
        if not path.exists():
            return None
        try:
            return load(path)
        except UNREADABLE as e:
            if path.exists():       # (not a file another process was replacing)
                why = (str(e).splitlines() or [""])[0][:120]
                warnings.warn(f"damaged FE cache file {path} ({type(e).__name__}: {why}): computing it again",
                              RuntimeWarning, stacklevel=3)
            return None

    # ---- tooth stiffness maps
    def _read_array(self, held: dict, key: str, var: str) -> np.ndarray | None:
        """A copy of the variable ``var`` of the map file of ``key``, from ``held`` or disk, or None."""
        def load(path):
            import xarray as xr
            with xr.open_dataset(path) as ds:       # (a map written before its stresses were stored lacks them)
                return ds[var].values.copy() if var in ds else None
        a = self._read(held, key, f"{key}.nc", load)
        return None if a is None else a.copy()

    def read_stiffness(self, key: str) -> np.ndarray | None:
        """A copy of the stiffness map of ``key`` from memory or disk, or None."""
        return self._read_array(self.stiffness, key, "k_fe")

    def read_root_stress(self, key: str) -> np.ndarray | None:
        """A copy of the fillet stresses [Pa] stored with the map of ``key``, or None."""
        return self._read_array(self.root_stress, key, "root_stress")

    def write_stiffness(self, key: str, k: np.ndarray, settings: dict, root_stress: np.ndarray | None = None) -> None:
        """Store the map ``k`` [N·m/rad] and, when given, the fillet stresses [Pa] of the same teeth."""
        import xarray as xr

        from study.archive.netcdf import write_netcdf
        self.stiffness[key] = k.copy()
        data = {"k_fe": xr.Variable("tooth", k, {"units": "N m rad-1", "long_name": "FE tooth torsion stiffness"})}
        if root_stress is not None:
            self.root_stress[key] = root_stress.copy()
            data["root_stress"] = xr.Variable("tooth", root_stress, {
                "units": "Pa", "long_name": "largest von Mises fillet stress under the tooth's own reference load"})
        ds = xr.Dataset(data, attrs={"settings": json.dumps(settings, default=float)})
        try:
            write_netcdf(ds, self.folder / f"{key}.nc")
        except OSError:
            pass

    # ---- bulk compliances
    def read_compliance(self, key: str):
        """The `BodyCompliance` of ``key`` from memory or disk, or None."""
        def load(path):
            from solver.fe.flank_compliance import BodyCompliance
            with np.load(path) as d:
                return BodyCompliance(d["u"], d["read"], d["load"], d["g"], bool(d["symmetric"]), int(d["teeth"]))
        return self._read(self.compliance, key, f"ltca-{key}.npz", load)

    def write_compliance(self, key: str, c) -> None:
        self.compliance[key] = c
        path = self.folder / f"ltca-{key}.npz"
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f".{path.stem}.tmp.npz")      # readers never see a half-written file
            np.savez(tmp, u=c.u, read=c.read_teeth, load=c.load_teeth, g=c.g, symmetric=c.symmetric_body, teeth=c.teeth)
            tmp.replace(path)
        except OSError:
            pass

    # ---- body fields (renders)
    def read_fields(self, key: str) -> list | None:
        """The `BodyField` list of ``key`` from disk, or None (not held in memory: a render reads
        them once)."""
        def load(path):
            from solver.fe.body import BodyField
            with np.load(path) as d:
                return [BodyField(d["points"], d["triangles"], d["thickness"], d["web"], d["displacement"][j],
                                  d["von_mises"][j], int(d["tooth"][j]), float(d["load_N"][j]), d["load_point"][j],
                                  d["load_direction"][j]) for j in range(d["tooth"].size)]
        return self._read({}, key, f"fields-{key}.npz", load)

    def write_fields(self, key: str, fields: list) -> None:
        """Store the `BodyField` list of one body (one mesh; one load case each)."""
        path = self.folder / f"fields-{key}.npz"
        f0 = fields[0]
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f".{path.stem}.tmp{os.getpid()}.npz")      # readers never see a half-written file
            # uncompressed: 1.6 MB for a 21,000-element body, against 1 MB zipped for 0.05 s more
            # of a run's CPU (a run stores its render's fields: `study.inputs.springs.keep_render_fields`)
            np.savez(tmp, points=f0.points, triangles=f0.triangles, thickness=f0.thickness, web=f0.web,
                     displacement=np.stack([f.displacement for f in fields]),
                     von_mises=np.stack([f.von_mises for f in fields]),
                     tooth=np.array([f.tooth for f in fields]), load_N=np.array([f.load_N for f in fields]),
                     load_point=np.stack([f.load_point for f in fields]),
                     load_direction=np.stack([f.load_direction for f in fields]))
            tmp.replace(path)
        except OSError:
            pass

    # ---- factorised bodies and fits (memory only)
    def body(self, key: str, build):
        """The factorised body of ``key``, made by ``build()`` when it is not among the last
        `BODY_SLOTS` used."""
        return self.bodies.kept(key, build)

    def held_body(self, key: str):
        """The factorised body of ``key`` if held, else None (nothing built, nothing evicted)."""
        return self.bodies.get(key)

    def has_fields(self, key: str) -> bool:
        """True when the body fields of ``key`` are on disk (`write_fields`)."""
        return (self.folder / f"fields-{key}.npz").is_file()

    def rim(self, key: str, build):
        """The condensed teeth and rim of ``key``, made by ``build()`` when it is not among the
        last `RIM_SLOTS` used."""
        return self.rims.kept(key, build)

    # ---- arrays of a condensed rim (its condensed stiffness, the products of a load set)
    def read_arrays(self, name: str) -> dict | None:
        """The arrays of ``{name}.npz`` on disk, or None when missing or unreadable."""
        def load(path):
            with np.load(path) as d:
                return {k: d[k] for k in d.files}
        return self.read_file(f"{name}.npz", load)

    def write_arrays(self, name: str, **arrays) -> None:
        """Store ``arrays`` as ``{name}.npz`` (two workers may write the same file at once:
        each writes its own temporary file, the last rename wins)."""
        path = self.folder / f"{name}.npz"
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.npz")   # readers never see a half-written file
            np.savez(tmp, **arrays)
            tmp.replace(path)
        except OSError:
            pass

    def fit(self, key, build):
        """The coupling fit of ``key`` (any hashable), made by ``build()`` when not held."""
        return self.fits.kept(key, build)


FE_CACHE = FECache()
