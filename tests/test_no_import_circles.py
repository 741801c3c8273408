"""No import circles (issue 16): among the engine's Rust modules (`use` at the top of each file
under crates/kinema/src, unit tests left out) and among kinema's Python modules (imports at
module level). A circle means a shared piece sits in the wrong module: the four the issue found
were ode/adaptive.rs <-> ode/solve.rs, render/raster.rs <-> render/scenery.rs, cli <-> demo and
io <-> trajectory. A module and its own parent (a Rust `mod.rs`, a Python package's
`__init__`) are not counted: the language ties them.

The checks are graph searches (Tarjan's strongly connected components) on edges read from the
source text; `test_a_circle_is_found` shows they see one."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RUST_SRC = ROOT / "crates" / "kinema" / "src"
PY_SRC = ROOT / "python"


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def rust_graph(src: Path) -> dict[str, set[str]]:
    """Module (a file: `ode::solve`) -> the modules its top-level `use crate::…`/`use super::…`
    name, unit tests and test helpers left out."""
    files: dict[tuple[str, ...], Path] = {}
    for p in src.rglob("*.rs"):
        parts = list(p.relative_to(src).with_suffix("").parts)
        if parts[-1] in ("mod", "lib"):
            parts = parts[:-1]
        if "tests" in parts or parts[-1:] == ["testing"]:
            continue
        files[tuple(parts)] = p

    def resolve(cur: tuple[str, ...], path: str) -> tuple[str, ...] | None:
        segs = path.split("::")
        if segs[0] == "crate":
            base, segs = [], segs[1:]
        elif segs[0] in ("super", "self"):
            base = list(cur)
            while segs and segs[0] == "super":
                base, segs = base[:-1], segs[1:]
            if segs and segs[0] == "self":
                segs = segs[1:]
        else:
            return None  # another crate
        best = None
        for k in range(len(segs) + 1):
            if tuple(base + segs[:k]) in files:
                best = tuple(base + segs[:k])
        return best

    graph: dict[str, set[str]] = {"::".join(m): set() for m in files}
    for m, p in files.items():
        text = p.read_text().split("#[cfg(test)]")[0]
        for use in re.findall(r"^(?:pub(?:\([\w:]+\))? )?use\s+([^;]+);", text, re.M):
            use = " ".join(use.split())
            grouped = re.match(r"([\w:]+)::\{(.*)\}$", use)
            items = re.split(r",(?![^{]*\})", grouped.group(2)) if grouped else [use]
            for item in items:
                item = item.strip().split(" as ")[0].split("::{")[0]
                if not item:
                    continue
                target = resolve(m, f"{grouped.group(1)}::{item}" if grouped else item)
                if target and target != m and m[: len(target)] != target:  # not itself, not an ancestor
                    graph["::".join(m)].add("::".join(target))
    return graph


def python_graph(src: Path) -> dict[str, set[str]]:
    """Module (`kinema.io.h5md`) -> the kinema modules it imports at module level (an import
    of a package's submodule counts as the submodule, not the package)."""
    mods: dict[str, Path | None] = {"kinema._core": None}
    for p in (src / "kinema").rglob("*.py"):
        name = ".".join(p.relative_to(src).with_suffix("").parts)
        mods[name.removesuffix(".__init__")] = p
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, p in mods.items():
        if p is None:
            continue
        package = m if p.name == "__init__.py" else m.rsplit(".", 1)[0]
        for node in ast.parse(p.read_text()).body:
            targets = []
            if isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    mod = ".".join(base + ([node.module] if node.module else []))
                else:
                    mod = node.module or ""
                targets = [f"{mod}.{a.name}" if f"{mod}.{a.name}" in mods else mod for a in node.names]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            for t in targets:
                if t in mods and t != m and not m.startswith(t + "."):
                    graph[m].add(t)
    return graph


def test_the_engine_has_no_import_circles():
    assert circles(rust_graph(RUST_SRC)) == []


def test_the_python_package_has_no_import_circles():
    assert circles(python_graph(PY_SRC)) == []


def test_a_circle_is_found(tmp_path):
    """The checks can fail: two Rust files that use each other, two Python modules that import
    each other, and the graphs they make."""
    src = tmp_path / "src"
    (src / "ode").mkdir(parents=True)
    (src / "lib.rs").write_text("pub mod ode;\n")
    (src / "ode" / "mod.rs").write_text("pub mod adaptive;\npub mod solve;\n")
    (src / "ode" / "adaptive.rs").write_text("use super::solve::{Recorder, Solution};\n")
    (src / "ode" / "solve.rs").write_text("use super::adaptive;\nuse crate::ode::mod_free as x;\n")
    assert circles(rust_graph(src)) == [["ode::adaptive", "ode::solve"]]
    py = tmp_path / "py" / "kinema"
    py.mkdir(parents=True)
    (py / "__init__.py").write_text("from .cli import main\n")
    (py / "cli.py").write_text("from .demo import run\n")
    (py / "demo.py").write_text("from . import cli\n")
    assert circles(python_graph(tmp_path / "py")) == [["kinema.cli", "kinema.demo"]]
