"""numba set-up shared by the run-out kernels: the cache directory, and the compile options.

Imported first by every kernel module, so the cache directory is configured before any
kernel is defined.
"""

from __future__ import annotations

from ..._jit import configure

configure()  # a user-writable cache directory (crashsim._jit), before any kernel is defined

#: Options of every kernel: cached on disk; ``error_model="numpy"`` (IEEE division, as NumPy:
#: no Python ZeroDivisionError checks); no GIL.
JIT = {"cache": True, "error_model": "numpy", "nogil": True}
#: Hot functions that allocate nothing are compiled without NRT reference counting: numba
#: otherwise increfs/decrefs every array argument (an atomic operation each) on every call,
#: which cost more than the arithmetic of a right-hand side (measured 0.6 -> 0.4 us per RHS
#: evaluation of the articulated truck, 0.41 -> 0.18 us for a car).  They only index arrays
#: owned by their NRT-managed callers.
HOT = dict(JIT, _nrt=False)
#: Small helpers are inlined at numba-IR level: a call passes the model and work tuples as a
#: few hundred scalar arguments, which cost ~20 % of a right-hand side evaluation.
INLINE = dict(HOT, inline="always")
#: Stages of a long kernel cut for reading (the segment loop), inlined into their one caller at
#: numba-IR level: compiled apart, every stage would carry the code of the kernels it calls
#: once more (numba links and optimizes a function's callees into it), which cost compile time.
STAGE = dict(JIT, inline="always")
