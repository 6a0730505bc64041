"""Scenario: schema, YAML loading with file:line errors, dotted-path overrides."""
from .loader import load_scenario
from .overrides import apply_overrides, parse_override
from .schema import Scenario

__all__ = ["Scenario", "load_scenario", "apply_overrides", "parse_override"]
