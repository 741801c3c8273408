"""docs/architecture.md names only what exists, and its lists that claim to be whole are whole.

The map is checked the way a reader uses it: every name it gives must be found. The page is
parsed by markdown-it-py (CommonMark), so that code spans, links and fenced blocks are what a
reader sees. Names are taken from:

- inline code spans (```name```) of the prose, and those inside the ```` ```text ```` blocks
  (the layer diagram, the step, the collide stage's map, the repository layout);
- link targets (``[world.md](world.md)``): a page beside this one, and its ``#anchor`` a
  heading of that page;
- in the ```` ```text ```` blocks, the words that are code by their form: ``Type::name`` and
  ``module::name`` paths, calls ``name()``, CamelCase words (``BoxContainer``),
  SCREAMING_CASE and snake_case words with an underscore (``CELL_SLACK``,
  ``take_removed_ids``), dotted names (``World.run``, ``kinema.render``), and capitalised
  words (``Particles``, ``Sleep``), of which people, programs and terms
  (:data:`PROPER_NOUNS`) and the page's own section titles are not code.

Each name is resolved by its form:

- a file or folder path (``world/collide.rs``, ``io/``, ``../examples/notebooks``): a
  tracked path ends with it (the build products the page calls untracked excepted; a file
  the code writes, ``summary.csv``, is one of its string literals);
- ``kinema <command>``: a command of the typer app ``kinema.cli.app``; ``make <target>``: a
  target of the Makefile;
- a Rust path: ``Type::member`` is a method of an ``impl`` of the type or of a trait it
  implements, a trait's method, an associated constant, an enum variant or a struct field
  (the page writes ``Properties::energy`` for a field); ``module::item``, ``crate::…`` and
  ``kinema::…`` are an item defined in that module's files or below them;
  ``Enum::{A, B}`` must be every variant of the enum (a braced list is the whole enum), and
  ``Name { a, b }`` exactly the fields of a struct or struct-like variant of that name;
- a call with plain identifiers as arguments (``rhs(t, y, dydt)``) is also checked against
  the parameter names of a Rust or Python function of that name, and a shown Python call's
  keyword arguments (``h=0.01``) against the function's signature;
- a dotted Python name (``kinema.X``, ``World.method``, ``Class.attr``,
  ``_core.World.sync``): imported and walked attribute by attribute from ``kinema`` (or
  ``kinema._core``, a submodule, a class of the package, an importable module such as
  ``numpy``); an attribute that exists only on instances (set in ``__init__``, a dataclass
  field) is found by AST in the class or its bases; ``window.…`` is the viewer's JavaScript;
- a bare identifier (``stable_step``, ``ContactForce``, ``CG_TOLERANCE``, ``y0``): defined
  in the Rust sources under ``crates/`` (``fn``, ``struct``, ``enum``, ``trait``, ``type``,
  ``const``, ``static``, ``mod``, variants, fields, parameters, generic parameters, names a
  ``use`` brings in, the crates and their dependencies) or in the repository's Python
  (modules, classes, functions, parameters, assignments, attributes, ``_core.pyi``,
  pyproject's dependencies), a CLI command, a Makefile target, a Rust or Python builtin, or
  else used by the code: an identifier of the Rust or Python code (comments and docstrings
  left out), a whole string literal of it (``KINEMA_BLENDER``), a word of the viewer's
  JavaScript or of the Makefile;
- a quoted string (``"non-finite"``): a string literal of the Rust or Python sources;
- an attribute (``#![warn(missing_docs)]``): written so in a Rust source.

Deliberately not checked: the ```` ```python ```` and ```` ```toml ```` blocks (test_docs.py
runs them), formulas (a subscript such as ``m_i`` in a text block is math), shell commands
and other programs' names and keywords, listed in :data:`NOT_CHECKED` with why (LAMMPS's
``dump custom``, a sysctl setting, mkdocstrings' ``::: kinema.NAME``). The page's prose
words are not names: only its code spans are. A name is resolved where it can be found, not
where the page says it lives (``Sleep`` beside ``collide/sleep.rs`` is found in any file).

Besides the names: the lists the page gives whole are compared with the code's
(``test_a_list_the_page_gives_whole_is_the_code_s_list``: the ``Error`` and ``Divergence``
variants, ``SimulationDiverged.reason``'s words, the ``Force`` trait's methods, the CLI's
commands, the Makefile's targets, the collision settings and statistics, the export
formats, ...), the repository layout names every source file, and the engine's box in
"Layers" is the order of its modules' ``use``, with every use upward named under it.
``test_a_made_up_name_is_reported`` shows that a made-up name of each form is reported.
"""

from __future__ import annotations

import ast
import builtins
import functools
import importlib
import inspect
import re
import subprocess
import tomllib
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "architecture.md"
NOT_FILES = {"three.js"}  # a library's name, not a file
FILE = re.compile(r"(?<![\w/.-])(/?[\w.-]+(?:/[\w.-]+)*\.(?:rs|py|pyi|md|toml|js|mjs|html|json|in|txt|yml|cfg))\b")
SUFFIXES = {"rs", "py", "pyi", "md", "toml", "js", "mjs", "html", "json", "in", "txt", "yml", "cfg", "so", "png", "csv"}
UNTRACKED = {".venv/", "target/", "out/", "site/", "python/kinema/_core.abi3.so"}  # build products, named as such

# Names the page gives that are not kinema's, or not names, with why.
NOT_CHECKED = {
    "mindlin/force": "LAMMPS's tangential model, not present in kinema",
    "mindlin_rescale": "LAMMPS's tangential model, not present in kinema",
    "dump custom": "LAMMPS's command",
    "dump local": "LAMMPS's command",
    "net.core.somaxconn": "a Linux sysctl setting",
    "restitution = 1.5 is invalid: ...": "an error message",
    "::: kinema.NAME": "mkdocstrings' syntax, NAME for each public name",
    "kinema = kinema.cli:main": "the console script's entry in pyproject.toml",
    "cargo build": "a shell command",
    "cargo test": "a shell command",
    "cargo test --workspace --exclude kinema-py --release": "a shell command (the Makefile's)",
    "pytest": "a shell command",
    "default-members": "a key of Cargo.toml's [workspace]",
    "...": "doctest's ellipsis",
    "NumPy": "a library's name",
    "SciPy": "a library's name",
    "PyO3": "a library's name",
    "JavaScript": "a language's name",
    "MercuryCG": "a program's name",
}
# Capitalised words of the text blocks that are not code: people, programs, math.
PROPER_NOUNS = {
    "Baraff", "Witkin", "Bridson", "Butcher", "Coulomb", "Dormand", "Prince", "Enskog", "Ericson",
    "Guendelman", "Kahn", "Kepler", "Lamb", "Oseen", "Lorenz", "Morton", "Newton", "Perlin",
    "Rayleigh", "Smallenburg", "Voronoi", "Dask", "Houdini", "Pillow", "Jacobian", "Jacobians", "Hessians", "Ctrl",
}  # fmt: skip
# A variable the page's prose calls by name: what it stands for.
ALIASES = {"w": "kinema.World"}

