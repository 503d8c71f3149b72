"""A sweep store that never loses work: one NetCDF file per finished member, plus an index.

Layout of a store directory::

    sweep.toml          the full sweep definition (written once, first); identifies the sweep
    members/<id>.nc     each completed member: the run's Dataset (time series, per-contact data,
                        final state, config TOML, seed, status, package version in its attrs)
    failed/<id>.nc      the latest failed attempt of a member (status diverged or error, with
                        the reason in ``message``); rerun on resume, removed once it completes
    quarantine/<id>.nc  a member file found unreadable (truncated by a full disk, a partial copy,
                        a failing file system) when a sweep started, moved aside with the reason in
                        quarantine/<id>.reason.txt; the member is rerun
    checkpoints/<key>.nc  the state of a long task still running (or killed), to resume from; a
                        task's file is removed once its members are stored
    index.csv           one row per member (point, status, mu_star, ...): a readable summary,
                        rebuilt from the files above, never the source of truth
    invocations.jsonl   one line per sweep invocation (start, wall time, counts): a log
    .driver.lock        the driver lock (an OS file lock through ``filelock``), and
    driver.json         who holds it (host, pid, start): one driver per store at a time

Why per-member files (and not one Zarr array): every member is written exactly once, by one
process, with :func:`slipchain.results.io.write_dataset` (temporary file + ``os.replace``), so a crash
at any moment leaves each member either absent or complete; no two writers ever touch the same
file or chunk; members of different lengths (automatic run length) need no padding; and the
directory listing alone says what is done, so resuming needs no bookkeeping that a kill could
leave inconsistent. ``<id>`` is the hash of the member's full config (:func:`slipchain.sweeps.definition.member_id`).
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import os
import socket
import time
from contextlib import AbstractContextManager, contextmanager
from pathlib import Path
from typing import Any, Iterator

import numpy as np
import xarray as xr
from filelock import FileLock, Timeout

from ..results.io import read_attrs, read_dataset, write_dataset, write_text_atomic
from ..results.schema import SWEEP_VARIABLES, Status
from ..model.config import config_from_toml
from .definition import Member, SweepDefinition, SweepError, load_sweep_definition, member_id

DEFINITION = "sweep.toml"
MEMBERS = "members"
FAILED = "failed"
INDEX = "index.csv"
CHECKPOINTS = "checkpoints"
QUARANTINE = "quarantine"
LOG = "invocations.jsonl"
LOCK = ".driver.lock"
HOLDER = "driver.json"

# Per-member numbers gathered into the sweep Dataset (from the run schema): variable -> (attr, meaning).
SUMMARY_VARS = SWEEP_VARIABLES
ABSENT, MISSING, UNREADABLE = Status.ABSENT.value, Status.MISSING.value, Status.UNREADABLE.value


class Store:
    """A directory holding the members of one sweep (see the module docstring)."""

    def __init__(self, path: str | os.PathLike, sweep: SweepDefinition):
        self.path = Path(path)
        self.sweep = sweep

    # --- opening -------------------------------------------------------------------------
    @classmethod
    def open(cls, path: str | os.PathLike, sweep: SweepDefinition | None = None, *, create: bool = True) -> "Store":
        """Open the store at ``path``; with ``sweep``, create it if needed and check it matches.

        Refuses (SweepError) a directory that holds something else, and a store written by a
        different sweep definition, naming what differs. ``create=False``: the same checks, but a
        new store is not written (a dry run).
        """
        path = Path(path)
        definition = path / DEFINITION
        if definition.exists():
            stored = load_sweep_definition(definition, legacy=True)
            if sweep is not None and sweep.digest != stored.digest:
                raise SweepError(
                    f"store {str(path)!r} was written by a different sweep definition "
                    f"(its sweep {stored.name!r} has digest {stored.digest}, this one {sweep.name!r} has {sweep.digest}; "
                    f"{_difference(stored, sweep)}). Members of two sweeps are never mixed: "
                    "use another --store path, or delete this one to start over."
                )
            return cls(path, stored)
        if sweep is None:
            raise SweepError(f"{str(path)!r} is not a slipchain sweep store (no {DEFINITION} in it)")
        if path.exists() and (not path.is_dir() or any(path.iterdir())):
            raise SweepError(f"{str(path)!r} exists and is not a slipchain sweep store (no {DEFINITION}); "
                             "give a new or empty directory as --store")
        if not create:
            return cls(path, sweep)
        (path / MEMBERS).mkdir(parents=True, exist_ok=True)
        (path / FAILED).mkdir(exist_ok=True)
        write_text_atomic(definition, f"# slipchain sweep store; digest {sweep.digest}\n" + sweep.to_toml())
        return cls(path, sweep)

    # --- one driver at a time -----------------------------------------------------------------
    def driver_lock(self) -> "AbstractContextManager[str | None]":
        """Hold the store's driver lock while a sweep runs (:func:`driver_lock`)."""
        return driver_lock(self.path, "store")

    # --- members -------------------------------------------------------------------------
    def member_path(self, mid: str) -> Path:
        return self.path / MEMBERS / f"{mid}.nc"

    def failed_path(self, mid: str) -> Path:
        return self.path / FAILED / f"{mid}.nc"

    def checkpoint_path(self, group: list[Member]) -> Path:
        """The checkpoint file of the task that runs ``group`` (named by the hash of its member ids)."""
        key = group[0].id if len(group) == 1 else hashlib.sha1(" ".join(m.id for m in group).encode()).hexdigest()[:16]
        return self.path / CHECKPOINTS / f"{key}.nc"

    def prune_checkpoints(self, groups: list[list[Member]]) -> list[Path]:
        """Remove checkpoint files that no task of ``groups`` will use (their members were stored, or
        were batched differently); returns what was removed."""
        keep = {self.checkpoint_path(g) for g in groups}
        gone = [p for p in sorted((self.path / CHECKPOINTS).glob("*.nc")) if p not in keep]
        for p in gone:
            p.unlink(missing_ok=True)
        return gone

    def completed_ids(self) -> set[str]:
        return _ids_in(self.path / MEMBERS)

    def failed_ids(self) -> set[str]:
        return _ids_in(self.path / FAILED) - self.completed_ids()

    def pending(self) -> list[Member]:
        """Members not yet completed (missing or failed), in definition order."""
        done = self.completed_ids()
        return [m for m in self.sweep.members if m.id not in done]

    def write_member(self, member: Member, ds: xr.Dataset) -> Path:
        """Write one finished member atomically: completed ones to members/, others to failed/."""
        ds = ds.copy()
        ds.attrs["member_id"] = member.id
        ds.attrs["sweep_digest"] = self.sweep.digest
        for k, v in member.point:
            ds.attrs[f"sweep_{k}"] = v
        if ds.attrs.get("status") == Status.COMPLETED:
            path = write_dataset(ds, self.member_path(member.id))
            self.failed_path(member.id).unlink(missing_ok=True)
        else:
            path = write_dataset(ds, self.failed_path(member.id))
        return path

    def reuse_from(self, other: str | os.PathLike) -> list[str]:
        """Copy into this store the completed members of the store at ``other`` that this sweep has
        and does not hold yet; returns their ids.

        A member id is the hash of the member's full config (:func:`.definition.member_id`), so the
        same id is the same physics: extending a study (a superset grid in a new store) reruns only
        what is new. Each file is checked before it is taken: it must read, be completed, and carry
        the config whose hash is its id. The copy is written like a finished member (atomically, with
        this sweep's digest and coordinates); ``other`` is only read.
        """
        src = reuse_source(other, self.path)
        done = self.completed_ids()
        have = _ids_in(src / MEMBERS)
        taken = []
        for m in self.sweep.members:
            if m.id in done or m.id not in have:
                continue
            path = src / MEMBERS / f"{m.id}.nc"
            try:
                ds = read_dataset(path)
            except (OSError, ValueError, KeyError, RuntimeError):
                continue  # unreadable there: this sweep computes it
            if (ds.attrs.get("status") != Status.COMPLETED or ds.attrs.get("member_id") != m.id
                    or member_id(config_from_toml(ds.attrs["config"])) != m.id):
                continue
            self.write_member(m, ds)
            taken.append(m.id)
        return taken

    def read_member(self, member: Member | str) -> xr.Dataset:
        mid = member if isinstance(member, str) else member.id
        path = self.member_path(mid)
        if not path.exists():
            path = self.failed_path(mid)
        if not path.exists():
            raise SweepError(f"member {mid} has not been run yet (store {str(self.path)!r})")
        try:
            return read_dataset(path)
        except (OSError, ValueError, KeyError, RuntimeError) as e:
            raise SweepError(f"member {mid} of store {str(self.path)!r} is unreadable ({path}: {type(e).__name__}: {e}); "
                             "run the same `slipchain sweep` again: it quarantines and reruns it") from e

    def find(self, **coords: Any) -> Member:
        """The member at the given sweep coordinates (all dimensions must be given)."""
        missing = set(self.sweep.dims) - set(coords)
        if missing:
            raise SweepError(f"find needs every sweep dimension; missing {sorted(missing)}")
        for m in self.sweep.members:
            if all(np.isclose(coords[k], v) if isinstance(v, float) else coords[k] == v for k, v in m.point):
                return m
        raise SweepError(f"no member of sweep {self.sweep.name!r} at {coords}")

    # --- the sweep as one Dataset ---------------------------------------------------------
    def member_attrs(self, member: Member) -> dict[str, Any] | None:
        """The attributes of the member's file (completed, else failed); None if it has none.

        A file that cannot be read gives ``status = 'unreadable'`` and the reason in ``message``
        (the next ``slipchain sweep`` quarantines and reruns it), never an exception.
        """
        for path in (self.member_path(member.id), self.failed_path(member.id)):
            if path.exists():
                try:
                    return _header(path)
                except UnreadableMember as e:
                    return {"status": UNREADABLE, "message": str(e)}
        return None

    def check_members(self) -> list[tuple[str, str]]:
        """Open the header of every member file (members/ and failed/); move each one that cannot be
        read, or that names another member, to quarantine/ with the reason beside it.

        Returns ``[(member id, reason), ...]`` of what was moved; those members are then pending
        and the sweep reruns them. Cheap: only the HDF5 superblock and the attributes are read
        (a truncated file fails there, its end-of-file address being past the end).
        """
        moved = []
        for folder in (self.path / MEMBERS, self.path / FAILED):
            for path in _member_files(folder):
                try:
                    attrs = _header(path)
                    if attrs.get("member_id", path.stem) != path.stem:
                        raise UnreadableMember(f"{path} holds member {attrs['member_id']!r}, not {path.stem!r}")
                except UnreadableMember as e:
                    self._quarantine(path, str(e))
                    moved.append((path.stem, str(e)))
        return moved

    def _quarantine(self, path: Path, reason: str) -> Path:
        folder = self.path / QUARANTINE
        folder.mkdir(exist_ok=True)
        dest = folder / path.name
        if dest.exists():  # quarantined before: keep both
            dest = folder / f"{path.stem}.{time.strftime('%Y%m%dT%H%M%S')}.{os.getpid()}.nc"
        os.replace(path, dest)
        write_text_atomic(dest.with_suffix(".reason.txt"),
                          f"{time.strftime('%Y-%m-%dT%H:%M:%S%z')} moved here from {path.parent.name}/: {reason}\n")
        return dest

    def dataset(self) -> xr.Dataset:
        """Per-member results on the sweep's labelled grid: one dimension per swept parameter.

        ``status`` is the member's status, ``missing`` if not run yet, ``absent`` where no grid
        of the sweep has that combination.
        """
        sw = self.sweep
        coords = sw.coords
        shape = tuple(len(coords[d]) for d in sw.dims)
        data = {k: np.full(shape, np.nan) for k in SUMMARY_VARS}
        status = np.full(shape, ABSENT, dtype=object)
        message = np.full(shape, "", dtype=object)
        ids = np.full(shape, "", dtype=object)
        version = np.full(shape, "", dtype=object)
        vstatus = np.full(shape, "", dtype=object)
        backend = np.full(shape, "", dtype=object)
        for m in sw.members:
            idx = tuple(coords[d].index(v) for d, v in m.point)
            ids[idx] = m.id
            attrs = self.member_attrs(m)
            if attrs is None:
                status[idx] = MISSING
                continue
            status[idx] = attrs.get("status", Status.ERROR.value)
            message[idx] = attrs.get("message", "")
            version[idx] = attrs.get("slipchain_version", "")
            vstatus[idx] = attrs.get("velocity_status", "")
            backend[idx] = attrs.get("backend", "")
            for k, (attr, _) in SUMMARY_VARS.items():
                if attr in attrs:
                    data[k][idx] = float(attrs[attr])
        dims = sw.dims
        ds = xr.Dataset(
            {k: (dims, v, {"long_name": SUMMARY_VARS[k][1]}) for k, v in data.items()},
            coords={d: coords[d] for d in dims},
        )
        ds["status"] = (dims, status.astype(str))
        ds["message"] = (dims, message.astype(str))
        ds["member_id"] = (dims, ids.astype(str))
        ds["slipchain_version"] = (dims, version.astype(str))
        ds["backend"] = (dims, backend.astype(str))
        if (vstatus != "").any():
            ds["velocity_status"] = (dims, vstatus.astype(str))
        ds.attrs.update(sweep_name=sw.name, sweep_digest=sw.digest, store=str(self.path), definition=sw.to_toml())
        return ds

    def write_index(self) -> Path:
        """Rewrite index.csv (atomically) from the member files."""
        buf = io.StringIO()
        w = csv.writer(buf)
        w.writerow(["member_id", *self.sweep.dims, "status", "mu_star", "mu_star_sem", "t_total", "wall_time_s", "message"])
        for m in self.sweep.members:
            a = self.member_attrs(m) or {"status": MISSING}
            w.writerow([m.id, *(v for _, v in m.point), a.get("status", ""), a.get("mu_star", ""),
                        a.get("mu_star_sem", ""), a.get("t_total", ""), a.get("wall_time_s", ""), a.get("message", "")])
        path = self.path / INDEX
        write_text_atomic(path, buf.getvalue())
        return path

    def log_invocation(self, record: dict[str, Any]) -> None:
        """Append one line to invocations.jsonl (a log for people and reports; losing a line loses nothing)."""
        with (self.path / LOG).open("a") as fh:
            fh.write(json.dumps(record) + "\n")

    def invocations(self) -> list[dict[str, Any]]:
        path = self.path / LOG
        if not path.exists():
            return []
        out = []
        for line in path.read_text().splitlines():
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:  # a line cut by a kill
                continue
        return out


