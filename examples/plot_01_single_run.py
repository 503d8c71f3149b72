"""
A single run and its driving force
===================================

One realisation of the two-chain model (N = 101 blocks, theta = 0.3 of them with a contact),
started in steady sliding and run until the standard error of mu_star is below 1 %. The driving
force per block, f_d(t) = K_d (v_d t - <X>), fluctuates around its mean as contacts stick and slip;
its steady mean, divided by epsilon f0 theta, is mu_star (see "Drive, start and measurement" on the model page).
"""

import matplotlib.pyplot as plt

import slipchain

ds = slipchain.run({"N": 101, "theta": 0.3, "start": "steady"})
cfg = slipchain.make_config(N=101, theta=0.3)
norm = cfg.epsilon * cfg.f0 * ds.attrs["theta"]

fig, ax = plt.subplots(figsize=(7, 3.5), layout="constrained")
ax.plot(ds["time"] * 1e3, ds["f_d"] / norm, lw=0.8, label="f_d(t) / (epsilon f0 theta)")
ax.axvspan(0, ds.attrs["t_transient"] * 1e3, color="0.9", label="transient (excluded)")
ax.axhline(ds.attrs["mu_star"], color="k", ls="--", label=f"mu_star = {ds.attrs['mu_star']:.3f} ± {ds.attrs['mu_star_sem']:.3f}")
ax.set(xlabel="time (ms)", ylabel="driving force / (epsilon f0 theta)", title="One run: N = 101, theta = 0.3, v_d = v0")
ax.legend(loc="lower right", fontsize=8)
print(ds.attrs["status"], ds.attrs["mu_star"], ds.attrs["t_total"])
