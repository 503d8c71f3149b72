"""How much memory a run will need, checked before anything is allocated.

A run that does not fit is otherwise ended by the kernel's OOM killer (exit 137, no message)
after minutes of swapping; :func:`check_memory` turns it into a :class:`MemoryEstimateError`
(a ConfigError: the CLI prints it and exits 2, writing nothing) naming ``N`` and the figures.

The estimate (:func:`estimate_bytes`) counts what grows with the run, per realisation:

* ``BYTES_PER_BLOCK`` per block: the state (u, v, X, V of both layers), the batch's copy, the
  kernel's scratch, the final state in the Dataset;
* ``BYTES_PER_CONTACT`` per contact: sites and v*, the solver's warm start, scratch, the
  per-contact results; plus ``N_CACC * 8`` bytes per contact **per chunk** of ``CHUNK_TIME``
  simulated seconds (the per-chunk contact sums from which the steady window's means are taken:
  the term that dominates long runs of large N), up to twice the records
  :data:`~slipchain.engine.observers.CONTACT_SUMS_BYTES` allows (past it they are merged pairwise), one
  such record in all for a dead-weight run, whose averages span the whole run
  (:func:`slipchain.results.schema.contacts_over_whole_run`);
* ``BYTES_PER_SAMPLE`` per output sample of f_d and the mean displacements.

The coefficients were measured with peak RSS (``benchmarks/memory_estimate.py`` prints estimate
beside measurement): about 115 B per block and 160 B per contact at N = 2e6-4e6, and the chunk
term at N = 1e5, t_total = 10 ms; rounded up, the estimate lies 9-20% above the measured growth
for N >= 1e5 (68% above at N = 1001, where it is a few MB). ``BASE_BYTES`` stands for the
interpreter with numpy, numba and xarray loaded (about 0.3 GB).

What the machine has (:func:`available_bytes`): ``MemAvailable`` of /proc/meminfo, lowered to
the cgroup's limit minus its usage where a container sets one; elsewhere the OS's count of
available pages. ``SLIPCHAIN_MEMORY_CHECK=0`` switches the check off (e.g. with large swap).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

from ..model.config import Config, ConfigError
from ..model.geometries import geometry_of
from ..results.schema import contacts_over_whole_run
from . import scheme as S
from .control import CHUNK_TIME, LONG_CHUNK_TIME, chunk_time
from .observers import CONTACT_SUMS_BYTES, record_cap

BYTES_PER_BLOCK = 128
BYTES_PER_CONTACT = 176
BYTES_PER_SAMPLE = 128
BASE_BYTES = 300 * 2**20
GiB = 2**30


class MemoryEstimateError(ConfigError):
    """The run needs more memory than the machine has available (the message gives both)."""


def simulated_length(cfg: Config) -> float:
    """The longest simulated time the run can take, s: ``t_total``, else the cap ``t_max``."""
    return cfg.t_total if cfg.t_total is not None else cfg.t_max


# The slab and half-space add the kernel a**2 k(q) (8 bytes per block on the half grid, 4 per block)
# and the FFT's temporaries of one step: the spectrum (16 bytes per half-grid point) twice and the
# force field (8), rounded up.
BYTES_PER_BLOCK_FFT = 64


def estimate_bytes(cfg: Config, t: float | None = None) -> int:
    """Bytes that one realisation of ``cfg`` holds at its peak, beyond the interpreter (see the module
    docstring), for a run of ``t`` simulated seconds (default :func:`simulated_length`; past
    ``t_max``, a run extended by its slip cycles, in long chunks)."""
    t = simulated_length(cfg) if t is None else t
    extended = cfg.t_total is None and t > cfg.t_max
    chunks = int((cfg.t_max if extended else t) / max(chunk_time(cfg), cfg.output_interval)) + 1
    if extended:
        chunks += int((t - cfg.t_max) / max(LONG_CHUNK_TIME, cfg.output_interval)) + 1
    if contacts_over_whole_run(cfg):  # one running per-contact sum (the recorder's), whatever the length
        chunks = 1
    chunks = min(chunks, 2 * record_cap(cfg.n_contacts))  # the records merged pairwise past their budget (at its peak
    # the merge holds the old records and the new, 1.5 cap)
    samples = int(t / max(cfg.output_interval, cfg.dt)) + 1
    n_c = cfg.n_contacts
    per_block = BYTES_PER_BLOCK + (BYTES_PER_BLOCK_FFT if geometry_of(cfg).spectral else 0)
    per_contact = BYTES_PER_CONTACT
    if cfg.integrator in ("adaptive", "implicit"):  # the previous accelerations of both layers; each level's folds, the saved solver state
        per_block += 16
        per_contact += 16 * (cfg.step_levels + 1) + 24
    return int(cfg.n_blocks * per_block + n_c * (per_contact + S.N_CACC * 8 * chunks) + samples * BYTES_PER_SAMPLE)


def available_bytes() -> int | None:
    """Memory this process can still take, bytes (None where it cannot be told)."""
    found = []
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                found.append(int(line.split()[1]) * 1024)
                break
    except (OSError, ValueError, IndexError):
        pass
    for limit, usage in (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                         ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes")):
        try:
            lim = Path(limit).read_text().strip()
            if lim != "max" and int(lim) < 2**60:
                found.append(int(lim) - int(Path(usage).read_text().strip()))
            break
        except (OSError, ValueError):
            continue
    if not found:
        try:
            found.append(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
        except (ValueError, OSError, AttributeError):
            return None
    return max(0, min(found))


def check_memory(configs: Iterable[Config], available: int | None = None) -> int:
    """Raise MemoryEstimateError if the realisations of ``configs``, run together, would not fit.

    ``available``: bytes free (default: :func:`available_bytes`). Returns the estimate in bytes.
    """
    configs = list(configs)
    need = sum(estimate_bytes(c) for c in configs)
    if os.environ.get("SLIPCHAIN_MEMORY_CHECK", "1") == "0":
        return need
    have = available_bytes() if available is None else available
    if have is None or need + BASE_BYTES <= have:
        return need
    c = max(configs, key=estimate_bytes)
    rows = f" for {len(configs)} realisations run together" if len(configs) > 1 else ""
    length = f"t_total = {c.t_total:g} s" if c.t_total is not None else f"t_max = {c.t_max:g} s (automatic length)"
    raise MemoryEstimateError(
        f"N = {c.N} (theta = {c.theta:g}: {c.n_contacts} contacts; {length}) needs about {need / GiB:,.1f} GiB of "
        f"memory{rows}, more than the {have / GiB:,.1f} GiB this machine has available. Expected: N small enough "
        f"to fit (each block takes about {BYTES_PER_BLOCK} bytes, each contact {BYTES_PER_CONTACT} bytes plus "
        f"{S.N_CACC * 8} bytes per {CHUNK_TIME:g} s simulated, up to {2 * CONTACT_SUMS_BYTES / GiB:g} GiB). Reduce N, theta or the run length, "
        "or set SLIPCHAIN_MEMORY_CHECK=0 to run anyway.")

def extension_refusal(cfg: Config, t_now: float, t_new: float, available: int | None = None) -> str | None:
    """Why a run of ``cfg`` at ``t_now`` may not be extended to ``t_new`` simulated seconds by its slip
    cycles (:meth:`slipchain.engine.control.RowControl.extend`): the memory the extension adds (its
    estimate at ``t_new`` less that at ``t_now``, which the run already holds) is more than the
    machine has available, less the margin :func:`check_memory` keeps (BASE_BYTES). None where it
    fits, cannot be told, or ``SLIPCHAIN_MEMORY_CHECK=0``."""
    if os.environ.get("SLIPCHAIN_MEMORY_CHECK", "1") == "0":
        return None
    have = available_bytes() if available is None else available
    extra = estimate_bytes(cfg, t_new) - estimate_bytes(cfg, t_now)
    if have is None or extra + BASE_BYTES <= have:
        return None
    return (f"not extended to {t_new:g} s: that needs about {extra / GiB:,.1f} GiB more memory, more than the "
            f"{have / GiB:,.1f} GiB available (lower t_max_cycles or output_interval)")


__all__ = ["BASE_BYTES", "BYTES_PER_BLOCK", "BYTES_PER_CONTACT", "BYTES_PER_SAMPLE", "MemoryEstimateError",
           "available_bytes", "check_memory", "estimate_bytes", "extension_refusal", "simulated_length"]
