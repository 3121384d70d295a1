"""Which implementation runs the doublet-lattice and vortex-lattice kernel loops: the numpy one
(always available) or the compiled numba one (:mod:`asekit.aero._dlm_compiled`), chosen by
argument or by ``$ASEKIT_DLM_KERNEL``. One place for :mod:`asekit.aero.dlm` and
:mod:`asekit.aero.vlm` alike."""

from __future__ import annotations

import importlib.util
import os

#: Implementations of the all-planar kernel loop: the numpy one (always available) and the
#: compiled numba one (:mod:`asekit.aero._dlm_compiled`, when numba is installed).
KERNELS = ("numpy", "compiled")
#: Environment variable that chooses the default kernel implementation (``numpy`` or
#: ``compiled``); unset: compiled if numba is installed, else numpy.
KERNEL_ENV = "ASEKIT_DLM_KERNEL"


def compiled_kernel_available() -> bool:
    """True if numba is installed (the compiled kernel can be used)."""
    return importlib.util.find_spec("numba") is not None


def default_kernel() -> str:
    """The kernel implementation used when none is given: ``$ASEKIT_DLM_KERNEL`` if set, else
    "compiled" when numba is installed, else "numpy"."""
    env = os.environ.get(KERNEL_ENV, "").strip()
    if env:
        if env not in KERNELS:
            raise ValueError(f"{KERNEL_ENV} must be one of {list(KERNELS)}, got {env!r}")
        return env
    return "compiled" if compiled_kernel_available() else "numpy"


def check_kernel(kernel) -> str:
    """``kernel`` (None: :func:`default_kernel`) checked: one of :data:`KERNELS`, and
    "compiled" only with numba installed."""
    name = default_kernel() if kernel is None else kernel
    if name not in KERNELS:
        raise ValueError(f"kernel must be one of {list(KERNELS)} or None, got {kernel!r}")
    if name == "compiled" and not compiled_kernel_available():
        raise ValueError("kernel='compiled' needs numba (pip install numba); use "
                         "kernel='numpy'")
    return name