RUST_PRELUDE = {
    "Box", "Result", "Option", "Ok", "Err", "Some", "None", "Vec", "String", "Send", "Sync", "Self", "self",
    "f64", "f32", "usize", "u8", "u32", "u64", "i32", "i64", "bool", "str", "dyn", "mut", "impl", "fn", "std",
}  # fmt: skip
KEYWORDS = {"dyn", "mut", "impl", "fn", "pub", "for", "where", "as", "in", "and", "or", "not", "is", "self"}


# ------------------------------------------------------------------------------------------
# The page: its names


@dataclass(frozen=True)
class Name:
    text: str
    line: int
    kind: str  # "span" (a code span), "link" (a link's target) or "word" (a word of a text block)


FENCE_WORD = re.compile(
    r"""`(?P<span>[^`\n]+)`
    | (?P<word>
        \b[A-Za-z_]\w*(?:::[A-Za-z_]\w*)+(?:\(\))?          # Type::name, module::item
      | (?<![\w.])[A-Za-z_]\w*(?:\.[A-Za-z_]\w*)+(?:\(\))?   # World.run, kinema.render
      | \b[A-Za-z_]\w*\(\)                                   # name()
      | \b[A-Z][a-z0-9]+(?:[A-Z][a-z0-9]*)+\b                # CamelCase, two humps or more
      | \b[A-Z][A-Z0-9]*_[A-Z0-9_]*[A-Z0-9]\b                # SCREAMING_CASE
      | \b[a-z][a-z0-9]*(?:_[a-z0-9]+)+\b                    # snake_case
      | \b[A-Z][a-z0-9]+\b                                   # Capitalised: Particles, Sleep
    )""",
    re.VERBOSE,
)


def _line_of(lines: list[str], text: str, start: int, end: int) -> int:
    for i in range(start, min(end, len(lines))):
        if text in lines[i]:
            return i + 1
    return start + 1


def names_in(markdown: str) -> list[Name]:
    """Every name the page gives, in the forms the module's doc lists."""
    lines = markdown.splitlines()
    names: list[Name] = []
    for tok in MarkdownIt("commonmark").parse(markdown):
        if tok.type == "fence":
            if tok.info.split("{")[0].strip() not in ("", "text"):
                continue
            first = tok.map[0] + 1  # the fence line itself is map[0]
            for k, row in enumerate(tok.content.splitlines()):
                masked = FILE.sub(lambda m: " " * len(m.group()), row)
                for m in FENCE_WORD.finditer(masked):
                    if m.group("span"):
                        text = row[m.start("span") : m.end("span")]
                        names.append(Name(text, first + k + 1, "span"))
                    else:
                        names.append(Name(m.group("word"), first + k + 1, "word"))
        elif tok.type == "inline":
            for child in tok.children or []:
                if child.type == "code_inline":
                    names.append(Name(child.content, _line_of(lines, child.content, *tok.map), "span"))
                elif child.type == "link_open":
                    href = child.attrs["href"]
                    names.append(Name(href, _line_of(lines, f"({href})", *tok.map), "link"))
    return names


# ------------------------------------------------------------------------------------------
# The Rust sources

_RUST_NOISE = re.compile(
    r"""//[^\n]*
    | /\*.*?\*/
    | \br(\#*)".*?"\1
    | b?"(?:\\.|[^"\\])*"
    | '(?:\\[^']{1,10}|[^\\'\n])'""",
    re.VERBOSE | re.DOTALL,
)


def blank_rust(code: str) -> str:
    """``code`` with comments and the insides of its literals as spaces (lines kept)."""
    return _RUST_NOISE.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), code)


def _strip_balanced(text: str, open_: str, close: str) -> str:
    out, depth = [], 0
    for i, ch in enumerate(text):
        if ch == open_ and not (open_ == "<" and text[i - 1 : i] == "-"):
            depth += 1
        elif ch == close and depth and not (close == ">" and text[i - 1 : i] == "-"):
            depth -= 1
        elif depth == 0:
            out.append(ch)
    return "".join(out)


def _split_top(text: str) -> list[str]:
    """``text`` split at its commas outside brackets."""
    parts, depth, cur = [], 0, []
    for i, ch in enumerate(text):
        if ch in "([{" or (ch == "<" and text[i - 1 : i] != "-"):
            depth += 1
        elif ch in ")]}" or (ch == ">" and text[i - 1 : i] != "-"):
            depth -= 1
        if ch == "," and depth == 0:
            parts.append("".join(cur))
            cur = []
        else:
            cur.append(ch)
    parts.append("".join(cur))
    return [p.strip() for p in parts if p.strip()]


def _generics(text: str) -> list[str]:
    """The type parameters of a ``<...>`` that ``text`` starts with (lifetimes left out)."""
    if not text.startswith("<"):
        return []
    depth = 0
    for i, ch in enumerate(text):
        depth += ch == "<"
        depth -= ch == ">" and text[i - 1] != "-"
        if depth == 0:
            inner = text[1:i]
            break
    else:
        return []
    return [m.group(1) for p in _split_top(inner) if (m := re.match(r"(?:const\s+)?([A-Za-z_]\w*)", p))]


def _type_name(text: str) -> str | None:
    """The name of the type ``text`` spells (``crate::x::Foo<'a>`` is ``Foo``)."""
    text = _strip_balanced(text, "<", ">").strip()
    text = re.sub(r"^(?:&\s*(?:'\w+\s*)?(?:mut\s+)?|dyn\s+)", "", text)
    m = re.search(r"([A-Za-z_]\w*)\s*$", text)
    return m.group(1) if m else None


