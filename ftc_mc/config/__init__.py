"""Configuration files: the pydantic schema (the only validator of user values),
YAML loading with one-line errors, and commented YAML rendering.

* :mod:`~ftc_mc.config.schema`: the sections, :class:`Config` (``ftc-mc run`` and
  ``ftc-mc sweep``) and :class:`ScenarioConfig` (``ftc-mc scenario``);
* :mod:`~ftc_mc.config.load`: :func:`load_config`, :func:`load_scenario`, :func:`load_any`,
  :func:`parse_config`, :func:`with_overrides`;
* :mod:`~ftc_mc.config.render`: :func:`render_yaml` (``ftc-mc config show``).
"""

from .load import load_any, load_config, load_scenario, parse_config, with_overrides
from .render import render_yaml
from .schema import (CampaignConfig, Config, ControllerConfig, DrawsConfig,
                     EstimatorConfig, ExcitationConfig, ExplainConfig, FaultEvent,
                     ModelConfig, NoiseConfig, PlantConfig, ScenarioConfig, ScenarioSpec,
                     TimingConfig, ValidityConfig)

__all__ = ["CampaignConfig", "Config", "ControllerConfig", "DrawsConfig", "EstimatorConfig",
           "ExcitationConfig", "ExplainConfig", "FaultEvent", "ModelConfig", "NoiseConfig",
           "PlantConfig", "ScenarioConfig", "ScenarioSpec", "TimingConfig", "ValidityConfig",
           "load_any", "load_config", "load_scenario", "parse_config", "render_yaml", "with_overrides"]