def reuse_source(other: str | os.PathLike, store: str | os.PathLike) -> Path:
    """``other`` as a store to reuse members from (``--reuse``), or SweepError naming what it is instead."""
    src = Path(other)
    if not (src / DEFINITION).exists():
        raise SweepError(f"--reuse {str(src)!r} is not a slipchain sweep store (no {DEFINITION} in it); "
                         "expected the --store directory of an earlier sweep")
    if src.resolve() == Path(store).resolve():
        raise SweepError(f"--reuse {str(src)!r} is the --store itself; expected another store")
    return src


def open_sweep(path: str | os.PathLike) -> xr.Dataset:
    """The sweep Dataset of the store at ``path`` (see :meth:`Store.dataset`)."""
    return Store.open(path).dataset()


class UnreadableMember(Exception):
    """A member file that cannot be opened (the message names the file and the reason)."""


def _header(path: Path) -> dict[str, Any]:
    """A member file's attributes (:func:`slipchain.results.io.read_attrs`); UnreadableMember if it cannot be read."""
    try:
        return read_attrs(path)
    except Exception as e:  # h5py raises OSError, but also ValueError/KeyError/RuntimeError on odd bytes
        raise UnreadableMember(f"{path.name}: {type(e).__name__}: {e}") from e


@contextmanager
def driver_lock(folder: str | os.PathLike, what: str = "store") -> Iterator[str | None]:
    """Hold the driver lock of ``folder`` (a sweep store, or a mu-max output directory holding
    many) while its runs go on; yields a note if it was taken over.

    The lock is an OS file lock (``filelock``): the operating system releases it when its
    process ends, however it ends, so a SIGKILLed driver never blocks the folder. Its record in
    driver.json (host, pid, start) is removed on a clean exit; finding one on acquiring means
    the last driver was killed, and the yielded note says so. While another driver holds the
    lock, SweepError names the folder and the holder (two drivers would compute every member
    twice). Note: file locks on network file systems depend on their lock support.
    """
    folder = Path(folder)
    lock = FileLock(folder / LOCK)
    record = folder / HOLDER
    try:
        lock.acquire(timeout=0)
    except Timeout:
        raise SweepError(f"{what} {str(folder)!r} is being run by another slipchain driver "
                         f"({_holder_text(record)}); two drivers would compute every member twice. Wait for it "
                         "to finish or stop it (Ctrl-C), then run this command again.") from None
    try:
        note = None
        if record.exists():
            note = (f"took over the driver lock of {what} {str(folder)!r}: its last driver "
                    f"({_holder_text(record)}) ended without releasing it (killed); its finished members are kept")
        write_text_atomic(record, json.dumps({"host": socket.gethostname(), "pid": os.getpid(),
                                              "started": time.strftime("%Y-%m-%dT%H:%M:%S%z")}) + "\n")
        try:
            yield note
        finally:
            record.unlink(missing_ok=True)
    finally:
        lock.release()


