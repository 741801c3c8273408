"""The whole scene file, ``Scene`` (read from TOML, text or a dict, validated, written back),
``SceneError`` and the one-line-per-problem messages made of pydantic's errors. The tables
the scene holds are in ``kinema.scene.tables``; turning a scene into a World is
``kinema.scene.build``'s ``build``, which ``Scene.build`` calls through the one hook below
(``BUILDERS``): this module knows nothing of ``World`` (tests/test_no_import_circles.py).

Why a hook: a scene makes a World (``scene.build()``) and a world makes a scene
(``World.to_scene``, ``World.load_checkpoint``), so whichever of the two methods imports the
other class's module closes the circle schema -> build -> world -> scene.export -> schema. The
dependency is turned round instead, as a plug-in registers itself: ``kinema.scene.build``
imports this module and puts its ``build`` in ``BUILDERS`` when it is imported (the package
imports it, so every ``Scene`` builds); ``Scene.build`` is written here, in its class, and
calls what is there."""

from __future__ import annotations

import difflib
import math
import os
import re
import stat
import tomllib
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field, ValidationError, model_validator

from .tables import (
    MAX_NESTING,
    AnalysisTable,
    AttractorForce,
    Block,
    BoxCollider,
    Camera2DTable,
    Camera3DTable,
    ColliderItem,
    CollisionsTable,
    DragForce,
    EmitterTable,
    FileBlock,
    ForceItem,
    GravityForce,
    KeyframesMotion,
    KillItem,
    LatticeBlock,
    ListBlock,
    MeshCollider,
    OutputTable,
    PlaneCollider,
    RandomBlock,
    RenderTable,
    SphereCollider,
    SpringForce,
    SteadyMotion,
    WindForce,
    WorldTable,
    _Model,
)

#: What turns a scene into a World: ``{"world": kinema.scene.build.build}``, put here by that
#: module when it is imported (the module doc says why a hook and not an import).
BUILDERS: dict[str, Any] = {}

#: The largest scene file read, in bytes: a scene describes particles by blocks; even a list
#: of a million positions is ~60 MB of TOML.
SCENE_MAX_BYTES = 256 * 2**20


class SceneError(ValueError):
    """A scene that cannot be read or built. The message has one line per problem:
    ``<file>: <key path>: <value> is invalid: <what is allowed>``."""

    __module__ = "kinema"


# -- the scene --------------------------------------------------------------------------------


