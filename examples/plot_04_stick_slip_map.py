"""
Stick-slip maps at low and high load
====================================

Continue a steady run for 3 ms and record every interface block's velocity u_i(t) every 2 us
(``record_field``). Dark: the block sticks (u << v_d); bright: it slips. At low load
(theta = 0.1) contacts slip on their own in small, frequent events; at high load (theta = 1) they
stick and slip together in events that sweep the whole chain: the mechanism of the drop of
friction with load (``slip_events`` counts them).
"""

import matplotlib.pyplot as plt
import numpy as np

import slipchain
from slipchain.analysis.mechanism import record_field, slip_events, state_from_run

fig, axes = plt.subplots(2, 1, figsize=(7, 6), layout="constrained", sharex=False)
for ax, theta in zip(axes, (0.1, 1.0)):
    cfg = slipchain.make_config(N=101, theta=theta, start="steady", t_total=0.01)
    run = slipchain.run(cfg)
    field = record_field(slipchain.build_system(cfg), state_from_run(run), duration=3e-3, interval=2e-6)
    events = slip_events(field)
    sizes = events["event_size"].values
    print(f"theta = {theta:g}: {sizes.size} slip events, median size {np.median(sizes):.0f} blocks")
    im = ax.pcolormesh((field["time"] - field["time"][0]) * 1e3, field["block"], (field["u"] / cfg.v_d).T,
                       cmap="magma", vmin=0, vmax=3, shading="auto")
    ax.set(ylabel="interface block i",
           title=f"theta = {theta:g}: {sizes.size} events, median {np.median(sizes):.0f} blocks")
axes[-1].set_xlabel("time (ms)")
fig.colorbar(im, ax=axes, label="u_i / v_d")
