"""Backends that advance a batch of realisations: ``base`` (batch layout, protocol), ``cpu`` (numba), ``spectral`` (slab FFT), ``host`` (the CPU backend), ``cuda`` (numba.cuda)."""

from __future__ import annotations

from enum import StrEnum

from .base import Backend, Batch, ChunkOutput, kernel_params
from .host import CPUBackend


class BackendName(StrEnum):
    """Where a run is computed: ``cpu``, ``gpu`` (numba.cuda; an error without a GPU) or ``auto``
    (the GPU when numba.cuda finds one, else the CPU)."""

    CPU = "cpu"
    GPU = "gpu"
    AUTO = "auto"


def get_backend(name: str | BackendName = BackendName.CPU) -> Backend:
    """The backend called ``name`` (see :class:`BackendName`); a backend object is passed through."""
    if not isinstance(name, str):
        return name
    if name not in BackendName.__members__.values():
        raise ValueError(f"backend has value {name!r}; expected one of {', '.join(b.value for b in BackendName)}")
    if name == BackendName.CPU:
        return CPUBackend()
    from .cuda import CUDABackend, cuda_available

    if name == BackendName.GPU or cuda_available():
        return CUDABackend()
    return CPUBackend()


__all__ = ["Backend", "BackendName", "Batch", "CPUBackend", "ChunkOutput", "get_backend", "kernel_params"]
