"""Every code block of README.md and docs/*.md is a test: a page's Python blocks run in order
in a fresh process, and the output a page shows for a block is compared with what it prints.

The conventions, in the fence line of a block (docs/architecture.md, "Documentation"):

- ```` ```python ````: runs. The blocks of a page run in the order of the page, as one
  script (``__main__``, so that a ``if __name__ == "__main__":`` guard is entered), in a fresh
  Python process whose working directory is a new temporary folder holding a link to the
  repository's ``examples/``: a page's blocks are one continuous example, and a name one
  block defines is there for the next ones.
- ```` ```python {.skip reason="..."} ````: does not run, and says why beside it (a Slurm
  cluster, a GPU); a ``skip`` without a reason fails.
- ```` ```toml {file="camera.toml"} ```` (any language): the block is written to that file
  in the working folder before the page runs, for the Python blocks that read it.
- ```` ```text {.output} ```` right after a Python block: what that block prints, compared
  with ``doctest``'s checker (``...`` stands for any text; runs of spaces and newlines
  compare as one space). Other ```` ```text ```` blocks (formulas, tables, shell sessions)
  are prose.

The options are an attribute list in braces, which GitHub shows as the language's block and
the documentation site (pymdownx.superfences) renders as code; anything else after the
language is refused (the site would print the block as one line of inline code).

The page's blocks are parsed by markdown-it-py (CommonMark, the parser rich uses), not by
regular expressions, so fences inside lists and indented fences count as the reader sees them.
"""

from __future__ import annotations

import doctest
import os
import re
import subprocess
import sys
import tempfile
import textwrap
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
MARK = "@@kinema-docs-block@@"  # printed between blocks, to split what each printed
TIMEOUT = 600  # s, per page


@dataclass
class Block:
    line: int  # 1-based line of the fence in the page
    code: str
    skip: str | None = None  # the reason, when skipped
    output: str | None = None  # what the page shows it prints


OPTION = re.compile(r'\.([\w-]+)|([\w-]+)="([^"]*)"')


def fences(page: Path) -> Iterator[tuple[int, str, set[str], dict[str, str], str]]:
    """Each fence of the page: its line (1-based), language, classes and key="value" options
    (``{.skip reason="..."}``), and text."""
    for token in MarkdownIt("commonmark").parse(page.read_text(encoding="utf-8")):
        if token.type != "fence":
            continue
        line = token.map[0] + 1 if token.map else 0
        lang, _, rest = token.info.strip().partition(" ")
        rest = rest.strip()
        classes: set[str] = set()
        options: dict[str, str] = {}
        if rest:
            inside = rest[1:-1] if rest.startswith("{") and rest.endswith("}") else None
            if inside is None or OPTION.sub("", inside).strip():
                raise AssertionError(
                    f'{page.name}:{line}: fence options {rest!r}: write them in braces, {{.skip reason="..."}}, {{.output}} or {{file="name"}}'
                )
            for cls, key, value in OPTION.findall(inside):
                if cls:
                    classes.add(cls)
                else:
                    options[key] = value
        yield line, lang, classes, options, token.content


def files(page: Path) -> dict[str, str]:
    """The page's blocks marked ``{file="<name>"}`` (any language), by name."""
    out = {}
    for line, _, _, options, text in fences(page):
        if "file" in options:
            name = options["file"]
            if not name or "/" in name or name in out:
                raise AssertionError(f"{page.name}:{line}: file={name!r}: a new plain file name")
            out[name] = text
    return out