ATTR = re.compile(r"#!?\[[^\]]*\]")
ITEM = re.compile(
    r"(?<!')\b(?P<kind>fn|struct|enum|trait|type|const|static|mod|union|macro_rules!)\s+"
    r"(?!fn\b|unsafe\b|extern\b|async\b)(?P<name>[A-Za-z_]\w*)"
)
USE = re.compile(r"\buse\s+([^;]+);")


@dataclass
class Ctx:
    """A brace's context while a Rust file is read."""

    kind: str  # impl, trait, enum, struct, variant, mod, fn, block
    name: str = ""
    direct: list[str] = field(default_factory=list)  # its text outside inner braces


@dataclass
class RustIndex:
    names: set[str] = field(default_factory=set)  # everything defined or used by name
    types: dict[str, set[str]] = field(default_factory=lambda: defaultdict(set))  # type -> kinds
    members: dict[str, set[str]] = field(default_factory=lambda: defaultdict(set))  # type -> members
    variants: dict[str, list[str]] = field(default_factory=dict)  # enum -> its variants in order
    fields: dict[str, list[list[str]]] = field(default_factory=lambda: defaultdict(list))  # struct/variant
    params: dict[str, list[list[str]]] = field(default_factory=lambda: defaultdict(list))  # fn -> lists
    impls: dict[str, set[str]] = field(default_factory=lambda: defaultdict(set))  # type -> traits
    modules: dict[tuple[str, ...], set[str]] = field(default_factory=lambda: defaultdict(set))  # path -> names
    sources: list[str] = field(default_factory=list)  # the raw texts

    def add_file(self, path: Path, module: tuple[str, ...]) -> None:
        raw = path.read_text(encoding="utf-8")
        self.sources.append(raw)
        code = ATTR.sub(lambda m: " " * len(m.group()), blank_rust(raw))
        defined = self.modules[module]
        for m in USE.finditer(code):
            for ident in re.findall(r"[A-Za-z_]\w*", m.group(1)):
                self.names.add(ident)
        stack = [Ctx("mod", module[-1])]
        head_start = last = 0
        for m in re.finditer(r"[{};]|" + ITEM.pattern, code):
            tok = m.group()
            top = stack[-1]
            if tok in "{};":
                top.direct.append(code[last : m.start()])
                last = m.end()
                if tok == "{":
                    ctx = self._context(code[head_start : m.start()], top)
                    stack.append(ctx)
                    if ctx.kind == "mod":
                        module = (*module, ctx.name)
                        defined = self.modules[module]
                elif tok == "}" and len(stack) > 1:
                    done = stack.pop()
                    self._close(done)
                    if done.kind == "mod":
                        module = module[:-1]
                        defined = self.modules[module]
                head_start = m.end()
                continue
            kind, name = m.group("kind"), m.group("name")
            self.names.add(name)
            defined.add(name)
            if kind in ("struct", "enum", "trait", "type", "union"):
                self.types[name].add(kind)
            if kind == "mod":
                self.modules[(*module, name)]
            owner = top.name if top.kind in ("impl", "trait") else None
            if owner and kind in ("fn", "const", "type"):
                self.members[owner].add(name)
            rest = code[m.end() :]
            for g in _generics(rest.lstrip()):
                self.names.add(g)
            if kind == "fn":
                after = _strip_balanced(rest.lstrip()[: rest.lstrip().find("(")], "<", ">") if "(" in rest else ""
                if not after.strip():
                    self.params[name].append(self._params(rest[rest.find("(") :]))
                    if owner:
                        self.params[f"{owner}::{name}"].append(self.params[name][-1])
            elif kind == "struct" and re.match(r"\s*(?:<[^{;(]*>)?\s*\(", rest):
                self.fields[name].append([])  # a tuple struct

    def _params(self, text: str) -> list[str]:
        """The parameters' names of the list ``text`` starts with (``self`` left out)."""
        out = []
        for p in _split_top(text[1 : len(_braced(text, 0, "()")) + 1]):
            m = re.match(r"(?:mut\s+)?([A-Za-z_]\w*)\s*:", p)
            if m and m.group(1) != "py":  # PyO3's token of the GIL, not an argument
                out.append(m.group(1))
                self.names.add(m.group(1))
        return out

    def _context(self, head: str, parent: Ctx) -> Ctx:
        head = re.sub(r"\bpub(?:\s*\([^)]*\))?", " ", head).strip()
        if parent.kind == "enum":
            name = re.findall(r"[A-Za-z_]\w*", head)
            return Ctx("variant", f"{parent.name}::{name[-1]}" if name else "")
        m = re.match(r"(?:unsafe\s+)?impl\b\s*(.*)$", head, re.DOTALL)
        if m:
            rest = m.group(1).strip()
            params = _generics(rest)
            self.names.update(params)
            if rest.startswith("<"):
                rest = _strip_leading_generics(rest)
            rest = re.split(r"\bwhere\b", rest)[0]
            parts = re.split(r"\bfor\b", _strip_balanced(rest, "<", ">"), maxsplit=1)
            if len(parts) == 2:
                trait, ty = _type_name(parts[0]), _type_name(parts[1])
                if ty and trait:
                    self.impls[ty].add(trait)
                return Ctx("impl", ty or "")
            return Ctx("impl", _type_name(parts[0]) or "")
        m = re.search(r"\b(trait|enum|struct|union|mod|fn)\s+([A-Za-z_]\w*)", head)
        if m and not re.search(r"[=;]", head[: m.start()]):
            return Ctx(m.group(1) if m.group(1) != "union" else "struct", m.group(2))
        return Ctx("block")

    def _close(self, ctx: Ctx) -> None:
        text = _strip_balanced(_strip_balanced("".join(ctx.direct), "(", ")"), "[", "]")
        if ctx.kind == "enum":
            variants = []
            for part in _split_top(text):
                m = re.match(r"([A-Za-z_]\w*)", part)
                if m:
                    variants.append(m.group(1))
            self.variants[ctx.name] = variants
            self.members[ctx.name].update(variants)
            self.names.update(variants)
        elif ctx.kind in ("struct", "variant"):
            text = re.sub(r"\bpub\s+", "", text)  # pub(crate) lost its parentheses above
            names = [m.group(1) for p in _split_top(text) if (m := re.match(r"([A-Za-z_]\w*)\s*:(?!:)", p))]
            self.fields[ctx.name].append(names)
            if ctx.kind == "variant":
                self.fields[ctx.name.split("::")[1]].append(names)
            self.names.update(names)