class Scene(_Model):
    """A whole simulation; see docs/scenes.md for every key."""

    world: WorldTable = Field(default_factory=WorldTable)
    particles: list[Block] = Field(default_factory=list)
    forces: list[ForceItem] = Field(default_factory=list)
    colliders: list[ColliderItem] = Field(default_factory=list)
    emitters: list[EmitterTable] = Field(default_factory=list)
    kill_volumes: list[KillItem] = Field(default_factory=list)
    collisions: CollisionsTable | None = None
    render: RenderTable = Field(default_factory=RenderTable)
    output: OutputTable = Field(default_factory=OutputTable)
    analysis: AnalysisTable | None = None

    @model_validator(mode="after")
    def _references(self) -> Scene:
        for f in self.forces:
            if isinstance(f, SpringForce) and f.block is not None and f.block >= len(self.particles):
                raise ValueError(f"a spring names block = {f.block}, but the scene has {len(self.particles)} [[particles]] blocks")
        camera, dim = self.render.camera, self.world.dim
        for k, c in enumerate(self.colliders):
            if isinstance(c, MeshCollider) and dim != 3:
                raise ValueError(f"colliders[{k}].type: 'mesh' is invalid: a triangle mesh is a 3D collider, and this is a {dim}D world (world.dim = {dim})")
            if dim == 2 and c.motion is not None:
                problem = _planar_problem(c.motion)
                if problem is not None:
                    raise ValueError(
                        f"colliders[{k}].motion.{problem} is invalid: in a 2D world (world.dim = 2) a collider moves in the xy-plane and turns about z"
                    )
        if self.analysis is not None:
            if self.analysis.needs_contacts and "contacts" in self.output.model_fields_set and not self.output.contacts:
                raise ValueError(
                    f"output.contacts: false is invalid with analysis.measures {self.analysis.needs_contacts[0]!r}: it needs each frame's contacts, "
                    "which an [analysis] table records; remove output.contacts = false, or that measure"
                )
            if self.analysis.axis == "z" and dim == 2:
                raise ValueError("analysis.axis: 'z' is invalid: a 2D world (world.dim = 2) has the axes x and y")
            if self.analysis.needs_contacts and not self.output.contacts:
                self.output.contacts = True  # the measures read the recorded contacts (and the file keeps them)
        if camera is not None and camera.type != f"{dim}d":
            raise ValueError(f"render.camera.type: '{camera.type}' is invalid: a {dim}D world (world.dim = {dim}) needs a '{dim}d' camera")
        return self

    # reading -----------------------------------------------------------------------------
    @classmethod
    def from_toml(cls, path: str | Path) -> Scene:
        """Read and validate a scene file; raises ``SceneError`` (one line per problem)."""
        path = Path(path)
        if not path.exists():
            raise SceneError(f"{path}: no such file")
        if path.is_dir():
            raise SceneError(f"{path}: is a directory, not a scene file (.toml)")
        # Only a regular file, and one of a sane size: a FIFO blocked the reader forever and
        # /dev/zero was read to 3.8 GB (issue 26). Opened without blocking, checked on the
        # open descriptor (what is read is what was checked), read at most one byte past the
        # limit.
        try:
            fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
        except OSError as e:
            raise SceneError(f"{path}: cannot be read ({e.strerror or e})") from None
        from ..io._files import special_kind

        with os.fdopen(fd, "rb") as f:
            mode = os.fstat(fd).st_mode
            if not stat.S_ISREG(mode):
                kind = special_kind(mode) or "special file"
                raise SceneError(f"{path}: is not a regular file (a {kind}); a scene is a .toml file")
            try:
                data = f.read(SCENE_MAX_BYTES + 1)
            except OSError as e:
                raise SceneError(f"{path}: cannot be read ({e.strerror or e})") from None
        if len(data) > SCENE_MAX_BYTES:
            raise SceneError(f"{path}: is larger than {SCENE_MAX_BYTES // 2**20} MiB; a scene file describes particles by blocks, it does not list millions")
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError as e:
            raise SceneError(f"{path}: cannot be read ({e})") from None
        scene = cls.from_string(text, source=str(path))
        # A file block's relative path (a mesh's file) names a file beside the scene file: made absolute here,
        # so that the scene builds from any working folder and writes back (to_toml) as one
        # that does.
        for block in scene.particles:
            if isinstance(block, FileBlock) and not os.path.isabs(block.path):
                block.path = os.path.abspath(os.path.join(path.parent, block.path))
        for collider in scene.colliders:  # a mesh's file too
            if isinstance(collider, MeshCollider) and collider.file is not None and not os.path.isabs(collider.file):
                collider.file = os.path.abspath(os.path.join(path.parent, collider.file))
        for emitter in scene.emitters:  # and an emitter's mesh's
            if emitter.mesh is not None and emitter.mesh.file is not None and not os.path.isabs(emitter.mesh.file):
                emitter.mesh.file = os.path.abspath(os.path.join(path.parent, emitter.mesh.file))
        return scene

    @classmethod
    def from_string(cls, text: str, source: str = "<scene>") -> Scene:
        """Validate a scene given as TOML text; ``source`` names it in messages."""
        try:
            data = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise SceneError(f"{source}: TOML syntax error: {e}") from None  # the message has "(at line L, column C)"
        except ValueError as e:  # an integer of more than 4300 digits
            raise SceneError(f"{source}: cannot be read as TOML: {e}") from None
        except RecursionError:  # arrays or inline tables nested hundreds deep
            raise SceneError(_too_deep_in_text(text, source)) from None
        return cls.from_dict(data, source)

    @classmethod
    def from_dict(cls, data: dict, source: str = "<scene>") -> Scene:
        deep = _too_deep(data, source)
        if deep is not None:
            raise SceneError(deep)
        try:
            return cls.model_validate(data)
        except ValidationError as e:
            raise SceneError("\n".join(_describe_all(e.errors(), source))) from None

    # size --------------------------------------------------------------------------------
    def particle_count(self) -> int:
        """How many particles ``build`` makes, counted without making them (a file block's file
        is read, once: its frame's particles are counted). A file that cannot be read is a
        ``SceneError`` naming the block."""
        total = 0
        for k, b in enumerate(self.particles):
            try:
                total += block_size(b)
            except ValueError as e:
                raise SceneError(f"particles[{k}]: {e}") from None
        return total

    def emitted_count(self, seconds: float) -> int:
        """How many particles the emitters give in the first ``seconds`` of a run (births at
        start + k / rate, k = 0, 1, ..., before ``end``), counted without making them."""
        total = 0
        for e in self.emitters:
            until = min(e.end, seconds)
            if until >= e.start:
                count = math.floor((until - e.start) * e.rate) + 1
                if math.isfinite(e.end):
                    count = min(count, math.ceil((e.end - e.start) * e.rate))
                total += count
        return total

    # writing -----------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """Plain data, ``None`` values left out (TOML has no null)."""
        return self.model_dump(mode="python", exclude_none=True)

    def to_toml_string(self) -> str:
        import tomli_w

        return tomli_w.dumps(self.to_dict())

    def to_toml(self, path: str | Path) -> Path:
        """Write the scene as TOML under a temporary name, then rename; returns the path."""
        from ..io._files import atomic_file

        path = Path(path)
        text = self.to_toml_string()
        with atomic_file(path) as tmp:
            tmp.write_text(text, encoding="utf-8")
        return path

    # building --------------------------------------------------------------------------
    def build(self, source: str = "<scene>") -> Any:
        """The ``kinema.World`` this scene describes (``world.scene`` is this scene). An engine
        refusal (a 2D scene with z ≠ 0, a spring index out of range, ...) is a ``SceneError``
        naming the entry. (``kinema.scene.build.build`` makes it: the module doc says why
        through ``BUILDERS``.)"""
        return BUILDERS["world"](self, source)


