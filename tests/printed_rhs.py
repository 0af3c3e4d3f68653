"""The paper's printed (28)-(30) for the figure eight of circles (35), in numpy, and a
scipy DOP853 integration of it: an independent reference for the tests (not rollplan code).

(29) is printed with ``v^2`` under the root; it is ``y^2`` as in (28).
"""

import numpy as np
from scipy.integrate import solve_ivp


def circle(a, phi, side, gamma):
    """Point (35) of the circle of radius a (side +1: +y, -1: -y) rotated by gamma (31), and d/dphi."""
    d = np.sqrt(1 - a * a)
    s, c = np.sin(phi), np.cos(phi)
    p = np.array([a * s, side * (-a * d * c + d * a), -a * a * c - d * d])
    dp = np.array([a * c, side * a * d * s, a * a * s])
    cg, sg = np.cos(gamma), np.sin(gamma)
    rz = np.array([[cg, -sg, 0.0], [sg, cg, 0.0], [0.0, 0.0, 1.0]])
    return rz @ p, rz @ dp


def rhs(phi, state, a, side, k, gamma):
    """(28)-(30) with R = 1, c_u, c_v from (26)."""
    (x, y, z), ct = circle(a, phi, side, gamma)
    psi = state[2]
    s = np.sqrt(1 - y * y)
    cut = np.array([z, 0.0, -x]) @ ct
    cvt = np.array([-x * y / s, s, -y * z / s]) @ ct
    return np.array([-np.cos(psi) / s * cut + np.sin(psi) * cvt,
                     np.sin(psi) / s * cut + np.cos(psi) * cvt,
                     (1 - k) * y * cut / (s * s) + k * x * cvt / (z * s)])


def trace(a, b, k, gamma=0.0, steps=1, rtol=1e-13, atol=1e-14):
    """(u_a, v_a, psi) after ``steps`` figure eights from zero, by DOP853."""
    x = np.zeros(3)
    for _ in range(steps):
        for r, side in ((a, 1.0), (b, -1.0)):
            sol = solve_ivp(rhs, (0.0, 2 * np.pi), x, method="DOP853", rtol=rtol, atol=atol, args=(r, side, k, gamma))
            x = sol.y[:, -1]
    return x
