"""The README is the door and the user guide the rooms: the README keeps its set-up commands, its size and its
links into the site (every code and console block of both runs in tests/test_docs.py)."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: the user guide's pages (docs/guide/*.md), where the README's examples moved
GUIDE = sorted((ROOT / "docs" / "guide").glob("*.md"))
#: the two set-up commands (.ci/run runs the second's install and test steps)
SETUP = (
    'python3 -m venv .venv && . .venv/bin/activate && pip install . && isolator simulate',
    'python3 -m venv .venv && . .venv/bin/activate && pip install -e ".[test]" && python -m pytest',
)


def test_the_readme_keeps_its_setup_commands():
    for command in SETUP:
        assert f"```bash\n{command}\n```" in README, command


def test_ci_installs_and_tests_as_the_readme_says():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert re.search(r'pip install --quiet -e "\.\[test[,\]]', ci), "CI must install the project as the README says"
    assert "python -m pytest" in ci


def test_the_readme_is_a_door():
    assert len(README.splitlines()) <= 200


def test_the_readme_links_resolve():
    """Every relative link of the README (and of the guide pages, to files) names a file that exists."""
    for source in [ROOT / "README.md", *GUIDE]:
        text = source.read_text(encoding="utf-8")
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target) or target.startswith("#"):
                continue
            path = (source.parent / target.split("#")[0]).resolve()
            assert path.exists(), f"{source.relative_to(ROOT)}: {target}"


def test_every_guide_page_is_linked_from_the_readme():
    for page in GUIDE:
        assert f"docs/guide/{page.name}" in README, page.name


def test_the_gallery_has_a_dozen_titled_examples():
    """sphinx-gallery's format: ``examples/<section>/plot_*.py``, each opening with a docstring whose first
    line is a title underlined with ``=`` (the site's build runs them; a section needs its GALLERY_HEADER)."""
    scripts = sorted((ROOT / "examples").glob("*/plot_*.py"))
    assert len(scripts) >= 12
    for script in scripts:
        lines = script.read_text(encoding="utf-8").splitlines()
        assert lines[0] == '"""', script.name
        assert set(lines[2]) == {"="}, script.name
        assert len(lines[2]) >= len(lines[1]), script.name
        assert (script.parent / "GALLERY_HEADER.rst").exists(), script.parent.name