def _strip_leading_generics(text: str) -> str:
    depth = 0
    for i, ch in enumerate(text):
        depth += ch == "<"
        depth -= ch == ">" and text[i - 1] != "-"
        if depth == 0:
            return text[i + 1 :]
    return text


@functools.cache
def rust() -> RustIndex:
    index = RustIndex()
    for crate in sorted((ROOT / "crates").iterdir()):
        if not (crate / "Cargo.toml").exists():
            continue
        index.names.add(crate.name)
        cargo = tomllib.loads((crate / "Cargo.toml").read_text(encoding="utf-8"))
        for table in ("dependencies", "dev-dependencies", "build-dependencies"):
            index.names.update(cargo.get(table, {}))
        root = crate.name.replace("-", "_")
        for path in sorted(crate.rglob("*.rs")):
            rel = path.relative_to(crate).with_suffix("").parts
            if rel[0] == "src":
                rel = rel[1:]
            if rel[-1] in ("mod", "lib", "main"):
                rel = rel[:-1]
            index.add_file(path, (root, *rel))
            index.names.update(rel)
    return index


# ------------------------------------------------------------------------------------------
# The Python package


@dataclass
class PyIndex:
    names: set[str] = field(default_factory=set)
    attrs: dict[str, set[str]] = field(default_factory=lambda: defaultdict(set))  # class -> attributes
    classes: dict[str, list[str]] = field(default_factory=lambda: defaultdict(list))  # class -> modules
    params: dict[str, list[list[str]]] = field(default_factory=lambda: defaultdict(list))  # function -> lists
    sources: list[str] = field(default_factory=list)


@functools.cache
def python() -> PyIndex:
    index = PyIndex()
    package = ROOT / "python" / "kinema"
    for path in python_files():
        text = path.read_text(encoding="utf-8")
        index.sources.append(text)
        inside = path.is_relative_to(package)
        rel = path.relative_to(package.parent if inside else ROOT).with_suffix("").parts
        module = ".".join(rel if rel[-1] != "__init__" else rel[:-1])
        index.names.update(rel)
        tree = ast.parse(text)
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                index.names.add(node.name)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                args = [a.arg for a in (*node.args.posonlyargs, *node.args.args, *node.args.kwonlyargs)]
                index.params[node.name].append([a for a in args if a not in ("self", "cls")])
            if isinstance(node, ast.ClassDef) and inside:
                index.classes[node.name].append(module)
                for sub in ast.walk(node):
                    if isinstance(sub, (ast.FunctionDef, ast.AsyncFunctionDef)):
                        index.attrs[node.name].add(sub.name)
                    elif isinstance(sub, ast.AnnAssign) and isinstance(sub.target, ast.Name):
                        index.attrs[node.name].add(sub.target.id)
                    elif isinstance(sub, ast.Assign):
                        index.attrs[node.name].update(t.id for t in sub.targets if isinstance(t, ast.Name))
                    if isinstance(sub, ast.Attribute) and isinstance(sub.value, ast.Name) and sub.value.id == "self":
                        if isinstance(sub.ctx, ast.Store):
                            index.attrs[node.name].add(sub.attr)
            elif isinstance(node, ast.arg):
                index.names.add(node.arg)
            elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store):
                index.names.add(node.id)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store):
                index.names.add(node.attr)
            elif isinstance(node, ast.alias):
                index.names.add((node.asname or node.name).split(".")[0])
                index.names.add(node.name.split(".")[-1])
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    deps = [*pyproject["project"]["dependencies"], *sum(pyproject["project"]["optional-dependencies"].values(), [])]
    index.names.update(re.match(r"[\w.-]+", d).group() for d in deps)
    return index


# ------------------------------------------------------------------------------------------
# The command line, the Makefile and the files


@functools.cache
def cli_commands() -> dict[str, set[str]]:
    """The commands of ``kinema.cli.app``, each with its options."""
    import typer.main

    from kinema.cli import app

    group = typer.main.get_command(app)
    return {name: {o for p in cmd.params for o in p.opts} for name, cmd in group.commands.items()}


@functools.cache
def make_targets() -> set[str]:
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    return set(re.findall(r"^([\w.-]+)\s*:(?!=)", text, re.MULTILINE))


@functools.cache
def tracked() -> tuple[str, ...]:
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    return tuple(out + [p.relative_to(ROOT).as_posix() for p in (ROOT / "python" / "kinema").glob("*.so")])


def path_exists(token: str) -> bool:
    """Whether a tracked path ends with ``token`` (a file, or a folder with ``/``), or is
    ``token`` seen from docs/ (``../examples``)."""
    files = tracked()
    if token in UNTRACKED:
        return True
    if token.startswith("../"):
        token = (Path("docs") / token).resolve().relative_to(Path("docs").resolve().parent).as_posix()
    token = token.rstrip("/")
    if "*" in token:
        pattern = re.compile(re.escape(token).replace(r"\*", "[^/]*") + "$")
        return any(pattern.search(f) for f in files)
    return any(f == token or f.endswith("/" + token) or f.startswith(token + "/") or f"/{token}/" in f for f in files)


def anchors(page: Path) -> set[str]:
    slugs = set()
    for line in page.read_text(encoding="utf-8").splitlines():
        m = re.match(r"#+\s+(.*)", line)
        if m:
            title = re.sub(r"[^\w\s-]", "", m.group(1).replace("`", "")).strip().lower()
            slugs.add(re.sub(r"[\s]+", "-", title))
    return slugs


# ------------------------------------------------------------------------------------------
# Resolving one name


