"""
The contact law, eq. (1)
========================

f(u, v*) = epsilon f0 exp(-c log10(abs(u)/v*)^2) sign(u) + m eta_c u: a bell in log-velocity around
v* plus a viscous term. Below v* the force grows with velocity, above it falls (velocity
weakening: a contact there can stick-slip). The dashed curve averages the law over the v* of the
contacts of one realisation (log-uniform over v0 10^(+-delta)): Fig. 5 of the paper.
"""

import matplotlib.pyplot as plt

from slipchain.analysis.fig6 import contact_law_dataset

law = contact_law_dataset(N=1001, theta=1.0, seed=0)

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
for k in law["eta_c_factor"].values:
    label = "eta_c = 0" if k == 0 else f"eta_c = {k:g} omega0"
    ax.semilogx(law["v"], law["f"].sel(eta_c_factor=k), label=label)
ax.semilogx(law["v"], law["f_average"], "k--", label=f"average over {law.attrs['n_contacts']} contacts")
ax.set(xlabel="velocity u (m/s)", ylabel="f / (epsilon f0)", ylim=(0, 2), title="eq. (1) and its contact average")
ax.legend(fontsize=8)
