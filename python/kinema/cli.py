"""The ``kinema`` command (``python -m kinema`` is the same).

Exit codes: 0 done, 2 bad input (the message says what and where), 1 a failed run.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.table import Table

app = typer.Typer(
    name="kinema",
    help="kinema: particle systems that move by honest numerical methods.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
console = Console()
err_console = Console(stderr=True)


def _fail(message: str, code: int = 2) -> None:
    err_console.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _split_methods(methods: str) -> list[str]:
    import kinema

    names = [m.strip() for m in methods.split(",") if m.strip()]
    if not names:
        _fail(f"--methods {methods!r}: give at least one method name, comma separated")
    valid = kinema.method_names()
    for n in names:
        if n not in valid:
            _fail(f"--methods: unknown method '{n}'; valid methods are: {', '.join(valid)}")
    return names


def save_figure_atomically(fig, out: Path, dpi: int = 130) -> Path:
    """Write a matplotlib figure to ``out`` via a temporary file in the same folder, so an
    interrupted or failed write never leaves a half-written file under the final name."""
    out = Path(out)
    if out.is_dir():
        _fail(f"--out {out}: is a directory; give a file name such as {out / 'regions.png'}")
    suffix = out.suffix.lower().lstrip(".")
    if suffix not in {"png", "svg", "pdf", "jpg", "jpeg"}:
        _fail(f"--out {out}: unsupported image format '{out.suffix}'; use .png, .svg, .pdf or .jpg")
    parent = out.parent if str(out.parent) else Path(".")
    try:
        parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{out.name}.", suffix=out.suffix, dir=parent)
    except OSError as e:
        _fail(f"--out {out}: cannot write there ({e.strerror})")
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=dpi, format=suffix, bbox_inches="tight")
        os.replace(tmp, out)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return out


@app.command()
def methods() -> None:
    """List the integration methods of the registry."""
    import kinema

    table = Table(title="kinema methods")
    for col in ("name", "order", "kind", "f evals/step", "summary"):
        table.add_column(col)
    for m in kinema.methods():
        table.add_row(m.name, str(m.order), m.kind, str(m.evals_per_step), m.summary)
    console.print(table)


@app.command()
def stability(
    methods: Annotated[str, typer.Option(help="Comma-separated method names.")] = "euler,midpoint,rk4,implicit_euler",
    out: Annotated[Path, typer.Option(help="Image to write (.png, .svg, .pdf).")] = Path("regions.png"),
    extent: Annotated[str, typer.Option(help="re_min,re_max,im_min,im_max of the z = hλ plane.")] = "-5,3,-4,4",
) -> None:
    """Plot the stability regions |R(hλ)| ≤ 1 and print each method's stable intervals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import kinema

    names = _split_methods(methods)
    try:
        box = tuple(float(v) for v in extent.split(","))
        if len(box) != 4 or not (box[0] < box[1] and box[2] < box[3]):
            raise ValueError
    except ValueError:
        _fail(f"--extent {extent!r}: give four numbers re_min,re_max,im_min,im_max with min < max")
    fig, ax = plt.subplots(figsize=(7, 6))
    kinema.stability.plot_regions(names, ax=ax, extent=box)
    path = save_figure_atomically(fig, out)
    plt.close(fig)
    table = Table(title="stable intervals of z = hλ")
    for col in ("method", "real axis", "imaginary axis"):
        table.add_column(col)
    for n in names:
        r = kinema.stability.real_interval(n)
        i = kinema.stability.imag_interval(n)
        table.add_row(n, f"[{r.lo:.4f}, {r.hi:.4f}]", "none" if i.empty else f"[{i.lo:.4f}, {i.hi:.4f}]")
    console.print(table)
    console.print(f"wrote {path}")


@app.command()
def demo(
    out: Annotated[Path, typer.Option(help="Folder for the pictures.")] = Path("out"),
) -> None:
    """Integrate a problem with every method; plot stability regions and convergence."""
    from .demo import run_demo

    if out.exists() and not out.is_dir():
        _fail(f"--out {out}: exists and is not a folder")
    run_demo(out, console)


def main() -> None:
    """Entry point of the ``kinema`` script."""
    app()


if __name__ == "__main__":
    main()
