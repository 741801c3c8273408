"""No import circles (issues 16 and 50): among the engine's Rust modules and among kinema's
Python modules. A circle means a shared piece sits in the wrong module.

The checks are graph searches (Tarjan's strongly connected components) on edges read from the
source text, and the edges are read honestly (issue 50: the first reader saw only top-level
`use` and `import` lines, and none of the circles there were):

- Python: every `import` and `from … import` anywhere in a module's syntax tree, inside
  functions (deferred imports) and inside `if TYPE_CHECKING:` blocks too. A TYPE_CHECKING
  import makes no circle at run time, but it is a dependency all the same (the module's
  signatures name the other module's types), and a circle of them is the same misplaced piece;
  so they count. `import kinema` (or `import kinema.io as kio`) counts as the modules its
  attributes name (`kinema.World` -> `kinema.world`).
- Rust: every `use` (anywhere, in function bodies too) and every path in the code that starts
  with `crate::`, `super::`, `self::`, a child module's name or a name a `use` bound to a
  module (`crate::world::World::RK45_SUBSTEPS` inside a function in `error.rs` is an edge
  error -> world). Comments and string literals are not code; `#[cfg(test)]` items, files
  reached only through them, `tests/` folders and `testing` modules are left out (unit tests
  and their helpers).

A name is followed to the module that defines it: a package's facade (a Python `__init__`, a
Rust `mod.rs` or `lib.rs`) that re-exports a name is passed through, so `from .render import
render_frames` is an edge to `kinema.render.frames` and `crate::collide::Contact` one to
`collide::contact`, not to the package (whose facade imports all of its parts). Where
the name is defined in the facade itself (or cannot be resolved) the edge is to the package.
A package's facade importing its own submodules is an edge like any other, but an edge from a
module to one of its own ancestors (a Rust `mod.rs`, a Python package's `__init__`) is not
counted: the language ties them (Python runs a package's `__init__` before any of its
submodules), and with re-exports followed nothing else reaches a facade for a name it only
passes on.

`test_a_circle_is_found` and `test_a_hidden_circle_is_found` show that the checks see circles,
including one made only by a function-level import and one only by an inline `crate::` path."""

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


# --- Rust ---------------------------------------------------------------------------------

_CHAR = re.compile(r"'(?:\\(?:x[0-9a-fA-F]{2}|u\{[0-9a-fA-F]+\}|.)|[^\\'\n])'")
_RAW = re.compile(r'b?r(#*)"')


def rust_code(text: str) -> str:
    """The text with comments removed and string and character literals emptied (lifetimes
    kept): what is left is code."""
    out: list[str] = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        prev = text[i - 1] if i else " "
        if text.startswith("//", i):
            j = text.find("\n", i)
            i = n if j < 0 else j
        elif text.startswith("/*", i):
            depth, i = 1, i + 2
            while i < n and depth:
                if text.startswith("/*", i):
                    depth, i = depth + 1, i + 2
                elif text.startswith("*/", i):
                    depth, i = depth - 1, i + 2
                else:
                    i += 1
            out.append(" ")
        elif (raw := _RAW.match(text, i)) and not (prev.isalnum() or prev == "_"):
            end = text.find('"' + raw.group(1), raw.end())
            i = n if end < 0 else end + 1 + len(raw.group(1))
            out.append('""')
        elif c == '"' or (c == "b" and text.startswith('b"', i) and not (prev.isalnum() or prev == "_")):
            i = text.index('"', i) + 1
            while i < n and text[i] != '"':
                i += 2 if text[i] == "\\" else 1
            i += 1
            out.append('""')
        elif c == "'" and (lit := _CHAR.match(text, i)):
            i = lit.end()
            out.append("' '")
        else:
            out.append(c)
            i += 1
    return "".join(out)


def _match_close(code: str, i: int) -> int:
    """The index just past the bracket that closes the one at i."""
    pairs = {"(": ")", "[": "]", "{": "}"}
    stack = []
    for j in range(i, len(code)):
        if code[j] in pairs:
            stack.append(pairs[code[j]])
        elif stack and code[j] == stack[-1]:
            stack.pop()
            if not stack:
                return j + 1
    return len(code)


