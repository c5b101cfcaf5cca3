"""The numba kernels of the multibody solver: arrays and scalars in, arrays out.

Every kernel is compiled with ``@njit(cache=True, no_cfunc_wrapper=True)``: cached on disk
(``$NUMBA_CACHE_DIR``), and without the C-callable wrapper numba otherwise builds beside the
Python one for each function (nothing here takes a kernel's C address; the wrappers were
about a tenth of the LLVM work of a first, uncached run). The Python wrapper stays, so every
kernel can be called and tested from Python. The stepping loops also release the GIL
(``nogil=True``), so that a progress bar can follow them from another thread. Column indices of the arrays are in `layout`.

numba's disk cache checks each file's own time stamp only, not those of the kernels it calls
nor the `layout` constants compiled in: a change to `gearmesh`, `contact`, `laws` or `layout`
must also change the files of the kernels that call them (`explicit`, `explicit_coupled`,
`implicit`, `statics`), or the cache (``$NUMBA_CACHE_DIR``) be cleared, else a stale stepping
loop runs the old contact search.
"""
