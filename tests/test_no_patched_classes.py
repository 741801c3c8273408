"""One snapshot (issue 50): a class's methods are in its class's body, and a world's state is
read and written through one object.

- No module of the package gives a method or an attribute to a class (or any object) it
  imported from another module of the package (`World.to_scene = to_scene`). `Scene.build`
  is written in `Scene`'s body and calls the builder `kinema.scene.build` registers
  (`schema.BUILDERS`: a scene makes a world and a world a scene, so the schema cannot import
  the world without a circle; the schema's module doc).
- The modules that write, read and export a world (`kinema.checkpoint` and its readers
  `kinema._checkpoint_reader`, `_checkpoint_world`, `_checkpoint_run`; `kinema.scene.export`,
  `kinema.scene.build`), and those that read it for a step's checks,
  add to it or run it (`kinema.first_step`, `kinema.emitter`, `kinema.runner` and its
  `kinema._run_source`), use none of
  the World's private attributes (`world._core`, `world._death`, `world._push()`, ...) but
  its state accessor and the run loop a resumed run goes on with: `World._state()` and
  `World._restore(state)` (`kinema._state.WorldState`), `World._record`. (The recorder of
  `kinema.trajectory`, which the world's run loop drives, reads it through the state too, and
  through the methods made for it: `_diagnostics_as_pulled` and the like.)

The scans read the source's syntax trees; `test_the_scans_find_what_there_was` shows that both
find what the code had before (`git show d725df4:python/kinema/scene/export.py`, and the
reaches of that commit's checkpoint.py)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "python" / "kinema"

# (the module, the object it imported, the attribute it gives it): and why, in the module's doc
ALLOWED_PATCHES: set[tuple[str, str, str]] = set()
# what of a World's private names the checkpoints, the export and the builder may use
STATE_ACCESS = {"_state", "_restore", "_record"}
WORLD_READERS = (
    "checkpoint.py",
    "_checkpoint_reader.py",
    "_checkpoint_world.py",
    "_checkpoint_run.py",
    "scene/export.py",
    "scene/build.py",
    "first_step.py",
    "emitter.py",
    "runner.py",
    "_run_source.py",  # (runner.py's: the run's source given to the world)
)


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")


def patches(source: str, module: str) -> set[tuple[str, str, str]]:
    """(module, name, attribute) for each assignment `name.attribute = ...` (or
    `setattr(name, "attribute", ...)`) in `source` where `name` was imported from a module of
    the package (a relative import, or one from `kinema`)."""
    tree = ast.parse(source)
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.level > 0 or (node.module or "").split(".")[0] == "kinema"):
            imported |= {a.asname or a.name for a in node.names}
    found = set()
    for node in ast.walk(tree):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "setattr" and len(node.args) >= 2:
            obj, name = node.args[0], node.args[1]
            if isinstance(obj, ast.Name) and obj.id in imported:
                found.add((module, obj.id, name.value if isinstance(name, ast.Constant) else ast.unparse(name)))
        for target in targets:
            for t in ast.walk(target):
                if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name) and t.value.id in imported:
                    found.add((module, t.value.id, t.attr))
    return found


def world_private_names() -> set[str]:
    """The private names of a World: its methods and properties and the attributes it sets on
    itself (`self._x = ...`), in world.py and in each of its bases of the package (the mixins
    `WorldCollisions` of world_collisions.py, `WorldViews` of _world_views.py, ...), each read
    from its own module's file."""
    import inspect

    from kinema.world import World

    names = set()
    for klass in (k for k in World.__mro__ if k.__module__.startswith("kinema.")):
        tree = ast.parse(Path(inspect.getsourcefile(klass)).read_text(encoding="utf-8"))
        for cls in (n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == klass.__name__):
            for node in ast.walk(cls):
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    names.add(node.name)
                elif isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "self" and isinstance(node.ctx, ast.Store):
                    names.add(node.attr)
    return {n for n in names if n.startswith("_") and not n.startswith("__")}


def world_reaches(source: str, private: set[str]) -> list[str]:
    """`name._x` (`_x` one of the World's private names `private`) in `source`, `self` left out:
    each as written, with its line."""
    out: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Attribute) and node.attr in private:
            if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                continue
            out.append((node.lineno, f"{node.lineno}: {ast.unparse(node)}"))
    return [text for _, text in sorted(out)]


def test_no_module_gives_a_class_of_another_its_methods():
    found = set()
    for path in sorted(PACKAGE.rglob("*.py")):
        found |= patches(path.read_text(encoding="utf-8"), _module_name(path))
    assert found == ALLOWED_PATCHES


def test_the_world_s_methods_are_in_its_class():
    """`World.to_scene`, `save_checkpoint`, `load_checkpoint` and `scene` are written in the
    class's body (a grep of world.py finds them), and so is `Scene.build` in `Scene`'s, which
    calls the builder kinema.scene.build registered."""
    import kinema
    from kinema.world import World

    assert {"to_scene", "save_checkpoint", "load_checkpoint", "scene", "_state", "_restore"} <= set(vars(World))
    assert World.scene is None and kinema.World().scene is None
    assert isinstance(vars(World)["load_checkpoint"], staticmethod)
    from kinema.scene import build, schema

    assert "build" in vars(schema.Scene)
    assert schema.BUILDERS == {"world": build.build}


def test_the_checkpoints_and_the_scene_export_use_the_world_s_state_only():
    private = world_private_names()
    assert {"_core", "_push", "_colors", "_emitters"} <= private
    for file in WORLD_READERS:
        reaches = world_reaches((PACKAGE / file).read_text(encoding="utf-8"), private)
        assert {r.split(".")[-1].split("(")[0] for r in reaches} <= STATE_ACCESS, f"{file}: {reaches}"


OLD_EXPORT_TAIL = """
from ..world import World
from ..checkpoint import load_checkpoint, save_checkpoint


def to_scene(world: World):
    inverse = world._core.inverse_masses
    for source in world._emitters:
        pass
    return world._spring_rest


World.to_scene = to_scene  # ``world.to_scene()``; the world module stays free of the scene format
World.save_checkpoint = save_checkpoint  # ``world.save_checkpoint(path)`` (kinema.checkpoint)
World.load_checkpoint = staticmethod(load_checkpoint)  # ``kinema.World.load_checkpoint(path)``
World.scene = None  # a world made in code has no scene; ``load_scene`` sets it on the instance
setattr(World, "to_scene", to_scene)
"""


def test_the_scans_find_what_there_was():
    """Both scans fail on what the code had before issue 50's snapshot (commit d725df4): its
    export's last lines (the World methods it gave the class) and the private attributes its
    export and checkpoint read."""
    found = patches(OLD_EXPORT_TAIL, "kinema.scene.export")
    assert found == {("kinema.scene.export", "World", a) for a in ("to_scene", "save_checkpoint", "load_checkpoint", "scene")}
    reaches = world_reaches(OLD_EXPORT_TAIL, world_private_names())
    assert reaches == ["7: world._core", "8: world._emitters", "10: world._spring_rest"]
    old_checkpoint = "world._push()\ncore = world._core\nf.attrs['warned'] = world._warned\nworld._new_views()\nw = world._state()\n"
    reaches = world_reaches(old_checkpoint, world_private_names())
    assert {r.split(".")[-1].split("(")[0] for r in reaches} - STATE_ACCESS == {"_push", "_core", "_warned", "_new_views"}
