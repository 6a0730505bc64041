"""Frames and animations: a sequence's steps (one PNG per step, and a GIF, MP4 too where
ffmpeg exists, that plays the transitions between steps) and a ``simulate`` run in time (a GIF
and MP4 with a clock, at real time or a stated speed-up)."""
import contextlib
import shutil
from pathlib import Path

import numpy as np

from ..output import atomic_path
from .robot3d import _pyplot, draw_robot, finish


def save_step_pngs(result, directory, **view):
    """``step_XX_NAME.png`` for every step, drawn as the paper draws the robot."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths, limits = [], _limits(result)
    for index, (name, solution) in enumerate(zip(result.names, result.solutions)):
        plt = _pyplot()
        objects = result.objects[index].values() if result.objects else ()
        title = f"({chr(97 + index) if index < 26 else index}) {name}"
        if result.stage and result.stage[index]:
            title += f"\n[{result.stage[index]}, not a TCA]"
        ax = draw_robot(solution, title=title, objects=objects, limits=limits, **view)
        path = directory / f"step_{index:02d}_{_slug(name)}.png"
        paths.append(finish(plt, ax.figure, path, dpi=110, bbox_inches="tight", pad_inches=0.15))
    return paths


def save_animation(result, directory, fps=8, progress=None, **view):
    """``sequence.gif`` (and ``sequence.mp4`` when ffmpeg is on the PATH): every transition
    frame and every step. Returns the paths written."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    frames = []
    for index, (name, solution, transition) in enumerate(zip(result.names, result.solutions, result.transitions)):
        moving = result.transition_objects[index] if result.transition_objects else [{}] * len(transition)
        final = result.objects[index] if result.objects else {}
        note = f"\n[{result.stage[index]}, not a TCA]" if result.stage and result.stage[index] else ""
        frames += [(f"-> {name}{note}", s, o, 1) for (_, s), o in zip(transition, moving)]
        frames.append((name + note, solution, final, 3))              # each step held three frames
    fig = plt.figure(figsize=(5.6, 5.6))
    ax = fig.add_subplot(projection="3d")
    limits = _limits(result)

    def draw(index):
        ax.clear()
        title, solution, objects, _ = frames[index]
        draw_robot(solution, ax=ax, title=title, objects=objects.values(), limits=limits, **view)
        if progress is not None:
            progress((index + 1) / len(frames), title)
        return []

    holds = [frame[3] for frame in frames]
    paths = _save_movies(fig, draw, len(frames), directory / "sequence", fps, holds=holds)
    plt.close(fig)
    return paths


#: how far a 3D drawing is enlarged in an animation's frame (1: matplotlib's default margins)
FRAME_ZOOM = 0.94


def _save_movies(fig, draw, count, stem, fps, holds=None):
    """Animate ``draw(frame)`` over ``count`` frames of ``fig`` into ``STEM.gif`` (and
    ``STEM.mp4`` when ffmpeg is on the PATH), each written atomically; returns the paths.
    ``holds``: for how many frame periods each frame is shown (1 each by default).

    Each frame is rendered once (matplotlib's ``FuncAnimation.save`` renders every frame twice,
    and again for each writer), however long it is held: the GIF's frames are the canvas's
    pixels, each with its duration; an MP4 takes the frames through matplotlib's ffmpeg writer."""
    holds = [1] * count if holds is None else list(holds)
    from PIL import Image
    fig.subplots_adjust(left=0.0, right=1.0, bottom=0.05, top=0.9)    # the drawing fills the frame
    paths, images = [stem.with_suffix(".gif")], []
    with contextlib.ExitStack() as stack:
        movie = None
        if shutil.which("ffmpeg"):
            from matplotlib.animation import FFMpegWriter
            paths.append(stem.with_suffix(".mp4"))
            movie = FFMpegWriter(fps=fps)
            stack.enter_context(movie.saving(fig, stack.enter_context(atomic_path(paths[1])), fig.dpi))
        for frame in range(count):
            draw(frame)
            for ax in fig.axes:
                ax.set_box_aspect(ax.get_box_aspect(), zoom=FRAME_ZOOM)
            fig.canvas.draw()
            images.append(Image.fromarray(np.asarray(fig.canvas.buffer_rgba())).convert("RGB"))
            for _ in range(holds[frame] if movie is not None else 0):
                movie.grab_frame()
        with atomic_path(paths[0]) as temporary:
            images[0].save(temporary, format="GIF", save_all=True, append_images=images[1:],
                           duration=[int(1000 / fps) * hold for hold in holds], loop=0)
    return paths


#: speed-ups a time animation may use (the smallest that keeps it within its frame budget)
SPEED_UPS = (1, 2, 5, 10, 20, 50, 100, 200, 500, 1000)


def animation_speed_up(duration, fps, max_frames):
    """The smallest of :data:`SPEED_UPS` that shows ``duration`` [s] in at most ``max_frames``
    frames at ``fps``."""
    return next((k for k in SPEED_UPS if duration * fps / k <= max_frames), SPEED_UPS[-1])


def frame_indices(t, fps, speed_up):
    """For frames ``1 / fps`` apart in the animation (``speed_up / fps`` apart in time), the
    index of the last output time ``t`` (n,) [s] at or before each frame's time; the last
    output is always the last frame."""
    t = np.asarray(t, float)
    clock = np.arange(t[0], t[-1] + 1e-9, speed_up / fps)
    indices = np.searchsorted(t, clock + 1e-9, side="right") - 1
    return np.append(indices, len(t) - 1) if indices[-1] != len(t) - 1 else indices