def resolve_python(dotted: str) -> bool:
    """Whether ``kinema.X.y``, ``World.run``, ``_core.World.sync`` or ``numpy.asarray`` exists."""
    import kinema

    parts = dotted.split(".")
    root, rest = parts[0], parts[1:]
    if root in ALIASES:
        return resolve_python(".".join([ALIASES[root], *rest]))
    candidates = []
    if root == "kinema":
        candidates.append(kinema)
    elif root == "_core":
        candidates.append(kinema._core)
    if hasattr(kinema, root):
        candidates.append(getattr(kinema, root))
    for module in python().classes.get(root, []):
        candidates.append(getattr(importlib.import_module(module), root, None))
    for name in (f"kinema.{root}", root):
        try:
            candidates.append(importlib.import_module(name))
        except ImportError:
            pass
    for obj in candidates:
        if obj is not None and _walk(obj, rest):
            return True
    return False


def _walk(obj: object, rest: list[str]) -> bool:
    for i, part in enumerate(rest):
        if hasattr(obj, part):
            obj = getattr(obj, part)
            continue
        if inspect.ismodule(obj):
            try:
                obj = importlib.import_module(f"{obj.__name__}.{part}")
                continue
            except ImportError:
                return False
        if inspect.isclass(obj) and i == len(rest) - 1:
            return any(part in python().attrs.get(c.__name__, ()) for c in obj.__mro__)
        return False
    return True


def _python_object(dotted: str) -> object | None:
    import kinema

    obj: object = kinema
    parts = dotted.split(".")
    if parts[0] in ALIASES:
        parts = [*ALIASES[parts[0]].split("."), *parts[1:]]
    if parts[0] == "kinema":
        parts = parts[1:]
    for part in parts:
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    return obj


def resolve_rust_path(path: str) -> bool:
    """Whether ``Type::member``, ``module::item`` or ``crate::a::b`` exists."""
    r = rust()
    parts = [p for p in path.split("::") if p]
    if parts[0] in ("crate", "kinema", "super", "self") and len(parts) > 1:
        parts = parts[1:]
    if parts[0] == "std":
        return True
    *prefix, last = parts
    owner = prefix[-1] if prefix else None
    if not prefix:
        return last in r.names
    if owner in r.types or owner in r.members:
        if last in r.members.get(owner, ()) or any(last in f for f in r.fields.get(owner, ())):
            return True
        if any(last in r.members.get(t, ()) for t in r.impls.get(owner, ())):
            return True
        if len(prefix) == 1:
            return False
        prefix = prefix[:-1]
        last = owner
    return any(
        module[-len(prefix) :] == tuple(prefix) and any(last in names for m, names in r.modules.items() if m[: len(module)] == module)
        for module in list(r.modules)
    )


def known_name(ident: str) -> bool:
    """Whether a bare identifier is defined (or used, as code or a string) by the code."""
    return (
        ident in rust().names
        or ident in python().names
        or ident in RUST_PRELUDE
        or hasattr(builtins, ident)
        or ident in cli_commands()
        or ident in make_targets()
        or ident in code_words()
    )


@functools.cache
def code_words() -> frozenset[str]:
    """The words the code uses that it does not define: other libraries' functions and
    classes it calls, environment variables, file names it writes, as identifiers or whole
    string literals of the Rust and Python sources (comments and docstrings left out), the
    viewer's JavaScript and the Makefile."""
    words: set[str] = set()
    for raw in rust().sources:
        words.update(re.findall(r"[A-Za-z_]\w*", blank_rust(raw)))
        literals = (m.group() for m in _RUST_NOISE.finditer(raw) if m.group().startswith(('"', 'b"')))
        words.update(m.group(1) for lit in literals if (m := re.fullmatch(r'b?"([\w.:/-]+)"', lit)))
    for path in python_files():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(d) for d in _docstrings(tree)}
        for node in ast.walk(tree):
            if isinstance(node, ast.Name):
                words.add(node.id)
            elif isinstance(node, ast.Attribute):
                words.add(node.attr)
            elif isinstance(node, ast.keyword) and node.arg:
                words.add(node.arg)
            elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                if re.fullmatch(r"[\w.:/-]+", node.value):
                    words.add(node.value)
    for path in [*sorted((ROOT / "viewer" / "src").glob("*.js")), ROOT / "Makefile"]:
        words.update(re.findall(r"[A-Za-z_][\w.]*", path.read_text(encoding="utf-8")))
    return frozenset(words)


@functools.cache
def string_literals() -> frozenset[str]:
    """Every string literal of the Rust sources and of the repository's Python (docstrings
    left out)."""
    out = {m.group()[m.group().index('"') + 1 : -1] for raw in rust().sources for m in _RUST_NOISE.finditer(raw) if m.group().startswith(('"', 'b"'))}
    for path in python_files():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        docstrings = {id(d) for d in _docstrings(tree)}
        out.update(n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and isinstance(n.value, str) and id(n) not in docstrings)
    return frozenset(out)


def _docstrings(tree: ast.AST) -> list[ast.Constant]:
    return [
        node.body[0].value
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    ]


def python_files() -> list[Path]:
    """The package's Python files, then the tests', the benchmarks' and the examples'."""
    package = ROOT / "python" / "kinema"
    files = sorted([*package.rglob("*.py"), *package.rglob("*.pyi")])
    for folder in ("tests", "benchmarks", "examples", "docs"):
        files += sorted((ROOT / folder).rglob("*.py"))
    return [f for f in files if f.resolve() != Path(__file__).resolve()]  # not this file's own names


PATHISH = re.compile(r"[A-Za-z_]\w*(?:(?:::|\.)[A-Za-z_]\w*)*(?:::\{)?")


