"""Time laws: how a plan's path parameter runs in time.

The minimum-jerk rest-to-rest law (:func:`rest_to_rest`) times each leaf of a
figure eight so that the robot starts and stops at rest, as the momentum
integral (11) assumes (no impulsive start).
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

__all__ = ["rest_to_rest"]


@lru_cache(maxsize=1)
def rest_to_rest() -> ca.Function:
    """The minimum-jerk profile ``s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5`` and its derivatives.

    ``f(tau) -> (s, ds/dtau, d2s/dtau2)``; ``s(0) = 0``, ``s(1) = 1``, first
    and second derivatives zero at both ends.
    """
    tau = ca.SX.sym("tau")
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    ds = ca.jacobian(s, tau)
    return ca.Function("rest_to_rest", [tau], [s, ds, ca.jacobian(ds, tau)], ["tau"], ["s", "ds", "dds"])
