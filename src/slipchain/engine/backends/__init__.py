"""Backends that advance a batch of realisations: ``base`` (batch layout, protocol), ``compose`` (the CPU loops composed from pieces), ``cpu``, ``adaptive``, ``spectral`` (the pieces), ``host`` (the CPU backend), ``cuda`` (numba.cuda)."""

from __future__ import annotations

import warnings
from enum import StrEnum

from .base import Backend, Batch, ChunkOutput, kernel_params
from .host import CPUBackend


class BackendName(StrEnum):
    """Where a run is computed: ``cpu``, ``gpu`` (numba.cuda; an error without a GPU, or for a
    combination the GPU does not run) or ``auto`` (the GPU when numba.cuda finds one and every
    config of the batch runs there, :mod:`slipchain.model.capabilities`; else the CPU)."""

    CPU = "cpu"
    GPU = "gpu"
    AUTO = "auto"


class BackendFallback(UserWarning):
    """``backend = 'auto'`` on a GPU host chose the CPU for a config the GPU does not run."""


def get_backend(name: str | BackendName = BackendName.CPU, configs=()) -> Backend:
    """The backend called ``name`` (see :class:`BackendName`) for a batch of ``configs``; a backend
    object is passed through. 'gpu' refuses a config the GPU does not run, with the reason of
    :func:`slipchain.model.capabilities.refusal`; 'auto' then falls back to the CPU, saying so
    (a :class:`BackendFallback` warning)."""
    from ...model.capabilities import config_refusal

    if not isinstance(name, str):
        return name
    if name not in BackendName.__members__.values():
        raise ValueError(f"backend has value {name!r}; expected one of {', '.join(b.value for b in BackendName)}")
    if name == BackendName.CPU:
        return CPUBackend()
    why = next((w for w in (config_refusal(c, "gpu") for c in configs) if w is not None), None)
    if name == BackendName.GPU:
        if why is not None:
            raise RuntimeError(f"backend 'gpu' cannot run this config: {why}; use backend 'cpu' or 'auto'")
        from .cuda import CUDABackend

        return CUDABackend()
    from .cuda import CUDABackend, cuda_available

    if not cuda_available():
        return CPUBackend()
    if why is not None:
        warnings.warn(f"backend 'auto' runs this batch on the CPU: {why}", BackendFallback, stacklevel=2)
        return CPUBackend()
    return CUDABackend()


__all__ = ["Backend", "BackendFallback", "BackendName", "Batch", "CPUBackend", "ChunkOutput", "get_backend", "kernel_params"]
