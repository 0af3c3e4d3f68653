"""Poses of the sphere along a motion: the orientation (2) and the contact point (1) at chosen times."""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from ..core import model

__all__ = ["animation_frames"]


@lru_cache(maxsize=1)
def _geometry() -> ca.Function:
    """``f(u_o, v_o, psi) -> (orientation (2) [3x3], contact point (1) on the unit sphere [3])``."""
    u, v, psi = ca.SX.sym("u"), ca.SX.sym("v"), ca.SX.sym("psi")
    return ca.Function("geometry", [u, v, psi], [model.orientation(u, v, psi), model.contact_point(u, v)])


def animation_frames(time, state, frames: int):
    """Frame times and, per frame, the interpolated state, orientation matrix and body-frame contact point.

    Returns
    -------
    t : (F,) frame times [s]
    x : (F, 5) states in :class:`~rollplan.problem.State` order
    rot : (F, 3, 3) orientation matrices (2)
    contact : (S, 3) contact points (1) on the unit sphere, body frame, at every sample
    """
    time = np.asarray(time, float)
    state = np.asarray(state, float)
    t = np.linspace(time[0], time[-1], frames)
    x = np.column_stack([np.interp(t, time, state[:, j]) for j in range(5)])
    geo = _geometry()
    rot = np.array([np.array(geo(x[i, 3], x[i, 4], x[i, 2])[0]) for i in range(frames)])
    contact = np.array(geo.map(time.size)(state[:, 3][None, :], state[:, 4][None, :], state[:, 2][None, :])[1]).T
    return t, x, rot, contact
