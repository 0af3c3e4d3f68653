"""The README's examples are the files in examples/ and they run: the Python API from another folder (so
the installed package is imported, not a source folder in the current directory), the batch CSV in
``tests/test_batch.py``."""

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()


def _blocks(lang):
    """The fenced code blocks of the README in language ``lang`` ("" for none), as text."""
    blocks, current, kind = [], None, None
    for line in README.splitlines(keepends=True):
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


def test_readme_shows_the_api_example_file():
    code = (ROOT / "examples" / "api.py").read_text()
    body = code.split('"""', 2)[2].lstrip("\n")   # without the module docstring
    assert body in _blocks("python")


def test_readme_shows_the_example_csv():
    assert (ROOT / "examples" / "targets.csv").read_text() in _blocks("")


@pytest.mark.slow
def test_api_example_runs_from_another_folder(tmp_path):
    r = subprocess.run([sys.executable, str(ROOT / "examples" / "api.py")], cwd=tmp_path, check=True,
                       capture_output=True, text=True, timeout=600)
    first = r.stdout.splitlines()[0].split()
    assert float(first[0]) == pytest.approx(0.300429, abs=5e-7) and first[3] == "0"
    assert r.stdout.splitlines()[-1].endswith("N m")
