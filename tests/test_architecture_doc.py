"""docs/architecture.md names only files that exist: every file name it mentions is in the
repository (a path with folders must be the end of a tracked path), and it cites nothing
outside the repository."""

import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DOC = ROOT / "docs" / "architecture.md"
NOT_FILES = {"three.js"}  # a library's name, not a file
FILE = re.compile(r"(?<![\w/.-])(/?[\w.-]+(?:/[\w.-]+)*\.(?:rs|py|pyi|md|toml|js|mjs|html|json|in|txt|yml|cfg))\b")


def tracked() -> list[str]:
    out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    return out + [p.relative_to(ROOT).as_posix() for p in (ROOT / "python" / "kinema").glob("*.so")]


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
