"""Old import paths (slipchain 0.1's flat modules) that still work, with one DeprecationWarning each.

0.2 arranged the package in subpackages (docs/architecture.md; CHANGELOG.md). ``import
slipchain.store`` and ``from slipchain.sweep import make_sweep`` keep working through the table
below: the old name is an alias of the new module. Names that moved between modules are listed
in the CHANGELOG.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

MOVED = {
    "slipchain.config": "slipchain.model.config",
    "slipchain.contact_law": "slipchain.model.contact_law",
    "slipchain.system": "slipchain.model.system",
    "slipchain.kernel": "slipchain.engine.backends.cpu",
    "slipchain.backend": "slipchain.engine.backends",
    "slipchain.gpu": "slipchain.engine.backends.cuda",
    "slipchain.simulation": "slipchain.engine.simulate",
    "slipchain.reference": "slipchain.engine.reference",
    "slipchain.observables": "slipchain.results.observables",
    "slipchain.checks": "slipchain.results.checks",
    "slipchain.io": "slipchain.results.io",
    "slipchain.sweep": "slipchain.sweeps.definition",
    "slipchain.runner": "slipchain.sweeps.executor",
    "slipchain.store": "slipchain.sweeps.store",
    "slipchain.reproduction": "slipchain.analysis.fig6",
    "slipchain.mechanism": "slipchain.analysis.mechanism",
    "slipchain.figures": "slipchain.plots.paper",
    "slipchain.reproduce": "slipchain.workflows.reproduce",
    "slipchain.tester.io": "slipchain.tester.inputs",
    "slipchain.tester.velocity": "slipchain.results.velocity",
    "slipchain.tester.plots": "slipchain.plots.tester",
}


class _Alias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old module name and hands back the new module (warning once per name)."""

    def find_spec(self, fullname, path=None, target=None):
        if fullname in MOVED:
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec):
        new = MOVED[spec.name]
        warnings.warn(f"{spec.name} moved to {new} in slipchain 0.2 (CHANGELOG.md); the old path will be removed",
                      DeprecationWarning, stacklevel=3)
        return importlib.import_module(new)

    def exec_module(self, module):  # the new module is already executed
        pass


def install() -> None:
    if not any(isinstance(f, _Alias) for f in sys.meta_path):
        sys.meta_path.append(_Alias())