def _planar_problem(motion: Any) -> str | None:
    """``"<key> = <value>"`` of the first value of a collider's motion that leaves the xy-plane
    (a velocity or translation with z ≠ 0, a turn about x or y), else None."""
    if isinstance(motion, SteadyMotion):
        checks = [("velocity", motion.velocity, (2,)), ("angular_velocity", motion.angular_velocity, (0, 1))]
    else:
        checks = [(f"translations[{k}]", row, (2,)) for k, row in enumerate(motion.translations or [])]
        checks += [(f"rotations[{k}]", row, (0, 1)) for k, row in enumerate(motion.rotations or [])]
    for name, value, axes in checks:
        if any(a < len(value) and value[a] != 0 for a in axes):
            return f"{name} = {value}"
    return None


def block_size(block: Any) -> int:
    """The particles of one [[particles]] block, counted without making them (a file block reads
    its file; a ``ValueError`` when it cannot)."""
    if isinstance(block, ListBlock):
        return len(block.positions)
    if isinstance(block, LatticeBlock):
        return math.prod(block.counts)
    if isinstance(block, FileBlock):
        return len(block.particles()["positions"])
    return block.count


# -- errors -----------------------------------------------------------------------------------


def _describe_all(errors: list[dict], source: str) -> list[str]:
    """One line per mistake: the keys missing from one table and the unknown keys in it are
    one mistake (``radius = {a = 1}`` gave three lines: min missing, max missing, a unknown),
    said on one line for the table; every other error is its own line."""
    tables: dict[tuple, list[dict]] = {}
    for err in errors:
        if err["type"] in ("missing", "extra_forbidden") and len(err["loc"]) > 1:
            tables.setdefault(tuple(err["loc"][:-1]), []).append(err)
    lines, said = [], set()
    for err in errors:
        key = tuple(err["loc"][:-1])
        group = tables.get(key, [])
        if len(group) < 2 or not any(e["type"] == "extra_forbidden" for e in group):
            lines.append(_describe(err, source))
            continue
        if key in said:
            continue
        said.add(key)
        missing = [str(e["loc"][-1]) for e in group if e["type"] == "missing"]
        unknown = [str(e["loc"][-1]) for e in group if e["type"] == "extra_forbidden"]
        allowed = _allowed_keys(group[[e["type"] for e in group].index("extra_forbidden")]["loc"])
        loc = [p for p in key if not (isinstance(p, str) and p.startswith("~"))]
        words = [f"unknown key{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}"]
        if missing:
            words.append(f"missing {', '.join(missing)}")
        hint = f" (allowed keys here: {', '.join(allowed)})" if allowed else ""
        lines.append(f"{source}: {_path(loc)}: {'; '.join(words)}{hint}")
    return lines


def _describe(err: dict, source: str) -> str:
    """One line for one pydantic error: file, key path, value, what is allowed."""
    loc = [p for p in err["loc"] if not (isinstance(p, str) and p.startswith("~"))]
    path = _path(loc)
    kind = err["type"]
    msg = err["msg"].removeprefix("Value error, ")
    if kind == "extra_forbidden":
        allowed = _allowed_keys(err["loc"])
        hint = ""
        if allowed:
            close = difflib.get_close_matches(str(loc[-1]), allowed, n=1)
            hint = (f"; did you mean {close[0]!r}?" if close else "") + f" allowed keys here: {', '.join(allowed)}"
        return f"{source}: {path}: unknown key{hint}"
    if kind == "missing":
        return f"{source}: {path}: missing: a value is required"
    if not loc and kind == "value_error":  # Scene's own checks across tables: the message names the keys
        return f"{source}: {msg}"
    value = err.get("input")
    shown = repr(value) if not isinstance(value, dict | list) or len(repr(value)) < 60 else repr(value)[:57] + "..."
    msg = msg[0].lower() + msg[1:] if msg[:1].isupper() and not msg[1:2].isupper() else msg
    return f"{source}: {path}: {shown} is invalid: {msg}"


def _path(loc: list) -> str:
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "(top level)"


