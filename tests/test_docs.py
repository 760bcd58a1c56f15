"""The documentation: the site builds without a warning, the README stays short and shows
the code of ``examples/quickstart.py``, and no relative link points to a missing file."""

from __future__ import annotations

import ast
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
README = ROOT / "README.md"

#: ``[text](target)`` and ``![alt](target)`` in Markdown, outside code.
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def _markdown_files() -> list[Path]:
    return [README, *sorted(DOCS.glob("**/*.md"))]


def _without_code(text: str) -> str:
    """``text`` without fenced code blocks and inline code spans (links there are examples)."""
    text = re.sub(r"(?ms)^```.*?^```", "", text)
    return re.sub(r"`[^`\n]*`", "", text)


def _relative_links(path: Path) -> list[str]:
    targets = LINK.findall(_without_code(path.read_text(encoding="utf-8")))
    return [target for target in targets if not re.match(r"^[a-z][a-z0-9+.-]*:", target) and not target.startswith("#")]


def test_the_site_builds_strictly(tmp_path: Path) -> None:
    """``mkdocs build --strict`` (mkdocs-material, mkdocstrings) passes: no broken link, no
    page missing from the site, no docstring griffe cannot read."""
    completed = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert completed.returncode == 0, completed.stdout + completed.stderr
    assert (tmp_path / "site" / "index.html").is_file()
    assert (tmp_path / "site" / "reference" / "planner" / "index.html").is_file()


def test_the_readme_is_at_most_200_lines() -> None:
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines; move detail to docs/"


def _code_of(path: Path) -> str:
    """The code of a Python file without its module docstring and leading comments."""
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    module = ast.parse(text)
    start = 0
    if module.body and isinstance(module.body[0], ast.Expr) and isinstance(module.body[0].value, ast.Constant) \
            and isinstance(module.body[0].value.value, str):
        start = module.body[0].end_lineno or 0
    body = lines[start:]
    while body and (not body[0].strip() or body[0].lstrip().startswith("#")):
        body = body[1:]
    return "\n".join(body).strip()


def test_the_readme_library_example_is_the_quickstart_example() -> None:
    text = README.read_text(encoding="utf-8")
    section = text.index("## The library")
    start = text.index("```python", section) + len("```python")
    shown = text[start:text.index("```", start)].strip()
    code = _code_of(ROOT / "examples" / "quickstart.py")
    assert shown == code, "README.md's library example differs from examples/quickstart.py"
    for page in (DOCS / "getting-started.md", DOCS / "guides" / "library.md"):
        assert f"```python\n{code}\n```" in page.read_text(encoding="utf-8"), \
            f"{page.relative_to(ROOT)} does not show examples/quickstart.py as it is"


@pytest.mark.parametrize("path", _markdown_files(), ids=lambda path: path.relative_to(ROOT).as_posix())
def test_relative_links_point_to_existing_files(path: Path) -> None:
    missing = []
    for target in _relative_links(path):
        file = target.split("#", 1)[0]
        if file and not (path.parent / file).exists():
            missing.append(target)
    assert not missing, f"{path.relative_to(ROOT)} links to missing files: {missing}"


def test_every_docs_page_is_in_the_navigation() -> None:
    """A page under docs/ is reachable from the site's menu (``mkdocs build`` only informs)."""
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    listed = set(re.findall(r":\s*([\w/-]+\.md)\s*$", config, flags=re.MULTILINE))
    pages = {page.relative_to(DOCS).as_posix() for page in DOCS.glob("**/*.md")}
    assert pages <= listed, sorted(pages - listed)
