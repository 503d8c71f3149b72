"""Sweep definitions: a base config plus lists of values for any parameters.

A sweep file is TOML with a ``[base]`` table (any config keys; defaults fill the rest) and one
or more grids. A grid maps parameter names to lists of values; the members of a grid are the
Cartesian product of its lists. Several grids (``[[grid]]`` array of tables) give the union of
their products, which is how Fig. 6 adds a few ``N = 1001`` points to the ``N = 301`` curves::

    [base]
    sem_target = 0.01

    [[grid]]
    N = [301]
    theta = [0.05, 0.5, 1.0]
    eta_c = [1e6, 3e5, 1e5]
    v_d = [1e-3, 3e-4]
    seed = [0, 1, 2, 3]

    [[grid]]
    N = [1001]
    theta = [1.0]
    eta_c = [1e6, 3e5, 1e5]
    v_d = [1e-3, 3e-4]
    seed = [0, 1, 2, 3]

Every grid must sweep the same parameters: they become the dimensions of the sweep Dataset
(in the order of the first grid), with the union of each parameter's values as coordinates.
Combinations that no grid contains are ``absent`` in the Dataset.

A member is identified by a hash of its full, validated config (:func:`member_id`), so the same
physics always has the same id and any change of a value (including a changed default) gives a
new one. The sweep's identity (:attr:`SweepDefinition.digest`) is the hash of its dimension
names and sorted member ids: a store refuses to mix members of two different sweeps.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass
from enum import StrEnum
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ..model.config import OFF, Config, ConfigError, make_config
from .catalogue import preset_files, read_study


class SweepError(ValueError):
    """A rejected sweep definition or store; the message names the key, the value and what is allowed."""


class SweepWarning(UserWarning):
    """Something about a store the user should know that does not stop the job (e.g. an unreadable
    member, left out of a figure); the CLI prints it as one ``warning:`` line."""


@dataclass(frozen=True)
class Member:
    """One run of a sweep: its coordinates along the sweep dimensions and its full config."""

    point: tuple[tuple[str, Any], ...]
    config: Config
    id: str

    @property
    def coords(self) -> dict[str, Any]:
        return dict(self.point)

    def label(self) -> str:
        return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in self.point)


# Options added after 0.1.0 whose absent value (None) switches a feature off: left out of the hash
# while off, so stores written before the option existed stay valid.
OPTIONAL_FEATURES = ("dead_weight", "top_mass", "p_theta1", "t_decide", "t_ramp", "prony_E", "prony_tau", "temperature", "T_ref", "wlf_C1",
                     "wlf_C2")  # absent (None): left out of the hashed text


def _same_value(coord: Any, value: Any) -> bool:
    """A sweep coordinate equals a value given on the command line (numbers to 1e-9, relative)."""
    if isinstance(coord, (int, float)) and not isinstance(coord, bool):
        try:
            return bool(np.isclose(float(coord), float(value), rtol=1e-9, atol=0.0))
        except (TypeError, ValueError):
            return False
    return str(coord) == str(value)


def member_id(config: Config) -> str:
    """Content hash of a full config (16 hex digits): equal configs, equal ids.

    The hash covers what version 0.1 hashed: every config key, plus ``backend = "cpu"`` (0.1's
    configs carried the backend and its ids were computed with it set to "cpu"; it is no longer a
    config key, but keeping it in the hashed text keeps every stored member id valid).
    """
    data = config.model_dump()
    data["backend"] = "cpu"  # frozen: part of the 0.1 id text (see the docstring)
    for key in OPTIONAL_FEATURES:
        if data.get(key) is None:
            data.pop(key, None)
    for key, off in OFF.items():  # the geometry keys (issue 13) at their chain values: as before
        if data.get(key) == off:
            data.pop(key, None)
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@dataclass(frozen=True)
class SweepDefinition:
    """A validated sweep: the base config, the grids, and the members they define."""

    base: Config
    grids: tuple[dict[str, tuple[Any, ...]], ...]
    name: str = "sweep"

    @property
    def dims(self) -> tuple[str, ...]:
        return tuple(self.grids[0])

    @property
    def coords(self) -> dict[str, list[Any]]:
        """The union of each swept parameter's values, sorted."""
        return {d: sorted({v for g in self.grids for v in g[d]}) for d in self.dims}

    @cached_property
    def members(self) -> list[Member]:
        seen: dict[str, Member] = {}
        for g in self.grids:
            for values in itertools.product(*(g[d] for d in self.dims)):
                point = tuple(zip(self.dims, values))
                cfg = self.base.with_updates(**dict(point))
                mid = member_id(cfg)
                seen.setdefault(mid, Member(point, cfg, mid))
        return list(seen.values())

    def selection(self, only: Mapping[str, Any] | None) -> set[str] | None:
        """The ids of the members at the given coordinates (``{dimension: [values, ...]}``; values may
        be the text of a number: any value of a dimension, every dimension given; ``slipchain sweep
        --only``), or None for all. Refuses (SweepError) a key that is not a dimension and a value
        that is not one of its coordinates, naming what is allowed."""
        if not only:
            return None
        want = {}
        for key, values in only.items():
            if key not in self.dims:
                raise SweepError(f"--only {key}=...: {key!r} is not a dimension of sweep {self.name!r}; "
                                 f"expected one of {list(self.dims)}")
            coords = self.coords[key]
            picked = []
            for v in values:
                match = [c for c in coords if _same_value(c, v)]
                if not match:
                    raise SweepError(f"--only {key}={v}: not a value of dimension {key!r}; expected one of "
                                     f"{[f'{c:g}' if isinstance(c, float) else c for c in coords]}")
                picked += match
            want[key] = picked
        return {m.id for m in self.members if all(any(_same_value(m.coords[k], v) for v in vs) for k, vs in want.items())}

    @cached_property
    def digest(self) -> str:
        ids = sorted(m.id for m in self.members)
        text = json.dumps({"dims": list(self.dims), "members": ids})
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def to_dict(self) -> dict[str, Any]:
        """Plain data (full base config, grids as lists): what the store records."""
        base = {k: v for k, v in self.base.model_dump().items() if v is not None}
        return {"name": self.name, "base": base, "grid": [{k: list(v) for k, v in g.items()} for g in self.grids]}

    def to_toml(self) -> str:
        lines = [f'name = "{self.name}"', "", "[base]"]
        lines += [f"{k} = {_toml(v)}" for k, v in self.to_dict()["base"].items()]
        for g in self.grids:
            lines += ["", "[[grid]]"] + [f"{k} = [{', '.join(_toml(x) for x in v)}]" for k, v in g.items()]
        return "\n".join(lines) + "\n"