def without_test_items(code: str) -> str:
    """`code` (comments and strings removed) with every item under `#[cfg(test)]` blanked."""
    while m := re.search(r"#\s*\[\s*cfg\s*\(\s*test\s*\)\s*\]", code):
        j = m.end()
        while True:  # the item's other attributes
            k = len(code) - len(code[j:].lstrip())
            if code.startswith("#", k) and "[" in code[k : k + 3]:
                j = _match_close(code, code.index("[", k))
            else:
                j = k
                break
        depth = 0
        while j < len(code):  # the item: to its `;` or its body's closing brace
            c = code[j]
            if c in "([":
                depth += 1
            elif c in ")]":
                depth -= 1
            elif c == ";" and depth == 0:
                j += 1
                break
            elif c == "{" and depth == 0:
                j = _match_close(code, j)
                break
            j += 1
        code = code[: m.start()] + " " * (j - m.start()) + code[j:]
    return code


def _use_tree(tree: str, prefix: list[str]) -> list[tuple[list[str], str | None]]:
    """The paths a `use` tree names, each with the name it binds (None for a glob)."""
    tree = tree.strip()
    if not tree:
        return []
    if tree.endswith("}"):
        head, _, body = tree.partition("{")
        segs = prefix + [s for s in head.split("::") if s.strip()]
        segs = [s.strip() for s in segs]
        parts, depth, cur = [], 0, ""
        for c in body[:-1]:
            if c == "," and depth == 0:
                parts.append(cur)
                cur = ""
                continue
            depth += (c == "{") - (c == "}")
            cur += c
        parts.append(cur)
        return [item for p in parts for item in _use_tree(p, segs)]
    path, _, alias = tree.partition(" as ")
    segs = prefix + [s.strip() for s in path.split("::")]
    if segs[-1] == "self":
        segs = segs[:-1]
    if segs[-1] == "*":
        return [(segs[:-1], None)]
    return [(segs, alias.strip() or segs[-1])]


_USE = re.compile(r"\buse\s+([^;]+);")
_PATH = re.compile(r"(?<![\w:$])(?:::\s*)?([A-Za-z_]\w*(?:\s*::\s*[A-Za-z_]\w*)+)")
_MOD = re.compile(r"\bmod\s+([A-Za-z_]\w*)\s*(;|\{)")


