"""Issue 26: each geometry is described once (model.geometries), and the description is what the
config, the capability table and the engine act on."""

from __future__ import annotations

import typing

import pytest

from slipchain import ConfigError, make_config
from slipchain.engine.backends import compose
from slipchain.model.capabilities import refusal
from slipchain.model.config import Config
from slipchain.model.geometries import GEOMETRIES, geometry_of


def test_the_descriptions_cover_the_configs_geometries():
    assert set(GEOMETRIES) == set(typing.get_args(Config.model_fields["geometry"].annotation))
    assert {g: compose.BODIES[g] for g in GEOMETRIES} == {g: d.body for g, d in GEOMETRIES.items()}


@pytest.mark.parametrize("name", sorted(GEOMETRIES))
def test_a_description_is_what_the_config_and_the_table_act_on(name):
    g = geometry_of(name)
    if g.two_d:
        cfg = make_config(geometry=name, N=8, Ly=4, integrator="fixed")
        assert geometry_of(cfg) is g and cfg.n_blocks == 32
    else:
        with pytest.raises(ConfigError, match="'Ly' has value 4"):
            make_config(geometry=name, N=8, Ly=4)
    # a dead weight needs a top to carry it
    assert (refusal(name, "fixed", "dead_weight") is None) == g.top
    if not g.top:
        with pytest.raises(ConfigError, match="no top"):
            make_config(geometry=name, N=8, Ly=4, dead_weight=0.9)
    # a spectral body has no upper layer of blocks: its top stiffness is the kernel's, not K_L
    cfg = make_config(geometry=name, N=8, Ly=4 if g.two_d else 1, integrator="fixed")
    assert (cfg.K_Y > 0) == (g.body == "lattice" and g.two_d)