def problems_of(name: Name) -> list[str]:
    """What is wrong with one name: empty when it resolves."""
    text = name.text.strip()
    if text in NOT_CHECKED:
        return []
    if name.kind == "link":
        target, _, anchor = text.partition("#")
        page = (DOC.parent / target).resolve() if target else DOC
        if not page.exists():
            return [f"{text}: no such page"]
        if anchor and anchor not in anchors(page):
            return [f"{text}: no such heading in {target or DOC.name}"]
        return []
    if text.startswith("```"):
        return []  # a fence line shown as an example
    if re.fullmatch(r'"[^"]*"', text):
        return [] if text[1:-1] in string_literals() else [f"{text}: no string literal of the sources is this"]
    if text.startswith("#[") or text.startswith("#!["):
        return [] if any(text in s for s in rust().sources) else [f"{text}: no Rust source has this attribute"]
    if re.fullmatch(r"kinema(?: [a-z][\w-]*)+.*", text) and not text.startswith("kinema ="):
        command = text.split()[1]
        if command in ("…", "..."):
            return []
        return [] if command in cli_commands() else [f"{text}: no such command of kinema.cli.app"]
    if re.fullmatch(r"make(?: [\w-]+)+", text):
        return [f"{text}: no such Makefile target" for t in text.split()[1:] if t not in make_targets()]
    if re.fullmatch(r"[a-z]_\w{1,2}", text):
        return []  # a subscript of a formula in a text block: m_i, u_n
    if name.kind == "word" and (text in PROPER_NOUNS or text.lower() in anchors(DOC)):
        return []  # a person, a program, a term, or a section of the page
    if text.startswith("window."):
        script = "".join(p.read_text(encoding="utf-8") for p in (ROOT / "viewer" / "src").glob("*.js"))
        missing = [part for part in text.removesuffix("()").split(".")[1:] if not re.search(rf"\b{part}\b", script)]
        return [f"{text}: {', '.join(missing)} not in viewer/src"] if missing else []
    if re.fullmatch(r"[\w.*/-]+", text) and ("/" in text or ("." in text and text.rsplit(".", 1)[-1] in SUFFIXES) or path_exists(text)):
        if path_exists(text) or (Path(text).suffix and Path(text).name in code_words()):  # a file the code writes
            return []
        return [f"{text}: no such file or folder"]
    return _problems_of_code(text)


def _problems_of_code(text: str) -> list[str]:
    r = rust()
    out: list[str] = []
    # Enum::{A, B { f, g }}: each a variant, and all of them
    for m in re.finditer(r"([A-Za-z_]\w*)::\{", text):
        enum = m.group(1)
        inner = _braced(text, m.end() - 1)
        listed = [re.match(r"\w+", p).group() for p in _split_top(inner)]
        if enum not in r.variants:
            out.append(f"{text}: {enum} is not an enum")
        elif set(listed) != set(r.variants[enum]):
            out.append(f"{text}: {enum}'s variants are {', '.join(r.variants[enum])}")
        for p in _split_top(inner):
            out += _problems_of_code(p) if "{" in p else []
        text = text[: m.start()] + enum + text[m.end() - 1 + len(inner) + 2 :]
    # Name { a, b }: exactly these fields
    for m in re.finditer(r"([A-Za-z_]\w*)\s*\{([^{}]*)\}", text):
        struct, listed = m.group(1), [f.strip() for f in m.group(2).split(",") if f.strip()]
        if not any(sorted(f) == sorted(listed) for f in r.fields.get(struct, [])):
            known = [", ".join(f) for f in r.fields.get(struct, [])]
            out.append(f"{text}: {struct}'s fields are not {', '.join(listed)} ({' / '.join(known) or 'no such struct'})")
    text = re.sub(r"\{[^{}]*\}", "", text)
    # calls with their arguments
    for m in re.finditer(r"([A-Za-z_][\w.:]*)\(([^()]*(?:\([^()]*\)[^()]*)*)\)", text):
        out += _call_problems(m.group(1), m.group(2), text)
    for m in PATHISH.finditer(re.sub(r"=\s*\"[^\"]*\"|\"[^\"]*\"|=\s*[\d.]+", "", text)):
        token = m.group().removesuffix("::{")
        if token in KEYWORDS or token in RUST_PRELUDE:
            continue
        if "::" in token:
            if not resolve_rust_path(token):
                out.append(f"{text}: {token} not found in the Rust sources")
        elif "." in token:
            if not resolve_python(token):
                out.append(f"{text}: {token} not found in the Python package")
        elif not known_name(token):
            out.append(f"{text}: {token} is defined nowhere")
    return out


def _braced(text: str, start: int, pair: str = "{}") -> str:
    """What is inside the brackets that open at ``text[start]``."""
    depth = 0
    for i in range(start, len(text)):
        depth += text[i] == pair[0]
        depth -= text[i] == pair[1]
        if depth == 0:
            return text[start + 1 : i]
    return text[start + 1 :]


def _call_problems(callee: str, args: str, text: str) -> list[str]:
    parts = _split_top(args)
    if not parts:
        return []
    if "." in callee and "::" not in callee:
        obj = _python_object(callee)
        try:
            signature = inspect.signature(obj) if obj is not None else None
        except (TypeError, ValueError):
            signature = None
        if signature is None:
            return []
        params = [p for p in signature.parameters if p != "self"]
        out = []
        for i, part in enumerate(parts):
            kw = re.match(r"([A-Za-z_]\w*)\s*=", part)
            if kw and kw.group(1) not in params:
                out.append(f"{text}: {callee} has no parameter {kw.group(1)}")
            elif not kw and re.fullmatch(r"[A-Za-z_]\w*", part) and (i >= len(params) or params[i] != part):
                out.append(f"{text}: {callee}'s parameter {i + 1} is not {part} ({', '.join(params)})")
        return out
    if not all(re.fullmatch(r"[a-z_]\w*", p) for p in parts):
        return []
    r = rust()
    name = callee.split("::")[-1]
    key = "::".join(callee.split("::")[-2:])
    signatures = r.params.get(key) or [*r.params.get(name, []), *(python().params.get(name, []) if "::" not in callee else [])]
    if callee.split("::")[-1] in r.variants.get(callee.split("::")[-2] if "::" in callee else "", []):
        return []
    signatures = [[a.lstrip("_") for a in s] for s in signatures]  # _t: a parameter left unused
    if signatures and parts not in signatures:
        shown = " or ".join(sorted({"(" + ", ".join(s) + ")" for s in signatures}))
        return [f"{text}: {callee} takes {shown}"]
    return []


def problems_in(markdown: str) -> list[str]:
    out = []
    for name in names_in(markdown):
        out += [f"line {name.line}: {p}" for p in problems_of(name)]
    return out


# ------------------------------------------------------------------------------------------
# The tests


def test_every_file_the_architecture_names_exists():
    files = tracked()
    names = {Path(f).name for f in files}
    missing = []
    for token in sorted(set(FILE.findall(DOC.read_text(encoding="utf-8")))):
        if token in NOT_FILES:
            continue
        if token.startswith("/"):
            missing.append(f"{token} (outside the repository)")
        elif "/" in token:
            if not any(f == token or f.endswith("/" + token) for f in files):
                missing.append(token)
        elif token not in names:
            missing.append(token)
    assert not missing, f"docs/architecture.md names files that do not exist: {missing}"


