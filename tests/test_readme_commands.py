"""Every shell command of the documentation runs: each fenced ``sh`` block of README.md and docs/**/*.md, its
``rollplan ...`` and ``python ...`` lines in order, in a temporary folder holding a fresh copy of examples/.

A line must exit 0, or the status its trailing comment states (``# exit 2``). Lines that need a Dask cluster
(``--scheduler``, ``dask ...``) or install packages (``pip install``) are skipped; other programs (``make``,
the generated C demo, QEMU) are not run here (tests/test_codegen.py and tests/test_embedded.py build them).
One test per block, so that a block's lines share their files (plan writes plan.json, simulate reads it)
and pytest-xdist spreads the blocks over the cores.

A ``rollplan`` line that is a command and its words only (no pipe, redirection, glob, variable or brace for
the shell to act on) runs in this process, through the same ``main`` as the console script
(``conftest.run``): a process of its own would only add its start-up (importing numpy, CasADi and matplotlib
again, about 1 s of CPU a line); the console script itself is tested in tests/test_cli.py. Every other line
runs in bash.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import run

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
RUN = ("rollplan", "python")                 # the commands run; anything else is left to the reader
EXIT = re.compile(r"\s#\s*exit (\d+)\b")     # the documented exit status of a line, when not 0


def shell_blocks(text):
    """``(line number, lines)`` of each fenced ``sh`` block of a Markdown text (line numbers from 1)."""
    blocks, current = [], None
    for number, line in enumerate(text.splitlines(), 1):
        if line.startswith("```"):
            if current is None:
                current = (number + 1, []) if line[3:].strip() == "sh" else (number + 1, None)
            else:
                if current[1] is not None:
                    blocks.append(current)
                current = None
        elif current is not None and current[1] is not None:
            current[1].append(line)
    return blocks


def skipped(command):
    """True for a line that needs a Dask cluster or installs packages."""
    words = command.split()
    return "--scheduler" in words or words[0] == "dask" or "pip install" in command


def commands(lines):
    """The lines to run, ``(command, expected exit status)``, backslash continuations joined."""
    joined, out = [], []
    for line in lines:
        if joined and joined[-1].endswith("\\"):
            joined[-1] = joined[-1][:-1] + " " + line.strip()
        else:
            joined.append(line.strip())
    for command in joined:
        if not command or command.startswith("#") or command.split()[0] not in RUN or skipped(command):
            continue
        match = EXIT.search(command)
        out.append((command, int(match.group(1)) if match else 0))
    return out


def documented_blocks():
    """``(id, commands)`` of every block with something to run, over README.md and docs/*.md."""
    found = []
    for page in PAGES:
        for number, lines in shell_blocks(page.read_text()):
            runnable = commands(lines)
            if runnable:
                found.append((f"{page.relative_to(ROOT)}:{number}", runnable))
    return found


BLOCKS = documented_blocks()


#: What makes a line more than a command and its words to bash (and braces holding a list or a range).
SHELL = set("|&;<>()$`\\*?[]~!#=")
BRACES = re.compile(r"\{[^}]*(,|\.\.)[^}]*\}")


def plain_argv(command):
    """The words after ``rollplan`` of a line bash would run as a command and its words only (the trailing
    ``# comment`` dropped), else None."""
    code = re.split(r"(?:^|\s)#", command, maxsplit=1)[0]
    if SHELL & set(code) or BRACES.search(code):
        return None
    words = shlex.split(code)
    return words[1:] if words and words[0] == "rollplan" else None


def run_block(block, folder, capture=None, timeout=900):
    """Run a block's commands in order in ``folder`` (with a copy of examples/); fail on the first line whose
    exit status is not the documented one. With ``capture`` (pytest's ``capfd``) the plain ``rollplan`` lines
    run in this process (:func:`plain_argv`)."""
    shutil.copytree(ROOT / "examples", folder / "examples", dirs_exist_ok=True)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}")
    for command, expected in block:
        argv = plain_argv(command) if capture is not None else None
        if argv is not None:
            code, out, err = run(capture, *argv, cwd=folder)
        else:
            r = subprocess.run(["bash", "-o", "pipefail", "-c", command], check=False, cwd=folder, env=env,
                               capture_output=True, text=True, timeout=timeout, stdin=subprocess.DEVNULL)
            code, out, err = r.returncode, r.stdout, r.stderr
        if code != expected:
            pytest.fail(f"`{command}` exited {code}, the docs say {expected}\n"
                        f"stdout: {out[-1500:]}\nstderr: {err[-1500:]}")


@pytest.mark.slow
@pytest.mark.parametrize("block", [b for _, b in BLOCKS], ids=[i for i, _ in BLOCKS])
def test_documented_commands_run(block, tmp_path, capfd):
    run_block(block, tmp_path, capfd)


def test_the_docs_have_commands_to_run():
    """Every page with shell blocks is read; the README's quick start is among them."""
    assert any(i.startswith("README.md") for i, _ in BLOCKS)
    assert len(BLOCKS) >= 10


def test_parsing_of_blocks():
    text = ("text\n```sh\nrollplan plan --to 0 1   # a comment\n# only a comment\n"
            "make -C planner_c\nrollplan plan --to 5 \\\n  0 --steps 0   # exit 2: refused\n"
            "pip install 'rollplan[distributed]'\ndask scheduler\nrollplan batch t.csv --scheduler tcp://x:1\n"
            "python -m json.tool x\n```\n```\nrollplan not sh\n```\n")
    [(number, lines)] = shell_blocks(text)
    assert number == 3
    assert commands(lines) == [("rollplan plan --to 0 1   # a comment", 0),
                               ("rollplan plan --to 5  0 --steps 0   # exit 2: refused", 2),
                               ("python -m json.tool x", 0)]


def test_a_failing_command_fails_its_block(tmp_path):
    """The check is not vacuous: a line whose status differs from the documented one fails the block."""
    with pytest.raises(pytest.fail.Exception, match="exited 3, the docs say 0"):
        run_block([("python -c 'import sys; sys.exit(3)'", 0)], tmp_path)
    with pytest.raises(pytest.fail.Exception, match="exited 0, the docs say 2"):
        run_block([("python -c 'pass'   # exit 2", 2)], tmp_path)
    run_block([("python -c 'import sys; sys.exit(2)'   # exit 2", 2), ("python -c 'pass'", 0)], tmp_path)


def test_plain_rollplan_lines_run_in_process_the_others_in_bash():
    assert plain_argv("rollplan plan --to 5 0 --steps 0   # exit 2: refused (a, b)") == ["plan", "--to", "5", "0",
                                                                                     "--steps", "0"]
    assert plain_argv("rollplan atlas --out 'atlas k{k}.png'   # one figure per k") == ["atlas", "--out",
                                                                                       "atlas k{k}.png"]
    for line in ("rollplan plan --json - | python -m json.tool", "rollplan plan > out.txt", "rollplan plan a#b",
                 "rollplan plan --out fig_{1,2}.png", "rollplan plan --out *.png", "X=1 rollplan plan",
                 "rollplan plan --to $U 0", "python examples/api.py", "make -C planner_c"):
        assert plain_argv(line) is None, line


def test_a_failing_line_in_process_fails_its_block(tmp_path, capfd):
    with pytest.raises(pytest.fail.Exception, match="exited 2, the docs say 0"):
        run_block([("rollplan plan --to 5 0 --steps 0", 0)], tmp_path, capfd)
    run_block([("rollplan plan --to 5 0 --steps 0   # exit 2", 2)], tmp_path, capfd)


def slug(heading):
    """GitHub's anchor of a Markdown heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_links_between_pages_resolve():
    """Every relative link of README.md and docs/*.md names a file that exists, and an anchor a heading of it."""
    for page in PAGES:
        for target in re.findall(r"\]\(([^)\s]+)\)", page.read_text()):
            if "://" in target:
                continue
            path, _, anchor = target.partition("#")
            linked = (page.parent / path).resolve() if path else page
            assert linked.exists(), f"{page.relative_to(ROOT)}: {target}"
            if anchor:
                headings = re.findall(r"^#+ (.+)$", linked.read_text(), flags=re.MULTILINE)
                assert anchor in {slug(h) for h in headings}, f"{page.relative_to(ROOT)}: {target}"
