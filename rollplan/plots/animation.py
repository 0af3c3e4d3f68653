"""Animation of the sphere rolling on the plane under its rotors (matplotlib + Pillow, GIF).

The motion shown is given (e.g. the rotor-driven simulation of a plan file,
:func:`rollplan.execution.plants.simulate_rotors`, so the animation shows what
the two motors produce). The sphere's centre is at ``(u_a, v_a, R)`` above the contact point and its
orientation is (2), ``R = Rz(psi)^T Rx(v_o)^T Ry(u_o)^T`` (:func:`rollplan.core.model.orientation`),
which maps the contact point (1) of the body frame to the bottom of the sphere.
Drawn (colours of :mod:`.colors`, all named in legends): the shell (meridians
and parallels), the body axes n_1 (rotor 1), n_2 (rotor 2) and n_3, the contact
path on the plane and on the shell so far, the start and the target, the time
of the frame, and the rotor rates with a moving cursor. Saving reports its
progress (``progress(label, done, total)``). The GIF has one palette for all
frames and stores, after the first, only the pixels that changed (the others
transparent): about 1 MB for 100 frames.
"""

from __future__ import annotations

import logging

import numpy as np
from matplotlib.figure import Figure

from ..execution.poses import animation_frames
from ..outputs import write_atomic
from .colors import AXIS_N3, MARK, ROTOR, ROTOR_LABELS, SIMULATED

__all__ = ["make_animation"]

log = logging.getLogger(__name__)

#: Colours of the GIF's one palette (the figure's colours and their anti-aliased edges).
GIF_COLOURS = 64


def make_animation(motion, robot, goal, out, frames: int = 100, fps: int = 20, progress=None,
                   dpi: float | None = None, blit: bool = True) -> None:
    """Write a GIF of the sphere rolling (see module docstring) to ``out`` atomically.

    ``motion`` is a :class:`~rollplan.timeseries.TimeSeries` with ``rotor_rates`` (the state in
    :class:`~rollplan.problem.State` order, [m, rad]); ``goal`` (u_a, v_a, ...) [m];
    ``progress(label, done, total)`` is called after each frame written; ``dpi`` scales the frames
    (default: matplotlib's); ``blit=False`` draws every frame whole (slower; the same picture but for a few pixels where
    the cursor meets the axes' frame).
    """
    from matplotlib.lines import Line2D

    R = robot.radius
    time, state, rates = motion.time, motion.state, motion.rotor_rates
    t, x, rot, contact = animation_frames(time, state, frames)

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
    ax.plot([state[0, 0]], [state[0, 1]], [0], "o", color=MARK, markersize=4)
    ax.plot([goal[0]], [goal[1]], [0], "*", color=MARK, markersize=10)

    # shell: 6 meridians and 5 parallels on the unit sphere, body frame
    s = np.linspace(0, 2 * np.pi, 49)
    circles = []
    for lon in np.linspace(0, np.pi, 6, endpoint=False):
        circles.append(np.stack([np.cos(lon) * np.cos(s), np.sin(lon) * np.cos(s), np.sin(s)]))
    for lat in np.linspace(-60, 60, 5) * np.pi / 180:
        circles.append(np.stack([np.cos(lat) * np.cos(s), np.cos(lat) * np.sin(s), np.full_like(s, np.sin(lat))]))
    shell = [ax.plot([], [], [], color="0.6", linewidth=0.6)[0] for _ in circles]
    axis_colors = (ROTOR[0], ROTOR[1], AXIS_N3)
    axes = [ax.plot([], [], [], color=c, linewidth=2.2)[0] for c in axis_colors]
    path = ax.plot([], [], [], color=SIMULATED, linewidth=1.4)[0]
    on_shell = ax.plot([], [], [], color=SIMULATED, linewidth=1.0, linestyle="--")[0]
    handles = [Line2D([], [], color=c, linewidth=2.2, label=lab) for c, lab in
               zip(axis_colors, ("body axis n1 (rotor 1)", "body axis n2 (rotor 2)", "body axis n3"))]
    handles += [Line2D([], [], color=SIMULATED, linewidth=1.4, label="simulated contact path, plane"),
                Line2D([], [], color=SIMULATED, linewidth=1.0, linestyle="--", label="simulated contact path, shell"),
                Line2D([], [], color=MARK, marker="o", markersize=4, linestyle="", label="start"),
                Line2D([], [], color=MARK, marker="*", markersize=10, linestyle="", label="target")]
    legend = ax.legend(handles=handles, loc="upper left", fontsize=7, bbox_to_anchor=(-0.12, 0.93))
    stamp = fig.text(0.27, 0.985, "", ha="center", va="top", fontsize=11, family="monospace",
                     bbox={"boxstyle": "round,pad=0.3", "fc": "white", "ec": "0.6"})

    for i in range(2):
        ax2.plot(time, rates[:, i], label=f"$\\dot\\varphi_{i + 1}$, {ROTOR_LABELS[i]}", color=ROTOR[i])
    cursor = ax2.axvline(time[0], color=MARK, linewidth=1)
    ax2.set_xlabel("time t [s]")
    ax2.set_ylabel("rotor rate [rad/s]")
    ax2.set_title("rotor rates (cursor: the frame's time)")
    ax2.grid(True, alpha=0.3)
    legend2 = ax2.legend(handles=ax2.get_legend_handles_labels()[0] + [Line2D([], [], color=MARK, linewidth=1,
                                                                    label="time of the frame")],
               loc="upper right", fontsize=8)
    fig.tight_layout()
    width = len(f"{time[-1]:.2f}")

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
        stamp.set_text(f"sphere rolling under its rotors, t = {t[i]:{width}.2f} s of {time[-1]:.2f} s")
        return shell + axes + [path, on_shell, legend, cursor, legend2, stamp]   # drawn in this order

    write_atomic(out, _gif(fig, update, frames, fps, dpi, progress, blit, still=(legend, legend2)))
    log.info("wrote %d frames to %s", frames, out)