def test_every_code_name_the_architecture_gives_exists():
    problems = problems_in(DOC.read_text(encoding="utf-8"))
    assert not problems, "docs/architecture.md names what does not exist:\n" + "\n".join(problems)


# A page made up for the self-test: the names of its second line exist, every other one does
# not, and each of those must be reported.
MADE_UP = """\
# A page
Real: `World::step`, `kinema.World.step`, `kinema run`, `make test`, `world/mod.rs`, `Force::reindex`, `rhs(t, y, dydt)`, [this](architecture.md#layers).
`World::frobnicate`
`Force::remove_particles`
`kinema.World.frobnicate`
`frobnicate_all`
`kinema frobnicate`
`make frobnicate`
`crates/kinema/src/frobnicate.rs`
`Divergence::{NonFinite, StepTooSmall}`
`SpringDashpot { stiffness }`
`rhs(t, x, dydt)`
`"frobnicated"`
[a page](frobnicate.md)
[a heading](world.md#frobnicate)

```text
  src/frob.rs    Frobnicator, frob_nicate(), World::frobnicate, Frobnicate, FROB_LIMIT
```
"""


def test_a_made_up_name_is_reported():
    names = [n for n in names_in(MADE_UP) if n.line != 1]
    real = [n for n in names if n.line == 2]
    made_up = [n for n in names if n.line != 2]
    assert len(real) == 8 and len(made_up) == 18, [n.text for n in names]
    assert {n.text: problems_of(n) for n in real} == {n.text: [] for n in real}
    assert [n.text for n in made_up if not problems_of(n)] == []


def test_what_the_page_leaves_unchecked_is_on_the_page():
    """The exceptions do not outlive what they excuse."""
    doc = DOC.read_text(encoding="utf-8")
    given = {n.text.strip() for n in names_in(doc)}
    assert [k for k in NOT_CHECKED if k not in given] == []
    assert sorted(w for w in PROPER_NOUNS if w not in given) == []


# ------------------------------------------------------------------------------------------
# Lists the page gives whole

NUMBERS = {"two": 2, "three": 3, "four": 4, "five": 5, "six": 6, "seven": 7, "eight": 8, "nine": 9, "ten": 10}
NUMBERS |= {"eleven": 11, "twelve": 12, "thirteen": 13, "fourteen": 14, "fifteen": 15, "sixteen": 16, "seventeen": 17}


@functools.cache
def flat_doc() -> str:
    """The page with each run of white space made one space (lists wrap across lines)."""
    return re.sub(r"\s+", " ", DOC.read_text(encoding="utf-8"))


def passage(start: str, end: str) -> str:
    """The page's text between the first ``start`` and the ``end`` after it."""
    text = flat_doc()
    assert start in text, f"docs/architecture.md no longer says {start!r}"
    i = text.index(start) + len(start)
    j = text.index(end, i)
    return text[i:j]


def spans(text: str) -> list[str]:
    """The first identifier of each code span of ``text`` outside parentheses."""
    return [re.match(r"\W*(\w+)", s).group(1) for s in re.findall(r"`([^`]+)`", _strip_balanced(text, "(", ")"))]


def words(text: str) -> list[str]:
    """A written list ``a, b and c`` (or ``a | b``), parentheses left out."""
    parts = re.split(r",|;|\||\band\b", _strip_balanced(text, "(", ")"))
    return [p.strip().strip("`") for p in parts if p.strip()]


def public_classes(module: str) -> set[str]:
    tree = ast.parse((ROOT / "python" / "kinema" / module).read_text(encoding="utf-8"))
    return {n.name for n in tree.body if isinstance(n, ast.ClassDef) and not n.name.startswith("_")}


def _reasons() -> set[str]:
    code = (ROOT / "crates" / "kinema-py" / "src" / "stepping.rs").read_text(encoding="utf-8")
    return set(re.findall(r'Divergence::\w+(?:\s*\{\s*\.\.\s*\})?\s*=>\s*"([^"]+)"', code))


def _registered() -> set[str]:
    code = (ROOT / "crates" / "kinema-py" / "src" / "lib.rs").read_text(encoding="utf-8")
    return set(re.findall(r"(\w+)::register\(m\)", code))


def _particle_arrays() -> set[str]:
    code = (ROOT / "crates" / "kinema" / "src" / "particles.rs").read_text(encoding="utf-8")
    body = code[code.index("pub struct Particles {") :]
    return set(re.findall(r"pub (\w+): Vec<", body[: body.index("\n}")]))


def _phony() -> set[str]:
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    return set(re.search(r"^\.PHONY:(.*)$", text, re.MULTILINE).group(1).split())


def _io_formats() -> set[str]:
    from kinema.io import FORMATS

    return set(FORMATS)


def _fields(name: str) -> set[str]:
    (fields,) = rust().fields[name]
    return set(fields)


