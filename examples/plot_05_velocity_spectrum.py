"""
Velocity spectra at low and high load
=====================================

The paper proposes the power spectrum of the block velocities (and of the acoustic signal) as
the way to see the collective stick-slip. Welch spectra (``spectra``) of 4 ms field recordings at
theta = 0.1 and theta = 1: at high load the power moves to lower frequencies (large, rare,
system-wide events).
"""

import matplotlib.pyplot as plt

import slipchain
from slipchain.analysis.mechanism import median_frequency, record_field, spectra, state_from_run

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for theta in (0.1, 1.0):
    cfg = slipchain.make_config(N=101, theta=theta, start="steady", t_total=0.01)
    run = slipchain.run(cfg)
    field = record_field(slipchain.build_system(cfg), state_from_run(run), duration=4e-3, interval=1e-6)
    psd = spectra(field, segment=1024)
    f_med = median_frequency(psd["frequency"].values, psd["psd_u"].values)
    ax.loglog(psd["frequency"][1:], psd["psd_u"][1:], label=f"theta = {theta:g} (median {f_med / 1e3:.0f} kHz)")
    print(theta, f_med)
ax.set(xlabel="frequency (Hz)", ylabel="PSD of u_i, mean over blocks ((m/s)^2/Hz)", title="Block-velocity spectra")
ax.legend()
