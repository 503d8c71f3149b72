"""Hashes of ten short slab, half-space and chain2d runs: does a change keep their bits?

    NUMBA_CACHE_DIR=$(mktemp -d) .venv/bin/python benchmarks/slab_bits.py > before.txt   # at the old revision
    NUMBA_CACHE_DIR=$(mktemp -d) .venv/bin/python benchmarks/slab_bits.py > after.txt    # at the new one
    diff <(cut -c1-43 before.txt) <(cut -c1-43 after.txt)                      # names and hashes

The cases cover the 2-D drivers' paths (compose.fft_advance, krylov_implicit_advance, the top's
driver): the fixed, adaptive, fold and implicit steppers; the elastic and 'prony' bodies; the spring
drive, the dead weight and the tester's top. A hash covers every data variable and attribute of the
run's Dataset but its wall time; a fresh cache each time, since numba's cache does not see edits in
the modules a loop inlines. Used for the direct pocketfft calls (2026-11-27: identical before and after).
Several runs end 'diverged' (their energy check over a short window): the bits are what is compared.
"""

import hashlib
import time

import slipchain as sc
S = dict(geometry="slab", N=8, Ly=8, theta=0.5, seed=1, output_interval=1e-4)
CASES = {
 "slab_fixed": dict(S, integrator="fixed", dt=2e-8, start="steady", t_total=2e-3),
 "slab_adaptive": dict(S, integrator="adaptive", dt=2e-8, start="steady", t_total=2e-3),
 "halfspace_fixed": dict(S, geometry="halfspace", integrator="fixed", dt=2e-8, start="steady", t_total=2e-3),
 "slab_dw_prony_fold": dict(S, N_L=5, integrator="fold", dt=1e-7, dead_weight=0.3, start="rest", material="prony", epsilon=1.0, eta_c=1e5, t_total=3e-3),
 "slab_prony_springs_fold": dict(S, N_L=5, integrator="fold", dt=1e-7, start="steady", material="prony", epsilon=1.0, eta_c=1e5, t_total=3e-3),
 "slab_implicit": dict(S, integrator="implicit", dt=1e-7, epsilon=1.0, eta_c=1e5, start="steady", t_total=5e-3),
 "tester_implicit": dict(geometry="slab", N=8, Ly=8, N_L=50, epsilon=1.0, material="prony", integrator="implicit", dt=1e-7,
           seed=0, theta=0.5, dead_weight=0.6, top_mass="tester", start="rest", output_interval=1e-3, t_total=0.005, t_ramp=1e-3),
 "slab_prony_springs_implicit": dict(S, N_L=5, integrator="implicit", dt=1e-7, start="steady", material="prony", epsilon=1.0, eta_c=1e5, t_total=3e-3),
 "halfspace_prony_implicit": dict(S, geometry="halfspace", integrator="implicit", dt=1e-7, start="steady", material="prony", epsilon=1.0, eta_c=1e5, t_total=3e-3),
 "chain2d_implicit": dict(S, geometry="chain2d", integrator="implicit", dt=1e-7, epsilon=1.0, eta_c=1e5, start="steady", t_total=3e-3),
}


def digest(ds) -> str:
    attrs = repr(sorted((k, str(v)) for k, v in ds.attrs.items() if k != "wall_time_s"))
    return hashlib.sha256(b"".join(ds[v].values.tobytes() for v in sorted(ds.data_vars)) + attrs.encode()).hexdigest()[:12]


if __name__ == "__main__":
    for name, cfg in CASES.items():
        t = time.perf_counter()
        ds = sc.run(cfg, progress=False)
        print(f"{name:30s} {digest(ds)} {time.perf_counter() - t:7.2f}s {ds.attrs['status']}", flush=True)