# (what, the page's list, the code's list): each a function, so that a missing passage
# fails its own case.
WHOLE_LISTS = {
    "Error's variants": (
        lambda: set(spans(passage("The variants:", "A callback returns"))),
        lambda: set(rust().variants["Error"]),
    ),
    "SimulationDiverged.reason's words": (
        lambda: set(re.findall(r'"([^"]+)"', passage("and `reason` (", ")"))),
        _reasons,
    ),
    "the Force trait's methods": (
        lambda: set(spans(passage("besides the force itself, and nothing more:", "**Collisions**"))) | {"name", "accumulate"},
        lambda: rust().members["Force"],
    ),
    "the Force trait's methods (layout)": (lambda: set(words(passage("mod.rs: Force (", ")"))), lambda: rust().members["Force"]),
    "the areas _core registers": (
        lambda: {s.split("::")[0] for s in re.findall(r"`(\w+)::register`", passage("and calls", ". `callbacks.rs`"))},
        _registered,
    ),
    "the areas _core registers (layout)": (lambda: set(words(passage("registers the areas (", ")"))), _registered),
    "the commands of kinema": (lambda: set(words(passage("the `kinema` command:", "("))), lambda: set(cli_commands())),
    "the Makefile's targets": (
        lambda: set(re.findall(r"[\w-]+", _strip_balanced(passage("Makefile ", "README.md"), "(", ")"))) - {"make", "also"},
        _phony,
    ),
    "MethodKind's variants": (lambda: set(spans(passage("`kind` (", ")"))), lambda: set(rust().variants["MethodKind"])),
    "the number of methods": (
        lambda: NUMBERS[re.search(r"`Method` lists the (\w+) names", flat_doc()).group(1)],
        lambda: len(rust().variants["Method"]),
    ),
    "the impulse model's stages": (
        lambda: set(words(passage("(`ImpulseStage`:", ")"))),
        lambda: {v.lower() for v in rust().variants["ImpulseStage"]},
    ),
    "the impulse model's stages (layout)": (
        lambda: set(words(passage("one step as the stage list (", ")"))),
        lambda: {v.lower() for v in rust().variants["ImpulseStage"]},
    ),
    "StageTimes' fields": (lambda: set(words(passage("`StageTimes`:", "(the impulse"))), lambda: _fields("StageTimes")),
    "CollisionParams' fields": (lambda: set(words(passage("`CollisionParams` (", ")"))), lambda: _fields("CollisionParams")),
    "CollisionStats' fields": (lambda: set(words(passage("`CollisionStats` —", "—"))), lambda: _fields("CollisionStats")),
    "ContactModel's variants": (lambda: set(spans(passage("`ContactModel` (", ";"))), lambda: set(rust().variants["ContactModel"])),
    "the particles' arrays": (
        lambda: {w.removeprefix("with spin ") for w in words(passage("Particles: struct of arrays (", ")"))},
        _particle_arrays,
    ),
    "the files of world/": (
        lambda: NUMBERS[re.search(r"`world` is a directory of (\w+) files", flat_doc()).group(1)],
        lambda: len(list((ROOT / "crates" / "kinema" / "src" / "world").glob("*.rs"))),
    ),
    "the classes of forces.py": (
        lambda: set(re.findall(r"\b[A-Z]\w+", passage("forces.py ", " (descriptions"))),
        lambda: public_classes("forces.py"),
    ),
    "the classes of colliders.py": (
        lambda: set(re.findall(r"\b[A-Z]\w+", passage("colliders.py ", " checkpoint.py"))) & (public_classes("colliders.py") | {"World"}) - {"World"},
        lambda: public_classes("colliders.py"),
    ),
    "the export formats": (lambda: set(spans(passage("The formats today:", "1."))), _io_formats),
}


@pytest.mark.parametrize("what", sorted(WHOLE_LISTS))
def test_a_list_the_page_gives_whole_is_the_code_s_list(what):
    page, code = WHOLE_LISTS[what]
    assert page() == code(), f"docs/architecture.md gives {what} as {page()}, the code has {code()}"


# ------------------------------------------------------------------------------------------
# The layout and the layers


def test_the_layout_names_every_source_file():
    """Every file of the engine, the binding, the package and the benchmarks is on the
    layout (a folder's ``mod.rs`` or ``__init__.py`` by its folder)."""
    layout = re.sub(r"\s+", " ", passage("## Repository layout", "## The `ode` module"))
    kinds = (".rs", ".py", ".pyi", ".toml", ".html", ".js")
    files = [f for f in tracked() if f.endswith(kinds) and re.match(r"crates/[^/]+/(src|tests|benches)/|python/kinema/|benchmarks/[^/]+\.py$", f)]
    missing = []
    for f in files:
        path = Path(f)
        named = [path.name]
        if path.name in ("mod.rs", "__init__.py"):
            named = [f"{path.parent.name}/{path.name}", f"{path.parent.name}/"]
        if not any(re.search(rf"(?<![\w.-]){re.escape(n)}(?![\w-])", layout) for n in named):
            missing.append(f)
    assert missing == [], f"docs/architecture.md's layout leaves out {missing}"


def _without_tests(code: str) -> str:
    """Rust code (blanked) without its ``#[cfg(test)]`` items."""
    while (i := code.find("#[cfg(test)]")) >= 0:
        rest = code[i + len("#[cfg(test)]") :]
        semi, brace = rest.find(";"), rest.find("{")
        if brace < 0 or 0 <= semi < brace:
            end = i + len("#[cfg(test)]") + semi + 1
        else:
            end = i + len("#[cfg(test)]") + brace + len(_braced(rest, brace)) + 2
        code = code[:i] + code[end:]
    return code


def engine_uses() -> set[tuple[str, str]]:
    """(module, module it uses) among the engine's top-level modules, read from ``crate::``
    paths outside comments, strings and tests (a root re-export counted as its module)."""
    src = ROOT / "crates" / "kinema" / "src"
    lib = (src / "lib.rs").read_text(encoding="utf-8")
    home = {name: module for module, names in re.findall(r"pub use (\w+)::\{?([^;}]+)", lib) for name in re.findall(r"\w+", names)}
    edges = set()
    for path in src.rglob("*.rs"):
        rel = path.relative_to(src)
        if "tests" in rel.parts or path.name in ("oracles.rs", "lib.rs"):
            continue
        top = rel.parts[0].removesuffix(".rs")
        for used in re.findall(r"\bcrate::(\w+)", _without_tests(blank_rust(path.read_text(encoding="utf-8")))):
            used = home.get(used, used)
            if used != top:
                edges.add((top, used))
    return edges


def test_the_engine_s_layers_are_as_the_page_draws_them():
    """The box of the engine in "Layers" lists each module above those it uses; the sentence
    under it names every use upward."""
    doc = DOC.read_text(encoding="utf-8")
    start = doc.index("crates/kinema  (the engine")
    box = doc[start : doc.index("```", start)]
    order = re.findall(r"^ {10}(\w+)(?:\.rs|/)\s", box, re.MULTILINE)  # a module's own line
    lib = (ROOT / "crates" / "kinema" / "src" / "lib.rs").read_text(encoding="utf-8")
    assert sorted(order) == sorted(re.findall(r"^\s*(?:pub(?:\([^)]*\))?\s+)?mod (\w+);", lib, re.MULTILINE))
    sentence = passage("uses only the modules below it in this box", ". `render/`")
    said = set(re.findall(r"`(\w+)(?:\.rs|/)?` uses `(\w+)`", sentence))
    upward = {(a, b) for a, b in engine_uses() if order.index(b) < order.index(a)}
    assert upward == said, f"uses upward in the code: {sorted(upward)}; on the page: {sorted(said)}"