def _preview(value: Any, width: int = 40) -> str:
    """The start of a value's repr, made without recursing (repr itself fails on deep values)."""
    out = ""
    while len(out) < width:
        if isinstance(value, list):
            out += "["
            if not value:
                out += "]"
                break
            value = value[0]
        elif isinstance(value, dict):
            out += "{"
            if not value:
                out += "}"
                break
            key, value = next(iter(value.items()))
            out += f"{key!r}: "
        else:
            out += repr(value)
            break
    return out[:width] + "..."


def _too_deep(data: Any, source: str) -> str | None:
    """A line naming the first value nested more than MAX_NESTING deep, or None."""
    stack: list[tuple[Any, list]] = [(data, [])]
    while stack:
        value, loc = stack.pop()
        if len(loc) > MAX_NESTING:
            where = _path(loc[:6]) + "..."  # the key, and the start of the path inside it
            return f"{source}: {where}: {_preview(value)} is invalid: arrays and tables nested more than {MAX_NESTING} levels deep are refused"
        if isinstance(value, dict):
            stack.extend((v, [*loc, k]) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, [*loc, k]) for k, v in enumerate(value) if isinstance(v, list | dict))
    return None


_TOKEN = re.compile(r'"""|\'\'\'|["\'#\n\[\]{}=]')
_STRING_END = {  # from just after the opening quotes to just after the closing ones
    '"': re.compile(r'(?:[^"\\\n]|\\.)*"?'),
    "'": re.compile(r"[^'\n]*'?"),
    '"""': re.compile(r'(?:[^"\\]|\\.|"(?!""))*(?:"""|$)', re.S),
    "'''": re.compile(r"(?:[^']|'(?!''))*(?:'''|$)", re.S),
}


def _too_deep_in_text(text: str, source: str) -> str:
    """The line for a TOML text too deep for the parser: the line and key where arrays or inline
    tables first nest more than MAX_NESTING deep (strings and comments skipped)."""
    depth, line, pos, key, start, table = 0, 1, 0, "", 0, ""
    seen: dict[str, int] = {}  # [[name]] headers so far, for the index of the next one
    while (m := _TOKEN.search(text, pos)) is not None:
        t, pos = m.group(), m.end()
        if t == "[" and depth == 0 and not text[start : m.start()].strip():  # a [table] or [[array]] header
            header = re.match(r"(\[\[?)\s*([^\]\n]*?)\s*\]", text[m.start() :])
            if header is not None:
                table = header.group(2)
                if header.group(1) == "[[":
                    seen[table] = seen.get(table, -1) + 1
                    table += f"[{seen[table]}]"
                pos = m.start() + header.end()
                continue
        if t in _STRING_END:
            stop = _STRING_END[t].match(text, pos).end()
            line += text.count("\n", pos, stop)
            pos = stop
        elif t == "#":
            end = text.find("\n", pos)
            pos = len(text) if end < 0 else end
        elif t == "\n":
            line += 1
            start = pos
        elif t == "=" and depth == 0:
            key = ".".join(filter(None, (table, text[start : m.start()].strip())))
        elif t in "[{":
            depth += 1
            if depth > MAX_NESTING:
                head = text[m.start() - MAX_NESTING + 1 : m.start() + 1].lstrip()
                return (
                    f"{source}: line {line}: {key or '(top level)'}: {head}... is invalid: arrays and tables nested more than {MAX_NESTING} levels deep"
                    " are refused"
                )
        elif t in "]}":
            depth = max(0, depth - 1)
    return f"{source}: arrays or tables are nested too deep to read (more than {MAX_NESTING} levels deep are refused)"


_TAGGED = {
    f"~{m.model_fields['type'].default}": m
    for m in (
        ListBlock,
        LatticeBlock,
        RandomBlock,
        FileBlock,
        GravityForce,
        DragForce,
        SpringForce,
        AttractorForce,
        WindForce,
        PlaneCollider,
        BoxCollider,
        SphereCollider,
        MeshCollider,
        Camera2DTable,
        Camera3DTable,
    )
}
_TAGGED.update({"~steady": SteadyMotion, "~keyframes": KeyframesMotion})  # a collider's motion, told apart by its times


def _allowed_keys(loc: tuple) -> list[str]:
    """The keys of the table that holds the unknown key at ``loc``."""
    cls: Any = Scene
    for part in loc[:-1]:
        if isinstance(part, int) or part in ("~dict", "~list", "~scalar", "~vectors"):
            continue
        if part in _TAGGED:
            cls = _TAGGED[part]
            continue
        field = cls.model_fields.get(part) if isinstance(cls, type) and issubclass(cls, BaseModel) else None
        if field is None:
            return []
        cls = _model_in(field.annotation)
    return sorted(cls.model_fields) if isinstance(cls, type) and issubclass(cls, BaseModel) else []


def _model_in(annotation: Any) -> Any:
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()) or ():
        found = _model_in(arg)
        if found is not None:
            return found
    return None