def blocks(page: Path) -> list[Block]:
    """The page's Python blocks with their skip reasons and shown output, in page order."""
    found: list[Block] = []
    last: Block | None = None
    for line, lang, classes, options, text in fences(page):
        known = {"python": ({"skip"}, {"reason"}), "text": ({"output"}, {"file"})}.get(lang, (set(), {"file"}))
        if classes - known[0] or set(options) - known[1]:
            raise AssertionError(f"{page.name}:{line}: unknown fence option in {lang} {{{' '.join(sorted(classes | set(options)))}}}")
        if lang == "python":
            reason = options.get("reason", "").strip()
            if "skip" in classes and not reason:
                raise AssertionError(f'{page.name}:{line}: a skipped block needs its reason: {{.skip reason="<why>"}}')
            if reason and "skip" not in classes:
                raise AssertionError(f"{page.name}:{line}: a reason without .skip")
            last = Block(line, text, reason or None)
            found.append(last)
            continue
        if "output" in classes:
            if last is None or last.output is not None:
                raise AssertionError(f"{page.name}:{line}: a {{.output}} block must follow the Python block it shows")
            last.output = text
        else:
            last = None
    return found


def script(page_blocks: list[Block]) -> str:
    """The page's runnable blocks as one script, printing MARK after each."""
    parts = ["import matplotlib\nmatplotlib.use('Agg')\n"]
    for b in page_blocks:
        if b.skip is None:
            parts.append(b.code)
            # (only in the script itself: worker processes that import it, a sweep's, print nothing)
            parts.append(f"if __name__ == '__main__':\n    print({MARK!r}, flush=True)\n")
    return "\n".join(parts)


def problems(page: Path) -> list[str]:
    """Runs the page's blocks (see the module doc); what went wrong, one text each."""
    page_blocks = blocks(page)
    runnable = [b for b in page_blocks if b.skip is None]
    for b in runnable:
        try:
            compile(b.code, f"{page.name}:{b.line}", "exec")
        except SyntaxError as e:
            return [f"{page.name}: the block at line {b.line} is not Python: {e.msg} (its line {e.lineno}: {(e.text or '').strip()})"]
    with tempfile.TemporaryDirectory(prefix="kinema-docs-") as work:
        os.symlink(ROOT / "examples", Path(work) / "examples")
        for name, text in files(page).items():
            (Path(work) / name).write_text(text, encoding="utf-8")
        path = Path(work) / f"{page.stem}_blocks.py"
        path.write_text(script(page_blocks), encoding="utf-8")
        env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONHASHSEED": "0", "COLUMNS": "100"}
        res = subprocess.run([sys.executable, str(path)], cwd=work, env=env, capture_output=True, text=True, timeout=TIMEOUT)
    printed = res.stdout.split(MARK + "\n")
    if res.returncode != 0:
        failed = runnable[min(len(printed), len(runnable)) - 1]
        tail = "\n".join(res.stderr.strip().splitlines()[-12:])
        return [f"{page.name}: the block at line {failed.line} fails:\n{textwrap.indent(tail, '    ')}"]
    checker = doctest.OutputChecker()
    flags = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
    return [
        f"{page.name}: the block at line {b.line} printed\n{textwrap.indent(out, '    ')}\n  where the page shows\n{textwrap.indent(b.output, '    ')}"
        for b, out in zip(runnable, printed, strict=False)
        if b.output is not None and not checker.check_output(b.output, out, flags)
    ]


@pytest.mark.parametrize("page", PAGES, ids=[p.relative_to(ROOT).as_posix() for p in PAGES])
def test_the_page_runs_as_written(page: Path) -> None:
    if not any(b.skip is None for b in blocks(page)):
        pytest.skip(f"{page.name} has no Python block to run")
    wrong = problems(page)
    assert not wrong, "\n\n".join(wrong)


def test_the_conventions_are_enforced(tmp_path: Path) -> None:
    # A skip without its reason and an output block with no block before it are errors of
    # the page, not silent passes; an output block is tied to the block right before it.
    page = tmp_path / "page.md"
    page.write_text("```python {.skip}\nx = 1\n```\n")
    with pytest.raises(AssertionError, match="needs its reason"):
        blocks(page)
    page.write_text("```python skip: no braces\nx = 1\n```\n")
    with pytest.raises(AssertionError, match="in braces"):
        blocks(page)
    page.write_text("text\n\n```text {.output}\n1\n```\n")
    with pytest.raises(AssertionError, match="must follow"):
        blocks(page)
    page.write_text('```python\nprint(1)\n```\n\n```text {.output}\n1\n```\n\n```python {.skip reason="needs a cluster"}\nx\n```\n')
    got = blocks(page)
    assert [(b.output, b.skip) for b in got] == [("1\n", None), (None, "needs a cluster")]