def rust_graph(src: Path) -> dict[str, set[str]]:
    """Module (a file: `ode::solve`) -> the modules it uses, in `use` lines and inline paths,
    unit tests and test helpers left out. The modules are the files `lib.rs` reaches by its
    `mod` declarations (not those under `#[cfg(test)]`)."""
    files: dict[tuple[str, ...], str] = {}  # module -> its code, tests left out
    children: dict[tuple[str, ...], set[str]] = {}
    inline: dict[tuple[str, ...], list[tuple[int, int]]] = {}  # spans of `mod x { … }` blocks
    todo = [((), src / "lib.rs")]
    while todo:
        m, p = todo.pop()
        if "tests" in m or m[-1:] == ("testing",) or not p.exists():
            continue
        code = without_test_items(rust_code(p.read_text()))
        files[m] = code
        children[m], inline[m] = set(), []
        folder = p.parent if p.name in ("lib.rs", "mod.rs") else p.with_suffix("")
        for d in _MOD.finditer(code):
            if d.group(2) == "{":
                inline[m].append((d.end() - 1, _match_close(code, d.end() - 1)))
            elif not any(a < d.start() < b for a, b in inline[m]):
                name = d.group(1)
                children[m].add(name)
                sub = folder / f"{name}.rs"
                todo.append((m + (name,), sub if sub.exists() else folder / name / "mod.rs"))

    def absolute(m: tuple[str, ...], segs: list[str], at: int = 0) -> list[str] | None:
        """`segs`, a path written in module m (at `at` in its code), from the crate's root."""
        if segs[0] == "crate":
            return segs[1:]
        depth = sum(a < at < b for a, b in inline[m])  # inside inline modules of the file
        if segs[0] == "self":
            return None if depth else list(m) + segs[1:]
        if segs[0] == "super":
            ups = 0
            while segs and segs[0] == "super":
                ups, segs = ups + 1, segs[1:]
            if ups < depth or ups - depth > len(m):
                return None  # within the file, or above the crate
            return list(m[: len(m) - (ups - depth)]) + segs
        if depth:
            return None
        if segs[0] in children[m]:
            return list(m) + segs
        if segs[0] in binds[m]:
            return binds[m][segs[0]] + segs[1:]
        return None  # another crate, a type, a variant

    def module_of(segs: list[str]) -> tuple[str, ...]:
        """The module that defines what the absolute path names, through re-exports."""
        for _ in range(50):
            k = max(n for n in range(len(segs) + 1) if tuple(segs[:n]) in files)
            mod, rest = tuple(segs[:k]), segs[k:]
            if rest and rest[0] in binds[mod] and binds[mod][rest[0]] != segs[: k + 1]:
                segs = binds[mod][rest[0]] + rest[1:]
            else:
                return mod
        return mod

    binds: dict[tuple[str, ...], dict[str, list[str]]] = {m: {} for m in files}
    uses: dict[tuple[str, ...], list[tuple[list[str], str | None, int]]] = {m: [] for m in files}
    for m, code in files.items():
        for u in _USE.finditer(code):
            for segs, name in _use_tree(" ".join(u.group(1).split()), []):
                uses[m].append((segs, name, u.start()))
        files[m] = _USE.sub(lambda u: " " * len(u.group(0)), code)
    for _ in range(3):  # a `use` may start from a name another `use` bound
        for m in files:
            for segs, name, at in uses[m]:
                full = absolute(m, segs, at)
                if full is not None and name and not any(a < at < b for a, b in inline[m]):
                    binds[m][name] = full

    graph: dict[str, set[str]] = {"::".join(m): set() for m in files}

    def edge(m: tuple[str, ...], target: tuple[str, ...]) -> None:
        if target != m and m[: len(target)] != target:  # not itself, not an ancestor
            graph["::".join(m)].add("::".join(target))

    for m, code in files.items():
        for segs, name, at in uses[m]:
            full = absolute(m, segs, at)
            if full is None:
                continue
            target = module_of(full)
            if name and list(target) == full and re.search(rf"(?<![\w:]){name}\s*::", code):
                continue  # a module bound to a name: its paths below say what is used
            edge(m, target)
        for p in _PATH.finditer(code):
            segs = [s.strip() for s in p.group(1).split("::")]
            full = absolute(m, segs, p.start())
            if full is not None:
                edge(m, module_of(full))
    return graph


# --- Python -------------------------------------------------------------------------------


