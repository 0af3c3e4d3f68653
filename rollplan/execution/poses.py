"""Poses of the sphere along a motion: the orientation (2) and the contact point (1) at chosen times, and back.

:func:`state_from_pose` inverts the map: from the centre's position on the plane and the orientation
matrix of the body frame (its columns n1, n2, n3 of (3)-(5)) to the state (u_a, v_a, psi, u_o, v_o).
"""

from __future__ import annotations

import numpy as np

from ..core import model

__all__ = ["animation_frames", "pose_of_state", "state_from_pose", "rotation_from_quaternion"]


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


def pose_of_state(state) -> tuple[np.ndarray, np.ndarray]:
    """The centre's (x, y) on the plane and the orientation matrix (2) of states ``(N, 5)``: ``(N, 2), (N, 3, 3)``.

    The centre lies above the contact point of the plane, so its (x, y) is (u_a, v_a) (6)-(7).
    """
    s = np.atleast_2d(np.asarray(state, float))
    return s[:, 0:2].copy(), model.orientations(s[:, 3], s[:, 4], s[:, 2])


def state_from_pose(xy, rotation) -> np.ndarray:
    """States ``(N, 5)`` from the centre's (x, y) ``(N, 2)`` and orientation matrices ``(N, 3, 3)`` (inverse of (2)).

    The contact point in the body frame is ``-R^T e_z`` (the point of the sphere under its centre), which is
    (1) at (u_o, v_o): ``u_o = atan2(R_31, R_33)``, ``v_o = asin(-R_32)``; (4) gives
    ``psi = atan2(R_12, R_22)`` (n2 = (cos v_o sin psi, cos v_o cos psi, -sin v_o)). Defined while
    ``cos v_o > 0`` (the contact point off the equator's poles at v_o = +-pi/2), the region where plans run;
    psi is in (-pi, pi].
    """
    xy = np.atleast_2d(np.asarray(xy, float))
    r = np.asarray(rotation, float).reshape(-1, 3, 3)
    u_o = np.arctan2(r[:, 2, 0], r[:, 2, 2])
    v_o = np.arcsin(np.clip(-r[:, 2, 1], -1.0, 1.0))
    psi = np.arctan2(r[:, 0, 1], r[:, 1, 1])
    return np.column_stack([xy[:, 0], xy[:, 1], psi, u_o, v_o])


def rotation_from_quaternion(q) -> np.ndarray:
    """Rotation matrices ``(N, 3, 3)`` of unit quaternions ``(N, 4)`` in (w, x, y, z) order (normalised first)."""
    q = np.atleast_2d(np.asarray(q, float))
    q = q / np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], axis=-1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], axis=-1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=1)
