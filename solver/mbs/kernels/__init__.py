"""The numba kernels of the multibody solver: arrays and scalars in, arrays out.

Every kernel is compiled with this package's ``@njit(cache=True, no_cfunc_wrapper=True)`` (numba's, with
the cache folder below): cached on disk,
and without the C-callable wrapper numba otherwise builds beside the Python one for each
function (nothing here takes a kernel's C address; the wrappers were about a tenth of the LLVM
work of a first, uncached run). The Python wrapper stays, so every kernel can be called and
tested from Python. The stepping loops also release the GIL (``nogil=True``), so that a
progress bar can follow them from another thread. Column indices of the arrays are in `layout`.

The stepping loops (`explicit`, `explicit_coupled`, `implicit`) and the static sweep (`statics`)
all find the contacts with `gearmesh.mesh_contacts`, which reads the flanks' profile deviations
(gear_par DEV_*, `solver.modification`), the local compliances in series with the contact
(CLOC_*) and the pitch errors and eccentricities (pair_par E_*, `solver.pitch_errors`) from the model
arrays. Which of those parts a model has (and its friction) the caller says with
`layout.ContactParts`, each part's array or None (`gearmesh.contact_parts`): numba compiles a
variant of the search, and of every kernel around it, per set of parts, with the code of the
absent ones pruned (a plain pair's search has none of it). `layout` also holds a glossary of
the kernels' short names and the named work tuples they carry.

The disk cache sits in a folder named after a hash of every kernel source,
``$NUMBA_CACHE_DIR/kernels-<KERNELS_FINGERPRINT>`` (without ``NUMBA_CACHE_DIR``: this package's
``__pycache__``): numba checks only the time stamp of a kernel's own file, not those of the
kernels it calls nor the `layout` constants compiled into it, so an edit of `gearmesh` would
otherwise leave a stepping loop cached with the old contact search. Any change to a kernel file
compiles them all afresh; folders of older versions can be deleted (``make clean``).
"""
import hashlib
import os
from pathlib import Path

_HERE = Path(__file__).resolve().parent


def sources_fingerprint(folder: Path) -> str:
    """A hash of the names and contents of the Python files in ``folder``."""
    return hashlib.sha256(b"".join(p.name.encode() + b"\0" + p.read_bytes()
                                   for p in sorted(Path(folder).glob("*.py")))).hexdigest()[:16]


KERNELS_FINGERPRINT = sources_fingerprint(_HERE)


def njit(**options):
    """``numba.njit(**options)`` whose disk cache (with ``cache=True``) is the fingerprinted
    folder; every kernel module decorates with it. numba fixes a function's cache location when
    it is decorated, so the folder is set for that moment and the user's setting restored.
    numba itself is imported here, not when the package is (`layout` is plain constants)."""
    import numba

    def decorate(fn):
        user = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = os.path.join(user or str(_HERE / "__pycache__"), f"kernels-{KERNELS_FINGERPRINT}")
        try:
            return numba.njit(**options)(fn)
        finally:
            numba.config.CACHE_DIR = user
    return decorate
