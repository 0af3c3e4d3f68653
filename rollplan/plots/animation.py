"""Animation of the sphere rolling on the plane under its rotors (matplotlib + Pillow, GIF).

The motion shown is given (e.g. the rotor-driven simulation of a plan file,
:func:`rollplan.execution.plants.simulate_rotors`, so the animation shows what
the two motors produce). The sphere's centre is at ``(u_a, v_a, R)`` above the contact point and its
orientation is (2), ``R = Rz(psi)^T Rx(v_o)^T Ry(u_o)^T`` (:func:`rollplan.core.model.orientation`),
which maps the contact point (1) of the body frame to the bottom of the sphere.
Drawn: the shell (meridians and parallels), the body axes n_1 (red, rotor 1),
n_2 (green, rotor 2), n_3 (blue), the contact path on the plane and on the
shell so far, and the rotor rates with a moving cursor.
"""

from __future__ import annotations

import logging
import os
import tempfile

import numpy as np
from matplotlib.figure import Figure

from ..errors import OutputError
from ..execution.poses import animation_frames
from ..outputs import write_atomic

__all__ = ["make_animation"]

log = logging.getLogger(__name__)


def make_animation(time, state, rates, robot, goal, out, frames: int = 100, fps: int = 20) -> None:
    """Write a GIF of the sphere rolling (see module docstring) to ``out`` atomically.

    ``state`` (N, 5) in :class:`~rollplan.problem.State` order at ``time``; ``goal`` (u_a, v_a, ...) [m].
    """
    from matplotlib.animation import FuncAnimation, PillowWriter

    R = robot.radius
    t, x, rot, contact = animation_frames(time, state, frames)
    time = np.asarray(time, float)
    state = np.asarray(state, float)
    rates = np.asarray(rates, float)

    fig = Figure(figsize=(11, 5.2))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    lo = np.minimum(state[:, :2].min(0), goal[:2]) - 1.2 * R
    hi = np.maximum(state[:, :2].max(0), goal[:2]) + 1.2 * R
    span = max(hi - lo)
    mid = 0.5 * (lo + hi)
    ax.set_xlim(mid[0] - span / 2, mid[0] + span / 2)
    ax.set_ylim(mid[1] - span / 2, mid[1] + span / 2)
    ax.set_zlim(0, span)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel("u_a [m]")
    ax.set_ylabel("v_a [m]")
    ax.set_zlabel("z [m]")
    ax.plot([state[0, 0]], [state[0, 1]], [0], "ko", markersize=4)
    ax.plot([goal[0]], [goal[1]], [0], "k*", markersize=10)

    # shell: 6 meridians and 5 parallels on the unit sphere, body frame
    s = np.linspace(0, 2 * np.pi, 49)
    circles = []
    for lon in np.linspace(0, np.pi, 6, endpoint=False):
        circles.append(np.stack([np.cos(lon) * np.cos(s), np.sin(lon) * np.cos(s), np.sin(s)]))
    for lat in np.linspace(-60, 60, 5) * np.pi / 180:
        circles.append(np.stack([np.cos(lat) * np.cos(s), np.cos(lat) * np.sin(s), np.full_like(s, np.sin(lat))]))
    shell = [ax.plot([], [], [], color="0.6", linewidth=0.6)[0] for _ in circles]
    axes = [ax.plot([], [], [], color=c, linewidth=2.2)[0] for c in ("tab:red", "tab:green", "tab:blue")]
    path = ax.plot([], [], [], color="tab:purple", linewidth=1.4)[0]
    on_shell = ax.plot([], [], [], color="tab:orange", linewidth=1.4)[0]
    ax.set_title("sphere rolling: body axes n1 (red), n2 (green), n3 (blue)", fontsize=9)

    ax2.plot(time, rates[:, 0], label="$\\dot\\varphi_1$ (about n1)", color="tab:red")
    ax2.plot(time, rates[:, 1], label="$\\dot\\varphi_2$ (about n2)", color="tab:green")
    cursor = ax2.axvline(time[0], color="k", linewidth=1)
    ax2.set_xlabel("time t [s]")
    ax2.set_ylabel("rotor rate [rad/s]")
    ax2.set_title("rotor rates")
    ax2.grid(True, alpha=0.3)
    ax2.legend(loc="upper right", fontsize=8)
    fig.tight_layout()

    def update(i):
        centre = np.array([x[i, 0], x[i, 1], R])
        for line, c in zip(shell, circles):
            p = centre[:, None] + R * rot[i] @ c
            line.set_data_3d(p[0], p[1], p[2])
        for j, line in enumerate(axes):
            tip = centre + 1.5 * R * rot[i][:, j]
            line.set_data_3d([centre[0], tip[0]], [centre[1], tip[1]], [centre[2], tip[2]])
        upto = time <= t[i] + 1e-12
        path.set_data_3d(state[upto, 0], state[upto, 1], np.zeros(upto.sum()))
        c = centre[:, None] + R * 1.01 * rot[i] @ contact[upto].T
        on_shell.set_data_3d(c[0], c[1], c[2])
        cursor.set_xdata([t[i], t[i]])
        return shell + axes + [path, on_shell, cursor]

    anim = FuncAnimation(fig, update, frames=frames, blit=False)
    try:
        with tempfile.TemporaryDirectory() as tmp:   # Pillow writes to a file name: rendered there, then copied
            name = os.path.join(tmp, "anim.gif")
            anim.save(name, writer=PillowWriter(fps=fps))
            with open(name, "rb") as fh:
                data = fh.read()
    except OSError as exc:
        raise OutputError(f"the animation cannot be rendered in the temporary folder {tempfile.gettempdir()!r}: "
                          f"{exc.strerror or exc}") from None
    write_atomic(out, data)
    log.info("wrote %d frames to %s", frames, out)
