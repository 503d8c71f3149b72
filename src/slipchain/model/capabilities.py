"""Where each combination of the engine's pieces runs: one table, read by Config, the backends,
``--backend auto`` and the docs (issue 26).

A run is one choice of each piece: geometry ('chain', 'chain2d', 'slab', 'halfspace'), integrator
('fixed', 'fold', 'adaptive'), drive ('spring', 'dead_weight') and backend ('cpu', 'gpu'). On the
CPU every combination runs but one that has no physical meaning (a dead weight on a half-space,
which has no top to carry it). On a GPU the numba.cuda kernel runs the chain with the fixed step
(either drive), and CuPy's array code the slab and half-space with the fixed step and the spring
drive; the rest is refused with the reason, and ``auto`` runs it on the CPU, saying so.

:func:`refusal` is the table; :func:`table` lists it for the docs (docs/architecture.md) and the
combination-matrix test (tests/physics/test_matrix.py). It lives with the config (model), which every layer may read.
"""

from __future__ import annotations

import itertools

from .geometries import GEOMETRIES as _GEOMETRIES

GEOMETRIES = tuple(_GEOMETRIES)
INTEGRATORS = ("fixed", "fold", "adaptive", "implicit")
MATERIALS = ("elastic", "prony")
DRIVES = ("spring", "dead_weight")
BACKENDS = ("cpu", "gpu")


def drive_of(cfg) -> str:
    """'dead_weight' or 'spring' for a config."""
    return "dead_weight" if cfg.dead_weight is not None else "spring"


def refusal(geometry: str, integrator: str, drive: str, backend: str = "cpu", material: str = "elastic") -> str | None:
    """None where the combination runs, else why not (a sentence for an error message)."""
    if drive == "dead_weight" and not _GEOMETRIES[geometry].top:
        return "a half-space has no top to carry the weight (use geometry = 'slab')"
    if material == "prony":
        if backend != "cpu":
            return "material = 'prony' runs on the CPU only in this version"
    if backend == "cpu":
        return None
    if integrator != "fixed":
        return f"integrator = '{integrator}' runs on the CPU only in this version (the GPU paths have the fixed step)"
    if geometry == "chain2d":
        return "geometry = 'chain2d' runs on the CPU only in this version (the GPU kernel is the chain's)"
    if _GEOMETRIES[geometry].spectral and drive == "dead_weight":
        return ("the dead weight on the slab runs on the CPU only in this version (the GPU's array code has no "
                "plate)")
    return None


def config_refusal(cfg, backend: str = "cpu") -> str | None:
    """:func:`refusal` for a config."""
    return refusal(cfg.geometry, cfg.integrator, drive_of(cfg), backend, cfg.material)


def table() -> list[tuple[str, str, str, str, str, str | None]]:
    """Every cell: (geometry, integrator, drive, backend, material, refusal or None)."""
    return [(g, i, d, b, m, refusal(g, i, d, b, m))
            for m, g, i, d, b in itertools.product(MATERIALS, GEOMETRIES, INTEGRATORS, DRIVES, BACKENDS)]


def markdown_table() -> str:
    """The table as Markdown: one row per material, geometry and drive, one column per integrator and backend."""
    cols = [(i, b) for b in BACKENDS for i in INTEGRATORS]
    lines = ["| material | geometry | drive | " + " | ".join(f"{i} ({b})" for i, b in cols) + " |",
             "|---|---|---|" + "---|" * len(cols)]
    for m, g, d in itertools.product(MATERIALS, GEOMETRIES, DRIVES):
        cells = ["runs" if refusal(g, i, d, b, m) is None else "no" for i, b in cols]
        lines.append(f"| {m} | {g} | {d} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


__all__ = ["BACKENDS", "DRIVES", "GEOMETRIES", "INTEGRATORS", "MATERIALS", "config_refusal", "drive_of", "markdown_table",
           "refusal", "table"]
