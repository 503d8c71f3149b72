"""Synthetic friction-tester data: the dead-weight set-up simulated, for examples and tests only.

The slider (mass M on the nominal area A0, pressure ``p0 = M*g/A0``) is pulled by a string over a
pulley by a hanging mass M'. Both move together::

    (M + M') dv/dt = M'*g - mu(v, p0)*M*g,     dx/dt = v,     x(0) = v(0) = 0,

integrated with scipy's LSODA (stiff at low velocity, where mu(v) is steep). The planted law is::

    mu(v, p0) = mu0 * exp(-c*xi**2) * [1 - s*(p0/p_ref - 1)*L(xi)],   xi = log10(v/v_peak),
    L(xi) = 1/(1 + exp(-(xi - xi_step)/w)),

a rising branch with its maximum near ``v_peak`` and a load effect of strength ``s`` that is
switched on by the logistic step L about ``xi_step`` decades from the maximum: near the maximum
mu falls by the fraction ``s`` per ``p_ref`` of pressure above ``p_ref``; two decades and more
below it, by less than 4 % of that. ``s = 0`` plants no load effect. Each run's surface differs a
little: its law is multiplied by ``1 + run_scatter*N(0, 1)`` (the run-to-run scatter of real
testers), and its truth is computed with that factor.

The hanging masses are chosen so that the steady velocities span ``v_min`` to 0.1 v_max and,
more densely, 0.2 to 0.8 v_max (solving mu(v, p0) = M'/M on the rising branch), plus runs above the maximum
(``runaway_factors`` times mu_max), which accelerate until the slider reaches the end of the track.
Each trace has ``points`` samples with Gaussian sensor noise ``noise_m``; the record lasts until
the slider has moved ``record_distance_m`` (at least ``min_duration_s``, at most ``max_duration_s``)
or reaches ``track_m``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar
from scipy.special import expit

G = 9.81


@dataclass(frozen=True)
class SynthLaw:
    """The planted mu(v, p0) (see module docstring)."""

    mu0: float = 1.2
    c: float = 0.1
    v_peak: float = 3e-3
    s: float = 0.15
    xi_step: float = -1.0
    w: float = 0.3
    p_ref: float = 25e3
    factor: float = 1.0  # run-to-run scale of the law (see run_scatter)

    def mu(self, v: np.ndarray | float, p0: float) -> np.ndarray:
        v = np.maximum(np.asarray(v, float), 1e-300)
        xi = np.log10(v / self.v_peak)
        step = expit((xi - self.xi_step) / self.w)
        return self.factor * self.mu0 * np.exp(-self.c * xi**2) * (1.0 - self.s * (p0 / self.p_ref - 1.0) * step)

    def maximum(self, p0: float) -> tuple[float, float]:
        """(v_max, mu_max) of the first maximum of mu(v) at pressure p0, coming from low velocity."""
        lv = np.linspace(np.log10(self.v_peak) - 8, np.log10(self.v_peak) + 3, 11001)
        mu = self.mu(10.0**lv, p0)
        falling = np.nonzero(np.diff(mu) < 0)[0]
        i = int(falling[0]) if falling.size else lv.size - 2
        res = minimize_scalar(lambda x: -float(self.mu(10.0**x, p0)), bounds=(lv[max(i - 1, 0)], lv[i + 1]),
                              method="bounded", options={"xatol": 1e-12})
        return 10.0**res.x, -res.fun

    def steady_velocity(self, mu_target: float, p0: float) -> float:
        """The velocity on the rising branch where mu(v, p0) = mu_target (< mu_max): the first crossing."""
        v_max, mu_max = self.maximum(p0)
        if not mu_target < mu_max:
            raise ValueError(f"mu = {mu_target} is above the maximum {mu_max} at p0 = {p0}")
        return 10.0 ** brentq(lambda lv: float(self.mu(10.0**lv, p0)) - mu_target, np.log10(v_max) - 20,
                              np.log10(v_max), xtol=1e-13)


@dataclass(frozen=True)
class SynthSetup:
    # the planted mu(v, p0): SynthLaw, or any object with its mu, maximum, steady_velocity and factor
    # (slipchain.analysis.fit.ModelLaw plants the fitted model)
    law: SynthLaw = field(default_factory=SynthLaw)
    surface: str = "synthetic-asphalt"
    compound: str = "synthetic-tread"
    temperature_C: float = 20.0
    area_m2: float = 4e-3
    slider_masses_kg: tuple[float, ...] = (5.0, 10.0, 20.0)
    v_min: float = 1e-6
    low_velocities: int = 6  # steady runs from v_min to 0.1 v_max (log-spaced)...
    near_velocities: int = 5  # ...and from 0.2 v_max to 0.8 v_max, where the load effect is
    runaway_factors: tuple[float, ...] = (1.1, 1.3)
    run_scatter: float = 0.02
    mass_uncertainty_kg: float = 1e-3
    noise_m: float = 1e-6
    points: int = 400
    record_distance_m: float = 5e-3
    min_duration_s: float = 5.0
    max_duration_s: float = 2e4
    track_m: float = 0.3
    seed: int = 0


def simulate_run(law: SynthLaw, M: float, Mh: float, p0: float, duration: float, track: float) -> tuple[float, callable]:
    """Integrate the dead-weight dynamics; returns the end time and the dense solution x(t)."""
    def rhs(t, y):
        return [y[1], (Mh * G - float(law.mu(y[1], p0)) * M * G) / (M + Mh)]

    def end_of_track(t, y):
        return y[0] - track

    end_of_track.terminal = True
    sol = solve_ivp(rhs, (0.0, duration), [0.0, 0.0], method="LSODA", dense_output=True, events=end_of_track,
                    rtol=1e-9, atol=[1e-12, 1e-14])
    return float(sol.t[-1]), (lambda t: sol.sol(t)[0])


def synthesize(setup: SynthSetup = SynthSetup()) -> tuple[pd.DataFrame, pd.DataFrame, pd.DataFrame]:
    """Runs table, traces and the truth (planted velocity and mu per run)."""
    rng = np.random.default_rng(setup.seed)
    law = setup.law
    runs, traces, truth = [], [], []
    k = 0
    for M in setup.slider_masses_kg:
        p0 = M * G / setup.area_m2
        v_max, mu_max = law.maximum(p0)
        targets = np.concatenate([np.geomspace(setup.v_min, 0.1 * v_max, setup.low_velocities),
                                  np.geomspace(0.2 * v_max, 0.8 * v_max, setup.near_velocities)])
        mus = [float(law.mu(v, p0)) for v in targets] + [f * mu_max for f in setup.runaway_factors]
        for mu_target in mus:
            k += 1
            rid = f"R{k:03d}"
            Mh = round(mu_target * M, 3)  # hanging masses come in grams
            mu_true = Mh / M
            run_law = replace(law, factor=1.0 + setup.run_scatter * rng.normal())
            run_max = run_law.maximum(p0)[1]
            runaway = mu_true >= run_max
            v_true = float("nan") if runaway else run_law.steady_velocity(mu_true, p0)
            duration = setup.max_duration_s if runaway else float(
                np.clip(setup.record_distance_m / v_true, setup.min_duration_s, setup.max_duration_s))
            if runaway:  # as long as a run just below the maximum would last
                duration = float(np.clip(setup.record_distance_m / (0.7 * v_max), setup.min_duration_s,
                                         setup.max_duration_s))
            t_end, x_of_t = simulate_run(run_law, M, Mh, p0, duration, setup.track_m)
            t = np.linspace(0.0, t_end, setup.points)
            x = x_of_t(t) + rng.normal(0.0, setup.noise_m, t.size)
            runs.append({"run_id": rid, "surface": setup.surface, "compound": setup.compound,
                         "temperature_C": setup.temperature_C, "slider_mass_kg": M, "hanging_mass_kg": Mh,
                         "nominal_area_m2": setup.area_m2, "mass_uncertainty_kg": setup.mass_uncertainty_kg})
            traces.append(pd.DataFrame({"run_id": rid, "time_s": t, "distance_m": x}))
            truth.append({"run_id": rid, "pressure_Pa": p0, "mu": mu_true, "velocity_m_s": v_true,
                          "runaway": runaway, "v_max": v_max, "mu_max": mu_max, "run_factor": run_law.factor})
    return pd.DataFrame(runs), pd.concat(traces, ignore_index=True), pd.DataFrame(truth)


NOTICE = ("SYNTHETIC DATA generated by `slipchain tester synth` for examples and tests: a simulated "
          "dead-weight friction tester with a planted mu(v, p0) law, not measurements.")


def write_synthetic(out: str | os.PathLike, setup: SynthSetup = SynthSetup()) -> dict[str, Path]:
    """Write runs.csv, traces.csv, truth.csv and README.txt (which says the data are synthetic)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    runs, traces, truth = synthesize(setup)
    paths = {"runs": out / "runs.csv", "traces": out / "traces.csv", "truth": out / "truth.csv",
             "readme": out / "README.txt"}
    runs.to_csv(paths["runs"], index=False)
    traces.to_csv(paths["traces"], index=False, float_format="%.9g")
    truth.to_csv(paths["truth"], index=False)
    params = "\n".join(f"  {f.name} = {getattr(setup, f.name)}" for f in fields(setup) if f.name != "law")
    law = "\n".join(f"  {f.name} = {getattr(setup.law, f.name)}" for f in fields(setup.law) if f.name != "r")
    if hasattr(setup.law, "r"):  # analysis.fit.ModelLaw: its lowering of the maximum
        law += (f"\n  r(theta): the model's lowering of the maximum from {setup.law.r.source or 'a table'} "
                f"(theta {[round(float(t), 4) for t in setup.law.r.theta]}, r {[round(float(r), 4) for r in setup.law.r.r]})")
    paths["readme"].write_text(f"{NOTICE}\n\nLaw ({type(setup.law).__module__}.{type(setup.law).__name__}):\n{law}\n\nSet-up:\n{params}\n\n"
                               "truth.csv holds the planted velocity and mu of every run.\n")
    return paths


__all__ = ["NOTICE", "SynthLaw", "SynthSetup", "simulate_run", "synthesize", "write_synthetic"]