def _toml(v: Any) -> str:
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return repr(v)
    return str(v)


def make_sweep(data: Mapping[str, Any], source: str = "sweep definition", *, legacy: bool = False) -> SweepDefinition:
    """Validate a sweep definition given as plain data (the parsed TOML).

    ``legacy=True`` (a store's own sweep.toml) accepts keys that older versions wrote into
    ``[base]`` (``backend``) and drops them; they never changed a member's identity.
    """
    unknown = set(data) - {"name", "base", "grid"}
    if unknown:
        raise SweepError(f"{source}: unknown top-level key(s) {sorted(unknown)}; expected 'name', 'base', 'grid'")
    name = data.get("name", "sweep")
    if not isinstance(name, str) or not name:
        raise SweepError(f"{source}: key 'name' has value {name!r}; expected a non-empty string")
    base_data = data.get("base", {})
    if not isinstance(base_data, Mapping):
        raise SweepError(f"{source}: key 'base' has value {base_data!r}; expected a table of config keys")
    try:
        base = make_config(base_data, legacy=legacy)
    except ConfigError as e:
        raise SweepError(f"{source}, [base]: {e}") from None
    raw = data.get("grid")
    if raw is None:
        raise SweepError(f"{source}: no [grid] table; expected at least one table of parameter lists")
    raw_grids = [raw] if isinstance(raw, Mapping) else raw
    if not isinstance(raw_grids, list) or not raw_grids:
        raise SweepError(f"{source}: key 'grid' has value {raw!r}; expected a table or an array of tables")
    grids: list[dict[str, tuple[Any, ...]]] = []
    for i, g in enumerate(raw_grids):
        where = f"{source}, grid {i + 1}"
        if not isinstance(g, Mapping) or not g:
            raise SweepError(f"{where}: {g!r} is not a non-empty table of parameter lists")
        grid: dict[str, tuple[Any, ...]] = {}
        for key, values in g.items():
            if key not in Config.model_fields and key != "backend":
                raise SweepError(f"{where}: unknown parameter '{key}'; known: {', '.join(sorted(Config.model_fields))}")
            if key == "backend":
                raise SweepError(f"{where}: parameter 'backend' cannot be swept (it does not change the physics; "
                                 "give --backend to `slipchain sweep`)")
            vals = list(values) if isinstance(values, list) else [values]
            if not vals:
                raise SweepError(f"{where}: parameter '{key}' has an empty list; expected at least one value")
            if len(set(map(repr, vals))) != len(vals):
                raise SweepError(f"{where}: parameter '{key}' has repeated values {vals!r}")
            grid[key] = tuple(float(v) if _is_float_key(key) and isinstance(v, int) and not isinstance(v, bool) else v
                              for v in vals)
        if grids and set(grid) != set(grids[0]):
            raise SweepError(f"{where} sweeps {sorted(grid)} but grid 1 sweeps {sorted(grids[0])}; "
                             "every grid must sweep the same parameters")
        if grids:
            grid = {k: grid[k] for k in grids[0]}
        grids.append(grid)
    sweep = SweepDefinition(base=base, grids=tuple(grids), name=name)
    # Validate every member now: a bad combination is reported before anything runs.
    for g_index, g in enumerate(grids):
        for values in itertools.product(*g.values()):
            try:
                base.with_updates(**dict(zip(g, values)))
            except ConfigError as e:
                point = ", ".join(f"{k}={v!r}" for k, v in zip(g, values))
                raise SweepError(f"{source}, grid {g_index + 1}, member ({point}): {e}") from None
    return sweep