def save_time_animation(series, directory, fps=10, max_frames=150, progress=None, **view):
    """``simulate.gif`` (and ``simulate.mp4`` when ffmpeg is on the PATH) of a ``simulate``
    :class:`~tca_casadi.time_simulation.heating.TimeSeries`: the robot at the solved output times, at
    real time or the smallest speed-up of :data:`SPEED_UPS` that fits ``max_frames`` frames,
    with a clock and the temperatures of the heated TCAs that are warm (0.5 K above the run's
    lowest temperature). Returns ``(paths, speed_up)``."""
    n = len(series.solutions)
    heated = [j for j in range(len(series.keys)) if not np.all(np.isnan(series.powers[:n, j]))]
    return animate_in_time(series.t[:n], series.solutions, series.keys, series.temperatures[:n], heated,
                           Path(directory) / "simulate", fps=fps, max_frames=max_frames, progress=progress,
                           objects=series.objects, **view)


def save_plan_animation(plan, solutions, directory, fps=10, max_frames=150, progress=None, **view):
    """``plan.gif`` (and ``plan.mp4`` with ffmpeg) of a :class:`~tca_casadi.control.plan.PlanResult`:
    the robot at every node's equilibrium (``solutions``, one per node) as
    :func:`save_time_animation` draws a run, with the target marked. Returns ``(paths, speed_up)``."""
    marks = [(plan.target, "target", "tab:green")]
    return animate_in_time(plan.t, solutions, plan.keys, plan.temperatures, list(range(len(plan.keys))),
                           Path(directory) / "plan", fps=fps, max_frames=max_frames, progress=progress, marks=marks,
                           **view)


def animate_in_time(t, solutions, keys, temperatures, heated, stem, fps=10, max_frames=150, progress=None,
                    objects=(), marks=(), view=None, projection=None):
    """A GIF (and MP4) at ``stem`` of the robot at times ``t`` (n,) [s] (``solutions``, one per
    time; ``objects``: per time, the object poses), at real time or the smallest speed-up of
    :data:`SPEED_UPS` that fits ``max_frames`` frames, with a clock and the temperatures
    (``temperatures`` (n, m) [degC] of ``keys``) of the TCAs ``heated`` (indices) that are warm;
    ``marks``: ``(position (3,) [m], label, color)`` drawn on every frame; ``view``,
    ``projection``: the camera (:func:`~tca_casadi.plotting.robot3d.apply_view`); the TCAs'
    temperature colours on one scale over every frame (only the frames' solutions are read). Returns ``(paths, speed_up)``."""
    stem = Path(stem)
    stem.parent.mkdir(parents=True, exist_ok=True)
    t = np.asarray(t, float)
    speed_up = animation_speed_up(t[-1] - t[0], fps, max_frames)
    frames = frame_indices(t, fps, speed_up)
    ambient = float(np.nanmin(temperatures)) if len(t) and np.size(temperatures) else 0.0
    shown = [solutions[k] for k in frames]          # (a dynamic run builds only these)
    points = [m.p for s in shown for m in s.modules]
    # where the rods touch an obstacle: an unbounded one (a wall) is drawn only inside the box
    points += [np.asarray(c.position, float).reshape(3, 1) for s in shown for c in s.contacts]
    points += [pose.corners() for k in frames if objects for pose in objects[k].values()]
    points += [np.asarray(position, float).reshape(3, 1) for position, _, _ in marks]
    every = np.hstack(points) * 1e3
    limits = every.min(axis=1), every.max(axis=1)
    from .robot3d import temperature_norm
    norm = max((temperature_norm(s) for s in shown), key=lambda n: n.vmax)
    plt = _pyplot()
    fig = plt.figure(figsize=(5.6, 5.6))
    ax = fig.add_subplot(projection="3d")
    pace = "real time" if speed_up == 1 else f"{speed_up}x real time"

    def draw(frame):
        ax.clear()
        k = frames[frame]
        warm = [f"{keys[j]} {temperatures[k, j]:.0f} degC" for j in heated
                if temperatures[k, j] > ambient + 0.5][:6]          # the TCAs that are warm now
        text = "\n".join("  ".join(warm[i:i + 3]) for i in range(0, len(warm), 3))
        draw_robot(shown[frame], ax=ax, objects=objects[k].values() if objects else (), extra_points=marks,
                   title=f"t = {t[k]:6.1f} s   ({pace})" + (f"\n{text}" if text else ""), view=view,
                   projection=projection, norm=norm, limits=limits)
        if progress is not None:
            progress((frame + 1) / len(frames), f"frame {frame + 1}/{len(frames)}")
        return []

    paths = _save_movies(fig, draw, len(frames), stem, fps)
    plt.close(fig)
    return paths, speed_up


def _limits(result):
    points = [m.p for s in result.solutions for m in s.modules]
    points += [m.p for t in result.transitions for _, s in t for m in s.modules]
    points += [pose.corners() for step in result.objects for pose in step.values()]
    every = np.hstack(points) * 1e3
    return every.min(axis=1), every.max(axis=1)


def _slug(name):
    return "".join(ch if ch.isalnum() else "_" for ch in name.lower()).strip("_")[:40] or "step"
