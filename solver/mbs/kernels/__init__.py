"""The numba kernels of the multibody solver: arrays and scalars in, arrays out.

Every kernel is compiled with this package's ``@njit(cache=True, no_cfunc_wrapper=True)`` (numba's, with
the cache folder below): cached on disk,
and without the C-callable wrapper numba otherwise builds beside the Python one for each
function (nothing here takes a kernel's C address; the wrappers were about a tenth of the LLVM
work of a first, uncached run). The kernels that only other kernels call are compiled without
the CPython wrapper too (``no_cpython_wrapper=True``: the wrappers, which unbox every argument
tuple, were a tenth of a first run's compile): the entry points (the stepping loops, the static
sweep, the contact search and what else Python calls) keep theirs. A wrapper-less kernel called
from Python raises a TypeError naming it (numba would jump to a null address); inside
`python_calls()` it runs its Python source instead, so that a kernel's source can be run as
plain Python (``kernel.py_func``) down to its innermost callees. The stepping loops also release
the GIL (``nogil=True``), so that a progress bar can follow them from another thread. Column
indices of the arrays are in `layout`.

Every kernel also takes numpy's error model (``error_model="numpy"``): a division by zero
gives inf or nan (which the loops' finite-state guard reports) instead of raising
ZeroDivisionError. The same arithmetic otherwise, to the bit; but without the raising branch
numba can drop the reference counts of the arrays a kernel holds (an atomic operation each,
through a call): with it, the contact search and its pre-search counted references to their
arrays at every call, a third of the paper model's time step. For the same reason the
coupled loop's force helpers are inlined into `explicit_coupled.coupled_forces` (``inline=
"always"``: numba keeps the counts of every array live across a call of a compiled function,
and that helper holds the loop's work tuples), and the contact search is called once a step
(`gearmesh.pair_contacts`), not once a candidate pair.

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
``$NUMBA_CACHE_DIR/kernels-<KERNELS_FINGERPRINT>`` (without ``NUMBA_CACHE_DIR``:
``$LIGHTGEAR_CACHE/numba``, by default ``./.lightgear-cache/numba`` beside the FE cache, the
folder the Makefile gives, so that the kernels ``make run`` compiled are the ones a
``lightgear run`` in the same folder loads; `cache_root`): numba checks only the time stamp of a kernel's own file, not those of the
kernels it calls nor the `layout` constants compiled into it, so an edit of `gearmesh` would
otherwise leave a stepping loop cached with the old contact search. Any change to a kernel file
compiles them all afresh; folders of older versions can be deleted (``make clean``).
"""
import contextlib
import hashlib
import os
import threading
from pathlib import Path

_HERE = Path(__file__).resolve().parent


def sources_fingerprint(folder: Path) -> str:
    """A hash of the names and contents of the Python files in ``folder``."""
    return hashlib.sha256(b"".join(p.name.encode() + b"\0" + p.read_bytes()
                                   for p in sorted(Path(folder).glob("*.py")))).hexdigest()[:16]


KERNELS_FINGERPRINT = sources_fingerprint(_HERE)


_PLAIN = threading.local()      # .on: wrapper-less kernels called from Python run their source


@contextlib.contextmanager
def python_calls():
    """Within this block (in this thread) a kernel compiled without its CPython wrapper, when
    called from Python, runs its Python source (``py_func``) instead of raising: a kernel's
    ``py_func`` then runs as plain Python down to its innermost wrapper-less callees (the
    kernels with a wrapper still run compiled), as the tests of the loops' sources do."""
    before = getattr(_PLAIN, "on", False)
    _PLAIN.on = True
    try:
        yield
    finally:
        _PLAIN.on = before


_KERNEL_ONLY = None


def _kernel_only_class():
    """numba's CPU dispatcher whose Python call of a wrapper-less kernel raises a TypeError
    naming it, or (inside `python_calls`) runs its source; compiled callers call the machine
    code directly and never pass through here."""
    global _KERNEL_ONLY
    if _KERNEL_ONLY is None:
        from numba.core.registry import CPUDispatcher

        class KernelOnlyDispatcher(CPUDispatcher):
            def __call__(self, *args, **kwargs):
                if getattr(_PLAIN, "on", False):
                    return self.py_func(*args, **kwargs)
                raise TypeError(f"kernel {self.py_func.__module__}.{self.py_func.__qualname__} is compiled "
                                "without its Python wrapper (only other kernels call it): call it from a "
                                "compiled function, or run its source inside solver.mbs.kernels.python_calls()")
        KernelOnlyDispatcher.__qualname__ = "KernelOnlyDispatcher"     # (see __getattr__ below)
        _KERNEL_ONLY = KernelOnlyDispatcher
    return _KERNEL_ONLY


def __getattr__(name):
    # the dispatcher class by its module and name, as pickle (a dask task's kernels) finds it;
    # made on first use, so that importing the package imports no numba
    if name == "KernelOnlyDispatcher":
        return _kernel_only_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# the root the first kernel was filed under (None before): numba fixes a kernel's folder when it
# is decorated, so a later change of LIGHTGEAR_CACHE in the same process moves the FE cache only
_filed_root: str | None = None


def cache_root() -> str:
    """The folder (absolute) under which the kernels' disk cache folder lies: numba's
    ``NUMBA_CACHE_DIR`` where set, else ``$LIGHTGEAR_CACHE/numba`` (default
    ``./.lightgear-cache/numba``, as the FE cache, `study.inputs.cache`) as it was when this
    process decorated its first kernel."""
    import numba
    return os.path.abspath(numba.config.CACHE_DIR or _filed_root
                           or os.path.join(os.environ.get("LIGHTGEAR_CACHE", ".lightgear-cache"), "numba"))


def njit(**options):
    """``numba.njit(**options)`` whose disk cache (with ``cache=True``) is the fingerprinted
    folder; every kernel module decorates with it. numba fixes a function's cache location when
    it is decorated, so the folder is set for that moment and the user's setting restored.
    With ``no_cpython_wrapper=True`` the dispatcher guards Python calls (`python_calls`).
    numba itself is imported here, not when the package is (`layout` is plain constants).
    The error model is numpy's unless a kernel says otherwise (see the module docstring)."""
    import numba
    options.setdefault("error_model", "numpy")

    def decorate(fn):
        global _filed_root
        user = numba.config.CACHE_DIR
        root = cache_root()
        if not user and _filed_root is None:
            _filed_root = root
        numba.config.CACHE_DIR = os.path.join(root, f"kernels-{KERNELS_FINGERPRINT}")
        try:
            if not options.get("no_cpython_wrapper") or numba.config.DISABLE_JIT:
                return numba.njit(**options)(fn)
            # what numba.njit does, with the guarding dispatcher class
            opts = {k: v for k, v in options.items() if k != "cache"}
            disp = _kernel_only_class()(py_func=fn, locals={}, targetoptions=dict(opts, nopython=True))
            if options.get("cache"):
                disp.enable_caching()
            return disp
        finally:
            numba.config.CACHE_DIR = user
    return decorate
