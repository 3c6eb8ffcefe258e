"""ftc-mc: Monte Carlo fault injection for indirect active fault-tolerant control.

Implements "Reconfiguration control method for non-redundant actuator faults on
UAV" on a Skywalker X8 model; see ``docs/paper-map.md``.
"""

__all__ = ["run_campaign"]


def run_campaign(config, **kwargs):
    """Run a Monte Carlo campaign; see :func:`ftc_mc.campaign.runner.run_campaign`."""
    from .campaign.runner import run_campaign as _run

    return _run(config, **kwargs)
