"""Frames and animations of a sequence: one PNG per step, and a GIF (MP4 too where ffmpeg
exists) that plays the transitions between steps."""
import shutil
from pathlib import Path

import numpy as np

from ..output import atomic_path, save_figure
from .robot3d import _pyplot, draw_robot, set_equal_limits


def save_step_pngs(result, directory):
    """``step_XX_NAME.png`` for every step, drawn as the paper draws the robot."""
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for index, (name, solution) in enumerate(zip(result.names, result.solutions)):
        plt = _pyplot()
        objects = result.objects[index].values() if result.objects else ()
        title = f"({chr(97 + index) if index < 26 else index}) {name}"
        if result.stage and result.stage[index]:
            title += f"\n[{result.stage[index]}, not a TCA]"
        ax = draw_robot(solution, title=title, objects=objects)
        _fix_limits(ax, _limits(result))
        path = directory / f"step_{index:02d}_{_slug(name)}.png"
        ax.figure.tight_layout()
        save_figure(ax.figure, path, dpi=110, bbox_inches="tight", pad_inches=0.15)
        plt.close(ax.figure)
        paths.append(path)
    return paths


def save_animation(result, directory, fps=8, progress=None):
    """``sequence.gif`` (and ``sequence.mp4`` when ffmpeg is on the PATH): every transition
    frame and every step. Returns the paths written."""
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    plt = _pyplot()
    frames = []
    for index, (name, solution, transition) in enumerate(zip(result.names, result.solutions, result.transitions)):
        moving = result.transition_objects[index] if result.transition_objects else [{}] * len(transition)
        final = result.objects[index] if result.objects else {}
        note = f"\n[{result.stage[index]}, not a TCA]" if result.stage and result.stage[index] else ""
        frames += [(f"-> {name}{note}", s, o) for (_, s), o in zip(transition, moving)] + [(name + note, solution, final)] * 3
    fig = plt.figure(figsize=(5.6, 5.6))
    ax = fig.add_subplot(projection="3d")
    limits = _limits(result)

    def draw(index):
        ax.clear()
        title, solution, objects = frames[index]
        draw_robot(solution, ax=ax, title=title, objects=objects.values())
        _fix_limits(ax, limits)
        if progress is not None:
            progress((index + 1) / len(frames), title)
        return []

    animation = FuncAnimation(fig, draw, frames=len(frames), blit=False)
    paths = [directory / "sequence.gif"]
    with atomic_path(paths[0]) as temporary:
        animation.save(temporary, writer=PillowWriter(fps=fps))
    if shutil.which("ffmpeg"):
        paths.append(directory / "sequence.mp4")
        with atomic_path(paths[1]) as temporary:
            animation.save(temporary, writer=FFMpegWriter(fps=fps))
    plt.close(fig)
    return paths


def _limits(result):
    points = [m.p for s in result.solutions for m in s.modules]
    points += [m.p for t in result.transitions for _, s in t for m in s.modules]
    points += [pose.corners() for step in result.objects for pose in step.values()]
    every = np.hstack(points) * 1e3
    return every.min(axis=1), every.max(axis=1)


def _fix_limits(ax, limits):
    set_equal_limits(ax, *limits)


def _slug(name):
    return "".join(ch if ch.isalnum() else "_" for ch in name.lower()).strip("_")[:40] or "step"