def python_graph(src: Path) -> dict[str, set[str]]:
    """Module (`kinema.io.h5md`) -> the kinema modules it imports, anywhere in its body (an
    import through a package's facade counts as the submodule that defines the name)."""
    mods: dict[str, Path | None] = {"kinema._core": None}
    for p in (src / "kinema").rglob("*.py"):
        name = ".".join(p.relative_to(src).with_suffix("").parts)
        mods[name.removesuffix(".__init__")] = p
    trees = {m: ast.parse(p.read_text()) for m, p in mods.items() if p is not None}
    packages = {m for m, p in mods.items() if p is not None and p.name == "__init__.py"}

    def base_of(m: str, node: ast.ImportFrom) -> str:
        if not node.level:
            return node.module or ""
        package = m if m in packages else m.rsplit(".", 1)[0]
        parts = package.split(".")
        base = parts[: len(parts) - (node.level - 1)]
        return ".".join(base + ([node.module] if node.module else []))

    # What each package's facade binds by import: name -> (module, name there)
    facade: dict[str, dict[str, tuple[str, str | None]]] = {m: {} for m in packages}
    for m in packages:
        for node in trees[m].body:
            if isinstance(node, ast.ImportFrom):
                base = base_of(m, node)
                for a in node.names:
                    facade[m][a.asname or a.name] = (base, a.name)

    def resolve(mod: str, name: str | None) -> str | None:
        """The module that `name` of `mod` comes from (`mod` itself for a plain import)."""
        for _ in range(20):
            if name is not None and f"{mod}.{name}" in mods:
                return f"{mod}.{name}"
            if mod in packages and name in facade[mod]:
                mod, name = facade[mod][name]
                continue
            return mod if mod in mods else None
        return mod

    graph: dict[str, set[str]] = {m: set() for m in mods}
    for m, tree in trees.items():
        targets: list[str | None] = []
        bound: dict[str, str] = {}  # a name an import bound to a kinema module -> the module
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                base = base_of(m, node)
                for a in node.names:
                    t = resolve(base, a.name)
                    if t == f"{base}.{a.name}":
                        bound[a.asname or a.name] = t  # `from . import io`: see its attributes
                    else:
                        targets.append(t)
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.asname:
                        bound[a.asname] = a.name
                    else:
                        bound[a.name.split(".")[0]] = a.name.split(".")[0]
                        if a.name not in packages:
                            targets.append(a.name)  # `import a.b`: a.b (a package: its attributes below)
        used: set[str] = set()
        inner: set[int] = set()
        for node in ast.walk(tree):  # `kinema.World`, `kio.save_h5md`: the module that defines it
            chain = []
            while isinstance(node, ast.Attribute) and id(node) not in inner:
                chain.append(node.attr)
                inner.add(id(node.value))
                node = node.value
            if chain and isinstance(node, ast.Name) and bound.get(node.id) in mods:
                used.add(node.id)
                path = bound[node.id].split(".") + chain[::-1]
                k = max(n for n in range(1, len(path) + 1) if ".".join(path[:n]) in mods)
                targets.append(resolve(".".join(path[:k]), path[k] if k < len(path) else None))
        targets += [t for name, t in bound.items() if name not in used]
        for t in targets:
            if t in mods and t != m and not m.startswith(t + "."):  # not itself, not an ancestor
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


def test_a_hidden_circle_is_found(tmp_path):
    """The circles the first reader missed: a Rust path written inline in a function body
    (through a facade's re-export), and a Python import inside a function and one under
    TYPE_CHECKING, each through a package's facade; comments, strings and unit tests make
    none."""
    src = tmp_path / "src"
    (src / "world").mkdir(parents=True)
    (src / "lib.rs").write_text("pub mod error;\npub mod limits;\npub mod world;\n#[cfg(test)]\nmod oracle;\n")
    (src / "error.rs").write_text(
        "//! See crate::limits::CAP.\n"
        "pub fn message() -> String {\n"
        '    format!("{} (crate::limits::CAP)", crate::world::World::SUBSTEPS)\n'
        "}\n"
        "#[cfg(test)]\nmod tests {\n    use crate::limits::CAP;\n}\n"
    )
    (src / "world" / "mod.rs").write_text("mod step;\npub use step::World;\n")
    (src / "world" / "step.rs").write_text("pub struct World;\nfn fail() { let _ = crate::error::message(); }\n")
    (src / "limits.rs").write_text('/* crate::error::message */\npub const CAP: &str = "crate::oracle";\n')
    (src / "oracle.rs").write_text("use crate::limits::CAP;\nuse crate::error::message;\n")
    graph = rust_graph(src)
    assert graph["error"] == {"world::step"}
    assert graph["limits"] == set()
    assert "oracle" not in graph
    assert circles(graph) == [["error", "world::step"]]

    py = tmp_path / "py" / "kinema"
    (py / "io").mkdir(parents=True)
    (py / "__init__.py").write_text("from .world import World\nfrom . import io\n")
    (py / "world.py").write_text("def save(w):\n    from .io import save_h5md\n    return save_h5md(w)\n")
    (py / "io" / "__init__.py").write_text("from .h5md import save_h5md\n")
    (py / "io" / "h5md.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .. import World\n"
        "def save_h5md(w: 'World'):\n    import kinema\n    return kinema.world\n"
    )
    (py / "io" / "units.py").write_text("import kinema.io as kio\nx = kio.save_h5md\n")
    graph = python_graph(tmp_path / "py")
    assert graph["kinema.world"] == {"kinema.io.h5md"}
    assert graph["kinema.io.units"] == {"kinema.io.h5md"}
    assert circles(graph) == [["kinema.io.h5md", "kinema.world"]]