def read_holder(record: Path) -> tuple[str, int, str] | None:
    """The driver record ``driver.json`` as (host, pid, started); None if absent or not complete yet."""
    try:
        h = json.loads(record.read_text())
        return str(h["host"]), int(h["pid"]), str(h["started"])
    except (OSError, ValueError, KeyError, TypeError):
        return None


def holder_text(holder: tuple[str, int, str]) -> str:
    host, pid, started = holder
    return f"host {host}, pid {pid}, started {started}"


def _holder_text(record: Path) -> str:
    holder = read_holder(record)
    return "holder not recorded yet" if holder is None else holder_text(holder)


def _member_files(folder: Path) -> list[Path]:
    """The member files of a store folder, in name order (not the temporary files of a write in progress)."""
    if not folder.is_dir():
        return []
    return sorted(p for p in folder.glob("*.nc") if not p.name.startswith("."))


def _ids_in(folder: Path) -> set[str]:
    return {p.stem for p in _member_files(folder)}


def _difference(a: SweepDefinition, b: SweepDefinition) -> str:
    """Say in words how two sweep definitions differ."""
    da, db = a.to_dict(), b.to_dict()
    diffs = [f"base {k}: {da['base'].get(k)!r} vs {db['base'].get(k)!r}"
             for k in sorted(set(da["base"]) | set(db["base"])) if da["base"].get(k) != db["base"].get(k)]
    if a.dims != b.dims:
        diffs.append(f"swept parameters {list(a.dims)} vs {list(b.dims)}")
    elif da["grid"] != db["grid"]:
        diffs.append("grid values differ: " + "; ".join(
            f"{k}: {sorted({v for g in da['grid'] for v in g[k]})} vs {sorted({v for g in db['grid'] for v in g[k]})}"
            for k in a.dims if a.coords[k] != b.coords[k]) or "grids differ")
    return ", ".join(diffs[:6]) or "same values, different package defaults"


__all__ = ["ABSENT", "MISSING", "UNREADABLE", "Store", "UnreadableMember", "open_sweep"]
