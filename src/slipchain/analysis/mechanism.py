"""The mechanism behind the load effect: stick-slip per contact, slip events, velocity spectra.

The paper explains the fall of mu_star with theta by contacts that stick-slip together (docs/model.md,
"Mechanism"). This module measures that.

**Stick-slip per contact.** During steady sliding a contact either follows the drive (its velocity
stays near v_d) or sticks and slips. The criterion: a contact **stick-slips** when it spends at
least ``STICK_FRACTION`` (5 %) of the steady-window steps nearly stuck, ``|u| < 0.1 v_d`` (the
kernel counts these steps for every contact, ``contact_slow_fraction``). The distributions are
bimodal (at v_d = v0, N = 301: 0 or above 0.2 for nearly every contact), so the threshold is not
critical. The coefficient of variation of the velocity, std/mean, is reported beside it. The
stick-slip fraction of a run is (stick-slipping contacts)/N_c with the binomial error
sqrt(p(1-p)/N_c); over seeds it is averaged like mu_star (:func:`slipchain.analysis.statistics.seed_average`).

**Field recordings** (:func:`record_field`): continuing a run from its final state, the interface
velocities u_i(t) are sampled every ``interval`` (instantaneous values), with the instantaneous
driving force f_d(t) = K_d (v_d t - <X>) and an acoustic proxy: the total tangential force that the
contacts exert on the substrate, A(t) = sum_i f(u_i, v*_i) (eq. 1).

**Slip events** (:func:`slip_events`): a block slips while ``u_i > SLIP_THRESHOLD * v_d`` (2 v_d).
Slipping (time, block) cells that touch in time or in space (4-connectivity, periodic in the block
index) form one event. Per event: size (distinct blocks), duration, total slip sum(u dt), the
released force K_T * slip (the force the slip takes out of the interface-to-upper-layer springs if
the upper layer stays put: a proxy), start time, first block, and whether it touches the start or
end of the recording (truncated).

**Spectra** (:func:`spectra`): one-sided power spectral densities by Welch's method
(``scipy.signal.welch``): Hann window, segments of ``WELCH_SEGMENT`` samples (or the whole record if
shorter), 50 % overlap, mean removed per segment. The block-velocity PSD is the mean over blocks.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr
from scipy import ndimage

from ..engine.backends import BackendName, Batch, get_backend
from ..engine.control import RowControl
from ..engine.driver import drive
from ..engine.observers import FieldRecorder
from ..model.config import config_from_toml
from ..model.system import State, System
from ..results.io import read_dataset
from ..results.observables import SLOW_FRACTION
from ..results.schema import Status
from .statistics import base_config, main_average, main_n, main_selection

STICK_FRACTION = 0.05
SLIP_THRESHOLD = 2.0
WELCH_SEGMENT = 4096


# --- stick-slip per contact ------------------------------------------------------------------
def classify_series(u: np.ndarray, v_d: float) -> tuple[bool, float, float]:
    """Classify one velocity series: (stick-slips?, slow fraction, coefficient of variation).

    The same statistics the kernel accumulates per contact, computed from a series (tests, data).
    """
    u = np.asarray(u, float)
    slow = float(np.mean(np.abs(u) < SLOW_FRACTION * v_d))
    mean = float(np.mean(u))
    cv = float(np.std(u) / mean) if mean != 0 else float("inf")
    return slow >= STICK_FRACTION, slow, cv


def contact_classes(run: xr.Dataset) -> xr.Dataset:
    """Per contact of a run Dataset: stick-slip flag, slow fraction, CV, and mean force vs f(v_d, v*)."""
    cfg = config_from_toml(run.attrs["config"])
    slow = run["contact_slow_fraction"].values
    with np.errstate(divide="ignore", invalid="ignore"):
        cv = run["contact_velocity_std"].values / run["contact_velocity_mean"].values
    single = cfg.contact_law.force(np.full(slow.shape, cfg.v_d), run["vstar"].values)
    return xr.Dataset({
        "stick_slip": ("contact", slow >= STICK_FRACTION),
        "slow_fraction": ("contact", slow),
        "velocity_cv": ("contact", cv),
        "vstar": ("contact", run["vstar"].values),
        "force_mean": ("contact", run["contact_force_mean"].values),
        "force_single": ("contact", single, {"long_name": "f(v_d, v*_i): an isolated contact sliding steadily at v_d"}),
    }, attrs={"v_d": cfg.v_d, "theta": run.attrs["theta"], "amplitude": cfg.epsilon * cfg.f0})


def stick_slip_fraction(run: xr.Dataset) -> tuple[float, float]:
    """Fraction of contacts that stick-slip, with its binomial standard error."""
    ss = run["contact_slow_fraction"].values >= STICK_FRACTION
    n = ss.size
    if n == 0:
        return float("nan"), float("nan")
    p = float(ss.mean())
    return p, float(np.sqrt(max(p * (1 - p), 0.25 / n) / n))  # floor: never claim zero error at p = 0 or 1


def stick_slip_dataset(store) -> xr.Dataset:
    """The sweep Dataset of a store with ``mu_star`` replaced by the stick-slip fraction (and its SE).

    Shaped like :meth:`slipchain.sweeps.store.Store.dataset`, so
    :func:`slipchain.analysis.statistics.seed_average` applies unchanged.
    """
    ds = store.dataset()
    frac = np.full(ds["mu_star"].shape, np.nan)
    err = np.full(ds["mu_star"].shape, np.nan)
    coords = store.sweep.coords
    for m in store.sweep.members:
        idx = tuple(coords[d].index(v) for d, v in m.point)
        if ds["status"].values[idx] != Status.COMPLETED:
            continue
        frac[idx], err[idx] = stick_slip_fraction(store.read_member(m))
    out = ds.copy()
    out["mu_star"] = (ds["mu_star"].dims, frac, {"long_name": "fraction of contacts that stick-slip"})
    out["mu_star_sem"] = (ds["mu_star"].dims, err, {"long_name": "binomial standard error"})
    return out


def stick_slip_average(stick_slip: xr.Dataset) -> xr.Dataset:
    """Seed means of the stick-slip fraction (:func:`stick_slip_dataset`) at the main values of the
    dimensions outside Fig. 6 and the main N; attrs: omega0 and the base eta_c (for the symbols)."""
    cfg = base_config(stick_slip)
    avg, _ = main_average(stick_slip)
    if "N" in avg.dims:
        avg = avg.sel(N=main_n(avg))
    return avg.assign_attrs(omega0=cfg.omega0, eta_c=cfg.eta_c)


def velocity_figure_data(ds: xr.Dataset, points: int = 200) -> xr.Dataset:
    """mu_star(v_d) seed means at the main values of other dimensions (the first value of any that
    remain besides v_d and theta), with the single-contact law f(v, v0)/(epsilon f0) on a ``v`` grid
    spanning the swept v_d; attrs: the smallest v* = v0 10**-delta and the values held."""
    cfg = base_config(ds)
    avg, _ = main_average(ds)
    other = [d for d in avg["mu"].dims if d not in ("v_d", "theta")]
    sub = avg.isel({d: 0 for d in other}) if other else avg
    v = np.geomspace(float(avg["v_d"].min()), float(avg["v_d"].max()), points)
    law = cfg.contact_law.force(v, cfg.v0) / (cfg.epsilon * cfg.f0)
    return sub.assign(law=("v", law)).assign_coords(v=v).assign_attrs(
        vstar_min=cfg.v0 * 10 ** -cfg.delta, held=", ".join(f"{d} = {sub[d].item():g}" for d in other))


# --- field recordings --------------------------------------------------------------------------
def state_from_run(run: xr.Dataset) -> State:
    """The final state stored in a run Dataset."""
    return State(run["x"].values.copy(), run["u"].values.copy(), run["X"].values.copy(), run["U"].values.copy(),
                 int(run.attrs["steps"]))


def record_field(system: System, state: State, duration: float, interval: float, *,
                 backend: str | BackendName = BackendName.CPU, positions: bool = False) -> xr.Dataset:
    """Continue from ``state`` for ``duration`` s, sampling u_i(t), f_d(t) and A(t) every ``interval`` s
    (and, with ``positions``, the displacement field x_i - v_d t as ``slip_field``).

    The engine's time loop with a :class:`~slipchain.engine.observers.FieldRecorder` observing
    chunks of one sample each. Raises FloatingPointError if the state goes non-finite.
    """
    cfg = system.config
    steps = max(1, int(round(interval / cfg.dt)))
    n = max(2, int(round(duration / (steps * cfg.dt))))
    batch = Batch.pack([system], [state.copy()])
    field = FieldRecorder(system, n, positions=positions)
    control = RowControl(limit=n)
    drive(get_backend(backend, [cfg]), batch, [control], sample_steps=steps, chunk=1, interval=steps * cfg.dt,
          observers=[field])
    if control.status == Status.DIVERGED:
        raise FloatingPointError(f"non-finite state during the field recording at step {int(batch.status[0])}")
    if control.status == Status.INTERRUPTED:
        raise KeyboardInterrupt
    extra = {} if field.x is None else {
        "slip_field": (("time", "block"), field.x, {"units": "m", "long_name": "x_i - v_d t (instantaneous)"})}
    return xr.Dataset(
        {**extra,
         "u": (("time", "block"), field.u, {"units": "m/s", "long_name": "interface block velocity (instantaneous)"}),
         "f_d_instant": ("time", field.f_d, {"units": "N", "long_name": "driving force per block, instantaneous"}),
         "acoustic": ("time", field.acoustic, {"units": "N", "long_name": "total contact force on the substrate"})},
        coords={"time": ("time", field.t, {"units": "s"}), "block": np.arange(cfg.n_blocks)},
        attrs={"interval": steps * cfg.dt, "v_d": cfg.v_d, "K_T": cfg.K_T, "theta": system.theta_realised,
               "geometry": cfg.geometry, "Lx": cfg.N, "Ly": cfg.Ly, "a": cfg.a, "G": cfg.G},
    )


def _periodic_labels(slipping: np.ndarray, periodic_axes: tuple[int, ...]) -> np.ndarray:
    """Connected clusters of ``slipping`` (face-connected: 4 neighbours in (time, block), 6 in
    (time, x, y)), merged across the periodic faces of ``periodic_axes`` (union-find)."""
    labels, n = ndimage.label(slipping)
    if not n:
        return labels
    parent = np.arange(n + 1)

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for axis in periodic_axes:
        first, last = np.take(labels, 0, axis=axis), np.take(labels, -1, axis=axis)
        both = (first > 0) & (last > 0)
        for a, b in zip(first[both], last[both]):
            ra, rb = find(a), find(b)
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    roots = np.array([find(i) for i in range(n + 1)])
    return roots[labels]


def slip_events(field: xr.Dataset, threshold: float = SLIP_THRESHOLD) -> xr.Dataset:
    """Connected clusters of slipping blocks in space and time (module docstring); on a 2-D interface
    (``Ly`` > 1 in the field's attrs) clusters in (t, x, y), periodic in x and y, with their area
    and seismic moment M0 = G a**2 sum(u dt) (issue 13)."""
    u = field["u"].values.astype(float)
    dt = float(field.attrs["interval"])
    lx, ly = int(field.attrs.get("Lx", u.shape[1])), int(field.attrs.get("Ly", 1))
    two_d = ly > 1
    slipping = u > threshold * float(field.attrs["v_d"])
    if two_d:
        slipping = slipping.reshape(-1, lx, ly)
    labels = _periodic_labels(slipping, (1, 2) if two_d else (1,)).reshape(u.shape)
    ids = np.unique(labels[labels > 0])
    keys = ("size", "duration", "slip", "force", "start", "first_block", "truncated") + (("area", "moment") if two_d
                                                                                        else ())
    rows: dict[str, list[Any]] = {k: [] for k in keys}
    times = field["time"].values
    for i in ids:
        ti, bi = np.nonzero(labels == i)
        rows["size"].append(np.unique(bi).size)
        rows["duration"].append((ti.max() - ti.min() + 1) * dt)
        slip = float(np.sum(u[ti, bi]) * dt)
        rows["slip"].append(slip)
        rows["force"].append(float(field.attrs["K_T"]) * slip)
        rows["start"].append(times[ti.min()])
        rows["first_block"].append(int(bi[np.argmin(ti)]))
        rows["truncated"].append(bool(ti.min() == 0 or ti.max() == u.shape[0] - 1))
        if two_d:
            a = float(field.attrs["a"])
            rows["area"].append(np.unique(bi).size * a * a)
            rows["moment"].append(float(field.attrs["G"]) * a * a * slip)
    units = {"size": ("blocks", "distinct blocks that slipped"), "duration": ("s", "duration"),
             "slip": ("m", "total slip, sum of u dt over the event"),
             "force": ("N", "released force K_T * slip (proxy)"), "start": ("s", "start time"),
             "first_block": ("", "a block slipping at the start"),
             "truncated": ("", "touches the start or end of the recording"),
             "area": ("m^2", "area that slipped, size * a**2"),
             "moment": ("N m", "seismic moment G a**2 sum(u dt)")}
    return xr.Dataset({f"event_{k}": ("event", np.asarray(v), {"units": units[k][0], "long_name": units[k][1]})
                       for k, v in rows.items()},
                      attrs={"slip_threshold_v_d": threshold})


def spectra(field: xr.Dataset, segment: int = WELCH_SEGMENT) -> xr.Dataset:
    """Welch PSDs of the block velocities (mean over blocks), of f_d(t) and of the acoustic proxy."""
    from scipy import signal  # here: its import (~1 s, scipy.stats with it) was paid by every figure command

    fs = 1.0 / float(field.attrs["interval"])
    n = field.sizes["time"]
    nper = min(segment, n)
    kw = dict(fs=fs, window="hann", nperseg=nper, noverlap=nper // 2, detrend="constant")
    f, pu = signal.welch(field["u"].values.astype(float), axis=0, **kw)
    _, pf = signal.welch(field["f_d_instant"].values, **kw)
    _, pa = signal.welch(field["acoustic"].values, **kw)
    return xr.Dataset({"psd_u": ("frequency", pu.mean(axis=1), {"units": "(m/s)^2/Hz"}),
                       "psd_f_d": ("frequency", pf, {"units": "N^2/Hz"}),
                       "psd_acoustic": ("frequency", pa, {"units": "N^2/Hz"})},
                      coords={"frequency": ("frequency", f, {"units": "Hz"})},
                      attrs={"welch": f"Hann window, {nper} samples per segment, 50% overlap, mean removed"})


# --- mechanism runs on a store -----------------------------------------------------------------
MECHANISM = "mechanism"


def mechanism_members(store) -> list:
    """The members analysed in detail: lowest and highest theta at each v_d (smallest eta_c, first
    seed, N = 301 or the first N, other dimensions at their most populated value)."""
    ds = store.dataset()
    sel = main_selection(ds)
    pick: dict[str, Any] = dict(sel)
    if "eta_c" in ds.dims:
        pick["eta_c"] = float(ds["eta_c"].min())
    if "seed" in ds.dims:
        pick["seed"] = int(ds["seed"].min())
    if "N" in ds.dims:
        pick["N"] = main_n(ds)
    out = []
    for vd in ds["v_d"].values.tolist():
        thetas = ds["theta"].values.tolist()
        for th in (min(thetas), max(thetas)):
            point = {**pick, "v_d": vd, "theta": th}
            out.append(store.find(**{d: point[d] for d in store.sweep.dims}))
    return out


def median_frequency(freq: np.ndarray, psd: np.ndarray) -> float:
    """The frequency below which half of the spectrum's power lies."""
    c = np.cumsum(psd)
    if c[-1] <= 0:
        return float("nan")
    return float(freq[int(np.searchsorted(c, 0.5 * c[-1]))])


def load_mechanism(store) -> list[xr.Dataset]:
    """The stored mechanism analyses of :func:`mechanism_members` (error naming the command if missing)."""
    out = []
    for m in mechanism_members(store):
        path = store.path / MECHANISM / f"{m.id}.nc"
        if not path.exists():
            raise FileNotFoundError(f"no mechanism analysis of {m.label()} in {store.path}; "
                                    f"run `slipchain mechanism --store {store.path}` first")
        out.append(read_dataset(path))
    return out


__all__ = ["MECHANISM", "SLIP_THRESHOLD", "STICK_FRACTION", "classify_series", "contact_classes", "load_mechanism",
           "mechanism_members", "median_frequency", "record_field", "slip_events", "spectra", "state_from_run",
           "stick_slip_average", "stick_slip_dataset", "stick_slip_fraction", "velocity_figure_data"]
