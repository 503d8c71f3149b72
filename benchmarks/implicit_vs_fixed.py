"""Issue 27: the implicit and adaptive steps against the fixed step where it can run at epsilon = 1
(dt = 2e-10, below the unique-root limit): N = 31, theta = 1, steady start, 10 ms in 0.1-ms samples
(the start event and the reload after it; a whole 1.2-s cycle is out of the fixed step's reach).
Prints per integrator the wall time, the sample of the event, the drive force at 2, 5 and 9 ms
(after the event: the slider's slip in it) and the reload rate; and the differences from the fixed step.

    .venv/bin/python benchmarks/implicit_vs_fixed.py      (about a minute; docs/numerics.md)
"""

import time, numpy as np
from slipchain import make_config, run
base = dict(N=31, theta=1.0, eta_c=1e5, v_d=1e-3, epsilon=1.0, seed=3, start="steady", output_interval=1e-4, t_total=0.01)
res = {}
for integ, dt in (("fixed", 2e-10), ("adaptive", 1e-7), ("implicit", 1e-7)):
    cfg = make_config(**base, integrator=integ, dt=dt)
    t0 = time.perf_counter(); ds = run(cfg); w = time.perf_counter() - t0
    f, t, X = ds.f_d.values, ds.time.values, ds.X_mean.values
    k = int(np.argmax(f < 0.5 * f.max()))  # the first sample after the event's fall
    low = f[k:k + 20].min()
    at = [float(f[np.argmin(np.abs(t - s))]) for s in (2e-3, 5e-3, 9e-3)]
    slip = at[1]
    creep = slice(k + 10, None)
    rate = np.polyfit(t[creep], f[creep], 1)[0]
    res[integ] = (low, slip, rate)
    print(f"{integ:8s} dt {dt:g}: wall {w:.1f} s, event in the sample ending {t[k]*1e3:.1f} ms, f_d after it {low:.7f} N, "
          f"f_d at 2, 5, 9 ms {np.round(at, 7).tolist()}, reload rate {rate:.7f} N/s, energy {ds.attrs['check_energy_balance']:.1e}", flush=True)
for integ in ("adaptive", "implicit"):
    lo, sl, ra = res[integ]; lo0, sl0, ra0 = res["fixed"]
    print(f"{integ} vs fixed: lowest f_d after the event {lo / lo0 - 1:+.2e}, f_d at 5 ms {sl / sl0 - 1:+.2e}, reload rate {ra / ra0 - 1:+.2e}")
