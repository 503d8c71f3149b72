"""What is simulated: the parameters (config), the contact law of eq. (1), the two chains with their disorder and start."""

from .config import ALLOWED, LEGACY_KEYS, Config, ConfigError, config_from_toml, load_config, make_config, parse_override, read_toml
from .contact_law import ContactLaw
from .system import DEAD_WEIGHT_RAMP, State, System, build_system, dead_weight_force, initial_state, mu_star_norm

__all__ = ["ALLOWED", "DEAD_WEIGHT_RAMP", "LEGACY_KEYS", "Config", "ConfigError", "ContactLaw", "State", "System", "build_system",
           "config_from_toml", "dead_weight_force", "initial_state", "load_config", "make_config", "mu_star_norm",
           "parse_override", "read_toml"]