def _is_float_key(key: str) -> bool:
    return Config.model_fields[key].annotation in (float, float | None)


def load_sweep_definition(path: str | Path, *, legacy: bool = False) -> SweepDefinition:
    """Read and validate a sweep TOML file (``legacy``: see :func:`make_sweep`; ``extends``: see
    :func:`~slipchain.sweeps.catalogue.read_study`)."""
    try:
        data = read_study(path)
    except ConfigError as e:
        raise SweepError(str(e).replace("config file", "sweep file")) from None
    return make_sweep(data, source=f"sweep file {str(path)!r}", legacy=legacy)


class Preset(StrEnum):
    """The shipped Fig. 6 sweeps: ``quick`` (60 runs, minutes), ``paper`` (368 runs, Fig. 6 in full) and
    ``fold`` (the Fig. 6 corners with integrator = 'fold' at three dt: issue 12's convergence table) and
    ``eps1`` (Fig. 6 at the physical contact stiffness, epsilon = 1, with integrator = 'adaptive': issue 12),
    ``eps1-check`` (its corners at the adaptive step's tolerance and at one ten times tighter; rest against steady start),
    ``eps01`` (the corners at epsilon = 0.1, the adaptive step against the fixed step at dt = 2e-9) and ``adaptive``
    (the corners at epsilon = 1e-2, the adaptive step against the fixed step at dt = 1e-8)."""

    QUICK = "quick"
    PAPER = "paper"
    FOLD = "fold"
    EPS1 = "eps1"
    EPS1_CHECK = "eps1-check"
    EPS01 = "eps01"
    ADAPTIVE = "adaptive"


PRESETS = tuple(p.value for p in Preset)


def preset_path(name: str | Preset) -> Path:
    """Path of a shipped Fig. 6 preset (``quick``, ``paper``, ``fold``, ``eps1``, ``eps1-check``, ``eps01``, ``adaptive``)."""
    if name not in PRESETS:
        raise SweepError(f"preset {name!r} is unknown; expected one of {', '.join(PRESETS)}")
    return preset_files()[f"fig6-{Preset(name).value}"]


def load_preset(name: str | Preset) -> SweepDefinition:
    return load_sweep_definition(preset_path(name))


__all__ = ["Member", "PRESETS", "Preset", "SweepDefinition", "SweepError", "load_preset", "load_sweep_definition",
           "make_sweep", "member_id", "preset_path"]
