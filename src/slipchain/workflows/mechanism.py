"""The mechanism on a store: field recordings, slip events and spectra of the chosen members, and the mechanism report.

:func:`analyse_store` records the lowest and highest theta at each v_d
(:func:`slipchain.analysis.mechanism.mechanism_members`) into ``STORE/mechanism/<id>.nc``, keeping
analyses already there unless ``force``; :func:`mechanism_figures` draws the figures and writes
``mechanism.md`` with the numbers.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from ..analysis.mechanism import (MECHANISM, contact_classes, load_mechanism, mechanism_members, record_field,
                                  slip_events, spectra, state_from_run, stick_slip_average, stick_slip_dataset,
                                  stick_slip_fraction)
from ..analysis.reports import mechanism_summary
from ..engine.backends import BackendName
from ..model.system import build_system
from ..plots.mechanism import plot_mechanism
from ..results.io import write_dataset, write_text_atomic
from ..results.schema import Status
from ..sweeps.definition import Member
from ..sweeps.store import Store


def analyse_member(store: Store, member: Member, duration: float = 1e-2, interval: float = 1e-6, *,
                   backend: str | BackendName = BackendName.CPU) -> Path:
    """Field recording, slip events and spectra for one completed member; written to STORE/mechanism/<id>.nc."""
    run = store.read_member(member)
    if run.attrs.get("status") != Status.COMPLETED:
        raise ValueError(f"member {member.label()} has status {run.attrs.get('status')!r}; only completed runs are analysed")
    system = build_system(member.config)
    field = record_field(system, state_from_run(run), duration, interval, backend=backend)
    out = xr.merge([field, slip_events(field), spectra(field), contact_classes(run)], combine_attrs="drop_conflicts")
    frac, err = stick_slip_fraction(run)
    out.attrs.update(member_id=member.id, theta=run.attrs["theta"], v_d=member.config.v_d, eta_c=member.config.eta_c,
                     mu_star=run.attrs["mu_star"], stick_slip_fraction=frac, stick_slip_fraction_se=err,
                     interval=float(field.attrs["interval"]), duration=duration, label=member.label())
    return write_dataset(out, store.path / MECHANISM / f"{member.id}.nc")


@dataclass
class Analysed:
    member: Member
    path: Path
    kept: bool  # already in the store, not redone


def analyse_store(store: str | os.PathLike, *, duration: float = 1e-2, interval: float = 1e-6, force: bool = False,
                  backend: str | BackendName = BackendName.CPU, on_member=None) -> list[Analysed]:
    """Analyse the mechanism members of the store at ``store`` (see the module docstring).

    ``on_member(Analysed)`` is called as each member is done (the CLI prints it). Raises
    SweepError for a path that is not a store, ValueError/FloatingPointError naming the member.
    """
    st = Store.open(store)
    done = []
    for m in mechanism_members(st):
        path = st.path / MECHANISM / f"{m.id}.nc"
        kept = path.exists() and not force
        if not kept:
            try:
                analyse_member(st, m, duration=duration, interval=interval, backend=backend)
            except (ValueError, FloatingPointError) as e:
                raise type(e)(f"{m.label()}: {e}") from None
        done.append(Analysed(m, path, kept))
        if on_member is not None:
            on_member(done[-1])
    return done


def mechanism_figures(store: str | os.PathLike, out: str | os.PathLike) -> list[Path]:
    """The mechanism figures and mechanism.md from a store analysed by :func:`analyse_store`."""
    st = Store.open(store)
    analyses = load_mechanism(st)
    ss = stick_slip_dataset(st)
    paths = plot_mechanism(stick_slip_average(ss), analyses, out)
    report = write_text_atomic(Path(out) / "mechanism.md", mechanism_summary(ss, analyses) + "\n" + "\n".join(
        f"![{p.name}]({p.name})" for p in paths if p.suffix == ".png") + "\n")
    return [*paths, report]


__all__ = ["Analysed", "analyse_member", "analyse_store", "mechanism_figures"]
