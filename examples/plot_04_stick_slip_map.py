"""
Stick-slip map of a field recording
===================================

Continue a steady run for 2 ms and record every interface block's velocity u_i(t) every 2 us
(``record_field``). Dark: the block sticks (u << v_d); bright: it slips. At high load (theta = 1)
contacts stick and slip together in events that sweep the whole chain: the mechanism of the
drop of friction with load.
"""

import matplotlib.pyplot as plt
import numpy as np

import slipchain
from slipchain.analysis.mechanism import record_field, slip_events, state_from_run

cfg = slipchain.make_config(N=101, theta=1.0, start="steady", t_total=0.01)
run = slipchain.run(cfg)
field = record_field(slipchain.build_system(cfg), state_from_run(run), duration=2e-3, interval=2e-6)
events = slip_events(field)
print(f"{events.sizes['event']} slip events, median size {np.median(events['event_size'].values):.0f} blocks")

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
im = ax.pcolormesh(field["time"] * 1e3, field["block"], (field["u"] / cfg.v_d).T, cmap="magma", vmin=0, vmax=3,
                   shading="auto")
fig.colorbar(im, ax=ax, label="u_i / v_d")
ax.set(xlabel="time (ms)", ylabel="interface block i", title="theta = 1: contacts slip together")