def test_a_wrong_output_and_a_failing_block_are_reported(tmp_path: Path) -> None:
    # The checks can fail: a shown output that differs from the printed one, and a block that
    # raises (named by its line, after a block that ran); `...` matches any text.
    page = tmp_path / "page.md"
    page.write_text("```python\nx = 2 + 2\nprint(x, 'apples')\n```\n\n```text {.output}\n5 apples\n```\n")
    (wrong,) = problems(page)
    assert "line 1 printed" in wrong and "5 apples" in wrong, wrong
    page.write_text("```python\nprint(2 + 2, 'apples')\n```\n\n```text {.output}\n4 ...\n```\n")
    assert problems(page) == []
    page.write_text("```python\nx = 1\n```\n\ntext\n\n```python\nraise ValueError('bad dt')\n```\n")
    (failed,) = problems(page)
    assert "line 7 fails" in failed and "ValueError: bad dt" in failed, failed


def test_every_public_name_and_command_has_a_reference_entry():
    # The site's reference (mkdocs.yml): one `::: kinema.NAME` per name of kinema.__all__ in
    # docs/reference/python.md (mkdocstrings renders it from the docstring; a name it cannot
    # find fails `make docs`), and the command line's page renders the whole `kinema` group
    # (mkdocs-click, every command at depth 1) from kinema.cli's click command.
    import kinema
    from kinema import cli

    text = (ROOT / "docs" / "reference" / "python.md").read_text(encoding="utf-8")
    listed = set(re.findall(r"^::: kinema\.(\w+)$", text, re.M))
    assert listed == set(kinema.__all__) - {"__version__"}, (set(kinema.__all__) - listed, listed - set(kinema.__all__))
    page = (ROOT / "docs" / "reference" / "cli.md").read_text(encoding="utf-8")
    assert ":module: kinema.cli" in page and ":command: click_command" in page and ":depth: 1" in page
    assert set(cli.click_command.commands) == {"methods", "stability", "demo", "run", "render", "export", "sweep", "analyze", "view"}


def test_the_site_has_an_install_page_linked_from_the_home_page_and_the_nav():
    import yaml

    page = (ROOT / "docs" / "install.md").read_text(encoding="utf-8")
    for needed in ("pip install", "venv", "make demo", "make test", "ffmpeg", "bpy", "ovito", "lammps"):
        assert needed in page.lower() or needed in page, f"docs/install.md does not say {needed!r}"
    assert "](install.md)" in (ROOT / "docs" / "index.md").read_text(encoding="utf-8")

    def pages(nav):
        for item in nav:
            for value in item.values() if isinstance(item, dict) else [item]:
                yield from pages(value) if isinstance(value, list) else [value]

    config = yaml.load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"), Loader=yaml.BaseLoader)
    assert "install.md" in list(pages(config["nav"]))


def test_no_page_speaks_of_the_seed_or_links_it():
    """The lecture notes the project grew from are not in the repository: pages name them
    "the lecture notes" and quote them, and link no path that is not there. (A random
    seed, "the seed" of a particle block or a sweep's member, is another thing.)"""
    for page in [*PAGES, ROOT / "python" / "kinema" / "demo.py", ROOT / "python" / "kinema" / "world_collisions.py"]:
        text = page.read_text(encoding="utf-8")
        assert not re.search(r"\bseed's\b|\.\./seed\b|\(seed/|the seed, shown", text, re.IGNORECASE), f"{page.name} speaks of the seed"
        if page.suffix == ".md":
            for target in re.findall(r"\]\(([^)#\s]+)", text):
                if not re.match(r"[a-z]+:", target):
                    assert (page.parent / target).exists(), f"{page.name} links {target}, which is not in the repository"
