"""What stops a campaign or an episode, as opposed to an outcome a controller reports."""

from __future__ import annotations

from prsc.errors import PrscError


class InfrastructureError(PrscError):
    """The machine cannot run episodes at all (MuJoCo cannot load a file, no GL context):
    the campaign stops with this message instead of recording an outcome."""


class SimulationTimeLimit(BaseException):
    """Raised by the episode's watchdog (harness._Watchdog) when an episode passes its simulated-time limit.

    A BaseException, so a controller's `except Exception` cannot swallow it."""
