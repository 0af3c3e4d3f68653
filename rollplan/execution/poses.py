"""Poses of the sphere along a motion: the orientation (2) and the contact point (1) at chosen times."""

from __future__ import annotations

import numpy as np

from ..core import model

__all__ = ["animation_frames"]


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
    rot = model.orientations(x[:, 3], x[:, 4], x[:, 2])
    contact = model.contact_points(state[:, 3], state[:, 4])
    return t, x, rot, contact
