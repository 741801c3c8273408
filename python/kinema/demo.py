"""`kinema demo`: the lecture notes, shown.

First half: one problem — the harmonic oscillator x'' = −x over ten periods — integrated by
every method of the registry at the same step, then three pictures: the phase portraits
(forward Euler spirals out, backward Euler spirals in, the symplectic methods stay on the
circle), the stability regions on p' = λp, and the measured convergence orders.

Second half: the scene kinema/scenes/demo.toml, 400 balls falling under gravity into a box,
integrated by velocity Verlet and colliding by Newton's restitution law (e = 0.7): the
trajectory (trajectory.h5), a video (demo.mp4), the browser viewer in one offline page
(demo.html) and the energy and momentum plot (energy.png), where the energy the collisions
take is booked.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
from rich.console import Console
from rich.table import Table

from . import convergence, methods, problems, solve_second_order, stability
from .runner import save_figure_atomically, simulate_scene

OMEGA = 1.0
PERIODS = 10
H = 0.1


def _phase_portraits(results: dict, out: Path) -> Path:
    import matplotlib.pyplot as plt

    names = list(results)
    cols = 4
    rows = (len(names) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), sharex=True, sharey=True)
    circle = np.linspace(0.0, 2.0 * np.pi, 200)
    for ax, name in zip(axes.flat, names, strict=False):
        sol = results[name]
        ax.plot(np.cos(circle), -np.sin(circle), color="0.75", lw=3, label="exact")
        ax.plot(sol.x[:, 0], sol.v[:, 0], lw=0.8)
        ax.set_title(name)
        ax.set_aspect("equal")
        ax.set_xlim(-2, 2)
        ax.set_ylim(-2, 2)
    for ax in list(axes.flat)[len(names) :]:
        ax.axis("off")
    fig.suptitle(f"x'' = -x, {PERIODS} periods, h = {H}: phase portraits (x, v)")
    path = save_figure_atomically(fig, out / "phase_portraits.png")
    plt.close(fig)
    return path


REGIONS = ["euler", "midpoint", "rk4", "rk45", "implicit_euler", "verlet"]
"""The methods of the stability picture: Verlet's stable set is the segment [−2i, 2i], a line."""

CONVERGENCE = ["euler", "symplectic_euler", "implicit_euler", "midpoint", "heun", "verlet", "rk4"]

# Each method's line in the convergence picture: its own marker and line style, not the colour
# alone. Midpoint and Heun have the same R(z) = 1 + z + z²/2, so on the linear oscillator their
# errors coincide: midpoint is drawn wide with large open circles, Heun narrow and dashed with
# small crosses inside them, so both show.
STYLES = {
    "euler": {"marker": "p", "linestyle": "-", "lw": 1.5, "ms": 6},
    "symplectic_euler": {"marker": "s", "linestyle": "-", "lw": 1.5, "ms": 6},
    "implicit_euler": {"marker": "v", "linestyle": ":", "lw": 1.8, "ms": 6},
    "midpoint": {"marker": "o", "linestyle": "-", "lw": 4.0, "ms": 12, "mfc": "none", "mew": 2.0},
    "heun": {"marker": "x", "linestyle": "--", "lw": 1.5, "ms": 6, "mew": 1.5},
    "verlet": {"marker": "^", "linestyle": "-.", "lw": 1.5, "ms": 6},
    "rk4": {"marker": "D", "linestyle": "-", "lw": 1.5, "ms": 5},
}


def _regions(out: Path) -> Path:
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 6.5))
    stability.plot_regions(REGIONS, ax=ax, extent=(-5.0, 3.0, -4.0, 4.0))
    path = save_figure_atomically(fig, out / "stability_regions.png")
    plt.close(fig)
    return path


def convergence_figure() -> tuple[Any, Table]:
    """The convergence picture (global error against h on x'' = −x, one line per method of
    ``CONVERGENCE`` in its ``STYLES``) and the table of measured orders."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7.5, 6))
    table = Table(title="measured orders on x'' = -x (least-squares slopes of log error vs log h)")
    for col in ("method", "order", "global slope", "local slope"):
        table.add_column(col, justify="right")
    for name in CONVERGENCE:
        r = convergence(name, problems.harmonic_oscillator())
        ax.loglog(r.h_global, r.global_error, label=f"{name}: slope {r.global_order:.2f}", gid=name, **STYLES[name])
        table.add_row(name, str(r.expected_order), f"{r.global_order:.3f}", f"{r.local_order:.3f}")
    ax.set_xlabel("step size $h$")
    ax.set_ylabel("global error at $t = 2$")
    ax.set_title("Convergence: global error $\\propto h^p$")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="small")
    return fig, table


def _convergence(out: Path, console: Console) -> Path:
    import matplotlib.pyplot as plt

    fig, table = convergence_figure()
    path = save_figure_atomically(fig, out / "convergence.png")
    plt.close(fig)
    console.print(table)
    return path


SCENE = Path(__file__).resolve().parent / "scenes" / "demo.toml"


def _falling_balls(out: Path, console: Console) -> list[Path]:
    """The scene ``kinema/scenes/demo.toml`` (examples/scenes/demo.toml): 400 balls falling
    into a box, Verlet, e = 0.7, run as `kinema run` runs it (trajectory.h5, demo.mp4,
    energy.png), plus the viewer in one offline page (demo.html)."""
    from .viewer import BundleMissingError, write_html

    start = time.perf_counter()
    traj, paths = simulate_scene(SCENE, out)
    console.print(f"{traj.positions.shape[1]} balls: {traj.t[-1]:g} s simulated and rendered in {time.perf_counter() - start:.1f} s")
    try:
        paths.append(write_html(traj, out / "demo.html", title="kinema demo: falling balls"))
    except BundleMissingError as e:
        console.print(f"[yellow]skipped demo.html:[/] {e}")
    return paths


def run_demo(out: Path, console: Console) -> list[Path]:
    """Run the demonstration, print a summary, write the pictures into ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    t_end = PERIODS * 2.0 * np.pi / OMEGA

    def accel(t, x, v):
        return -OMEGA * OMEGA * x

    table = Table(title=f"x'' = -x over {PERIODS} periods, h = {H} (rk45: adaptive, rtol = 1e-8)")
    for col in ("method", "order", "|x(T) - cos T|", "E(T)/E(0) - 1", "f evals", "steps"):
        table.add_column(col, justify="right")
    results = {}
    for info in methods():
        name = info.name
        kwargs = {"rtol": 1e-8, "atol": 1e-10} if name == "rk45" else {"h": H}
        sol = solve_second_order(accel, [1.0], [0.0], (0.0, t_end), method=name, **kwargs)
        results[name] = sol
        x, v = sol.x[-1, 0], sol.v[-1, 0]
        energy = 0.5 * (v * v + OMEGA * OMEGA * x * x) / 0.5
        table.add_row(name, str(info.order), f"{abs(x - np.cos(OMEGA * t_end)):.2e}", f"{energy - 1.0:+.2e}", str(sol.nfev), str(sol.nsteps))
    console.print(table)
    paths = [_phase_portraits(results, out), _regions(out), _convergence(out, console)]
    paths += _falling_balls(out, console)
    console.print(f"demo finished in {time.perf_counter() - start:.1f} s; wrote:")
    for p in paths:
        console.print(f"  {p}")
    return paths