#: Pixels around an artist's extent that its anti-aliased edges may touch.
_EDGE = 3


def overlaps(renderer, artists, box) -> bool:
    """Whether any of the drawn ``artists`` (their extents grown by :data:`_EDGE` pixels) meets the display box
    ``box``."""
    grown = box.padded(_EDGE)
    return any(a.get_visible() and a.get_window_extent(renderer).padded(_EDGE).overlaps(grown) for a in artists)


def _gif(fig, update, frames: int, fps: int, dpi, progress, blit: bool = True, still=()) -> bytes:
    """The frames ``update(i)`` draws, as a GIF: one palette of :data:`GIF_COLOURS` colours for every frame,
    without dithering, so that what does not move is the same pixels in every frame and each frame after
    the first stores only the rectangle that changed. ``update(i)`` returns the artists it changed and those
    to be drawn over them, in drawing order: with ``blit`` the rest of the figure is drawn once, and each frame
    is that picture with these artists drawn on it (the view of the axes must not change between frames).
    Those of the ``still`` artists among them (legends: text is the slow part of a frame) are drawn once too,
    into a second picture, which a frame starts from when no moving artist meets them: the same pixels."""
    import io

    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    canvas = FigureCanvasAgg(fig)
    if dpi is not None:
        fig.set_dpi(dpi)
    moving = update(0) if blit else []
    for artist in moving:
        artist.set_animated(True)
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)
    still = [a for a in still if a in moving]
    pictures = {(): background}   # the background with some of the still artists drawn on it, by their indices

    def picture(kept):
        if kept not in pictures:
            canvas.restore_region(background)
            for j in kept:
                fig.draw_artist(still[j])
            pictures[kept] = canvas.copy_from_bbox(fig.bbox)
        return pictures[kept]

    if still:   # each still artist: its extent, and the moving artists drawn before it
        renderer = canvas.get_renderer()
        under = [(a.get_window_extent(renderer), moving[:moving.index(a)]) for a in still]
    palette, coded, previous = None, [], None
    for i in range(frames):
        update(i)
        if blit:   # first with every still artist as drawn once; again with those a moving artist meets drawn too
            kept = tuple(range(len(still)))
            while True:
                canvas.restore_region(picture(kept))
                for artist in moving:
                    if artist not in still or still.index(artist) not in kept:
                        fig.draw_artist(artist)
                met = tuple(j for j in kept if overlaps(renderer, under[j][1], under[j][0]))
                if not met:
                    break
                kept = tuple(j for j in kept if j not in met)
        else:
            canvas.draw()
        image = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba()).convert("RGB")
        if palette is None:   # the first frame has every colour of the figure (the moving parts too)
            palette = image.quantize(GIF_COLOURS - 1, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            colours = palette.getpalette()[:3 * (GIF_COLOURS - 1)]
            colours += [0] * (3 * (GIF_COLOURS - 1) - len(colours)) + [255, 0, 255]   # the last: transparent
        index = np.asarray(image.quantize(palette=palette, dither=Image.Dither.NONE))
        delta = index.copy()
        if previous is not None:   # a pixel as in the frame before: transparent (the frame before shows through)
            delta[index == previous] = GIF_COLOURS - 1
        previous = index
        frame = Image.fromarray(delta, "P")
        frame.putpalette(colours)
        coded.append(frame)
        if progress is not None:
            progress("animation frames", i + 1, frames)
    buf = io.BytesIO()
    coded[0].save(buf, format="GIF", save_all=True, append_images=coded[1:], duration=round(1000 / fps), loop=0,
                  optimize=False, disposal=1, transparency=GIF_COLOURS - 1)
    return buf.getvalue()
