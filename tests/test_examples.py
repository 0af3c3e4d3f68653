"""The documentation's examples are the files in examples/ and they run: the Python API (shown in
docs/planning.md) from another folder (so the installed package is imported, not a source folder in the
current directory), the batch CSV (shown in docs/batches.md) in ``tests/test_batch.py``."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"


def _blocks(lang, page):
    """The fenced code blocks of a documentation page in language ``lang`` ("" for none), as text."""
    blocks, current, kind = [], None, None
    for line in page.read_text().splitlines(keepends=True):
        if line.startswith("```"):
            if current is None:
                current, kind = [], line[3:].strip()
            else:
                if kind == lang:
                    blocks.append("".join(current))
                current = None
        elif current is not None:
            current.append(line)
    return blocks


def test_docs_show_the_api_example_file():
    code = (ROOT / "examples" / "api.py").read_text()
    body = code.split('"""', 2)[2].lstrip("\n")   # without the module docstring
    assert body in _blocks("python", DOCS / "planning.md")


def test_docs_show_the_example_csv():
    assert (ROOT / "examples" / "targets.csv").read_text() in _blocks("", DOCS / "batches.md")


def test_docs_show_the_example_waypoints():
    assert (ROOT / "examples" / "waypoints.csv").read_text() in _blocks("", DOCS / "planning.md")


def test_readme_points_to_the_example_files():
    """The README's commands use the shipped example files by their path."""
    readme = (ROOT / "README.md").read_text()
    for name in ("robot.toml", "real.toml", "targets.csv", "api.py"):
        assert f"examples/{name}" in readme


@pytest.mark.slow
def test_api_example_runs_from_another_folder(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "api.py")], cwd=tmp_path, check=True,
                       capture_output=True, text=True, timeout=600)
    first = r.stdout.splitlines()[0].split()
    assert float(first[0]) == pytest.approx(0.300429, abs=5e-7) and first[3] == "0"
    assert r.stdout.splitlines()[-1].endswith("N m")
