"""The CPU backend object: ``advance`` on one core, the chains by the numba kernel of :mod:`.cpu`,
the slab and half-space by the FFT loop of :mod:`.spectral` (issue 13)."""

from __future__ import annotations

import numpy as np

from ..scheme import N_ACC, N_CACC, N_OUT
from . import adaptive, cpu, spectral
from .base import Batch, ChunkOutput


class CPUBackend:
    """The numba kernel on one CPU core: ``advance(batch, n_samples, sample_steps)``."""

    name = "cpu"

    def advance(self, batch: Batch, n_samples: int, sample_steps: int) -> ChunkOutput:
        if batch.kernel is not None:  # slab, half-space: the elastic force by FFT
            return spectral.advance(batch, n_samples, sample_steps)
        b = batch.x.shape[0]
        out = np.zeros((b, n_samples, N_OUT))
        acc = np.zeros((b, N_ACC))
        cacc = np.zeros((b, N_CACC, batch.sites.shape[1]))
        if batch.folds is not None:  # integrator = 'adaptive'
            adaptive.advance(batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar,
                             batch.n_contacts, batch.ysolve, batch.folds, batch.step_control, n_samples, sample_steps,
                             out, acc, cacc, batch.status)
            return ChunkOutput(out, acc, cacc)
        cpu.advance(batch.x, batch.u, batch.X, batch.U, batch.step, batch.params, batch.sites, batch.vstar,
                    batch.n_contacts, batch.ysolve, n_samples, sample_steps, out, acc, cacc, batch.status)
        return ChunkOutput(out, acc, cacc)


__all__ = ["CPUBackend"]
