"""
The friction-tester pipeline on synthetic data
==============================================

The paper's experiment hangs a weight on a rubber block on a road surface and measures how far
it slides with time. ``tester synth`` simulates such a tester (the data are SYNTHETIC: the
paper's own measurements are not in this repository), and the analysis reads the runs table and
the raw distance traces, finds the steady velocity of each run, flags runaways, and gives
mu(v) per nominal pressure with uncertainties.
"""

import tempfile
from pathlib import Path

import matplotlib.pyplot as plt

from slipchain.tester.synth import write_synthetic
from slipchain.workflows.tester import analyze

work = Path(tempfile.mkdtemp(prefix="slipchain-tester-"))
files = write_synthetic(work / "data")
result = analyze(files["runs"], files["traces"], work / "analysis")
table = result.runs
print(table["status"].value_counts().to_dict())

fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
ok = table[table["status"] == "ok"]
for p0, group in ok.groupby("pressure_Pa"):
    ax.errorbar(group["velocity_m_s"], group["mu"], group["mu_sem"], fmt="o", capsize=2, label=f"p0 = {p0 / 1e3:.1f} kPa")
ax.set_xscale("log")
ax.set(xlabel="steady velocity (m/s)", ylabel="mu", title="Synthetic tester: mu(v) per pressure")
ax.legend(fontsize=8)
