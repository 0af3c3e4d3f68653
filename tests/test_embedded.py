"""The generated C planner cross-compiled for two microcontrollers and run on QEMU's emulated boards.

Cortex-M7 with a double-precision FPU (board mps2-an500) and Cortex-M4F (mps2-an386), built by the
generated Makefile with ``arm-none-eabi-gcc -Wall -Wextra -Werror``, run with semihosting. The
reference is the host build of the same sources (itself checked against the Python planner and scipy
in ``test_codegen.py``): the same exit status, the same plan to rounding (newlib's libm and glibc differ
in the last ulp of sin/cos/atan2, so not bit for bit in general).

Skipped when arm-none-eabi-gcc or qemu-system-arm is absent, except with ROLLPLAN_REQUIRE_EMBEDDED=1
(set by .ci/run, which installs them), where a missing tool is an error: CI cannot pass by skipping.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

import pytest
from test_codegen import make

TOOLS = ("arm-none-eabi-gcc", "arm-none-eabi-objdump", "qemu-system-arm", "make", "cc")
MISSING = [t for t in TOOLS if shutil.which(t) is None]
if MISSING and os.environ.get("ROLLPLAN_REQUIRE_EMBEDDED") == "1":
    raise RuntimeError(f"ROLLPLAN_REQUIRE_EMBEDDED=1 but {', '.join(MISSING)} not installed")
pytestmark = [pytest.mark.slow, pytest.mark.skipif(bool(MISSING), reason=f"{MISSING} not installed")]

QEMU_TIMEOUT = 120       # s per emulated run; the slowest plans take a few seconds
BOARD = {"m7": "mps2-an500", "m4f": "mps2-an386"}
PAPER = ["0", "1", "0", "1", "2.5"]


@pytest.fixture(scope="module")
def boards(generated_c, tmp_path_factory):
    out = tmp_path_factory.mktemp("boards") / "planner"
    shutil.copytree(generated_c.out, out, symlinks=True)   # the shared build is read-only; the times are kept
    run = make("-s", "-C", str(out), "-j2", "plan_demo", "arm-m7", "arm-m4f", timeout=900)
    assert run.returncode == 0, run.stderr
    return out


def qemu(target: str, elf, args, timeout: float = QEMU_TIMEOUT):
    semi = ",".join(["enable=on", "target=native", "arg=plan_demo", *[f"arg={a}" for a in args]])
    cmd = ["timeout", "-k", "5", str(timeout), "qemu-system-arm", "-M", BOARD[target], "-nographic",
           "-monitor", "none", "-serial", "none", "-semihosting-config", semi, "-kernel", str(elf)]
    run = subprocess.run(cmd, capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=timeout + 10,
                         check=False)
    assert run.returncode not in (124, 137), f"QEMU run timed out: {' '.join(cmd)}"
    return run


def host(out, args):
    return subprocess.run([str(out / "plan_demo"), *args], capture_output=True, text=True, timeout=120, check=False)


def test_makefile_cross_compiles_strictly(boards):
    text = (boards / "Makefile").read_text()
    assert "ARM_CFLAGS = -std=c99 -Wall -Wextra -Werror" in text
    assert "-mcpu=cortex-m7 -mfpu=fpv5-d16 -mfloat-abi=hard" in text
    assert "-mcpu=cortex-m4 -mfpu=fpv4-sp-d16 -mfloat-abi=hard" in text
    for t in BOARD:
        assert (boards / "build" / t / "plan_demo.elf").stat().st_size > 0


def test_make_qemu_prints_the_host_plan(boards):
    run = make("-s", "-C", str(boards), "qemu", timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr
    lines = dict(line.split(":", 1) for line in run.stdout.splitlines() if ":" in line)
    want = host(boards, PAPER).stdout.split()[:3]
    assert len(want) == 3
    for name in ("mps2-an500 (m7)", "mps2-an386 (m4f)"):
        got = lines[next(k for k in lines if k.strip() == name)].split()[:3]
        assert [abs(float(g) - float(w)) <= 1e-13 for g, w in zip(got, want)] == [True] * 3


@pytest.mark.parametrize("args", [["0.1", "-0.3", "3", "2", "10"], ["0.3", "-0.2", "0.5", "1", "2.5"],
                                  ["0", "0", "0", "1", "2.5"], ["x"], ["0", "1", "0", "0", "2.5"],
                                  ["30", "0", "0", "1", "2.5"]])
def test_emulated_status_and_plan_are_the_host_ones(boards, args):
    want, got = host(boards, args), qemu("m7", boards / "build" / "m7" / "plan_demo.elf", args)
    assert got.returncode == want.returncode, got.stderr
    assert len(got.stdout.split()) == len(want.stdout.split())
    for g, w in zip(got.stdout.split()[:3], want.stdout.split()[:3]):
        assert abs(float(g) - float(w)) <= 1e-13 * (1 + abs(float(w)))
    assert got.stderr.count("\n") == want.stderr.count("\n")


def test_a_fault_exits_instead_of_hanging(boards, tmp_path):
    """The startup file turns every unexpected exception into one line and exit status 70 + number."""
    src = tmp_path / "fault.c"
    src.write_text("int main(void) { return *(volatile int *)0x30000000; }\n")
    elf = tmp_path / "fault.elf"
    flags = ["-mthumb", "-mcpu=cortex-m7", "-mfpu=fpv5-d16", "-mfloat-abi=hard"]
    subprocess.run(["arm-none-eabi-gcc", *flags, "-O2", "--specs=rdimon.specs", "-nostartfiles", f"-L{boards}",
                    f"-T{boards / 'mps2-an500.ld'}", "-o", str(elf), str(boards / "build" / "m7" / "startup.o"),
                    str(src)], check=True, timeout=120)
    run = qemu("m7", elf, [], timeout=30)
    assert run.returncode == 73 and "unexpected exception 03" in run.stderr


def test_static_memory_and_stack_bound(boards):
    run = make("-s", "-C", str(boards), "check-static", timeout=600)
    assert run.returncode == 0, run.stderr
    for t in BOARD:
        run = subprocess.run([sys.executable, str(boards / "stack_bound.py"), "--su", str(boards / "build" / t),
                              str(boards / "build" / t / "planner_only.elf"), "rollplan_plan"],
                             capture_output=True, text=True, timeout=120, check=True)
        bound = int(re.search(r"rollplan_plan: (\d+) bytes", run.stdout).group(1))
        assert 0 < bound < 0x10000   # the linker scripts' stack reserve


def test_make_size_reports_flash_ram_and_stack(boards):
    run = make("-s", "-C", str(boards), "size", timeout=600)
    assert run.returncode == 0, run.stderr
    for t in BOARD:
        assert re.search(rf"{t} planner firmware .*flash \d+ B, RAM \d+ B", run.stdout)
        assert re.search(rf"{t} static stack bound: rollplan_plan: \d+ bytes", run.stdout)
        assert re.search(rf"{t} measured stack of plan_demo .*: \d+ bytes", run.stdout)


def test_float_build_on_the_cortex_m4f(generated_c_float):
    """`rollplan codegen --real float`: built with -Wdouble-promotion -Werror, no double operation in the library
    (check-static), and `make qemu` prints the host's float plan on both boards; the Cortex-M4F's (its run of
    plan_demo, as `make qemu` prints it) has the paper's a1."""
    out = generated_c_float.out
    assert "M4F_EXTRA = -Wdouble-promotion" in (out / "Makefile").read_text()
    said = ""
    for goal in ("check-static", "qemu"):
        run = make("-s", "-C", str(out), "-j2", goal, timeout=900)
        assert run.returncode == 0, run.stdout + run.stderr   # `make qemu` fails if a board's run fails
        said += run.stdout
    assert "no double operation in the float library" in said and "both boards print the host's" in said
    lines = dict(line.split(":", 1) for line in said.splitlines() if ":" in line)
    got = lines[next(k for k in lines if k.strip() == "mps2-an386 (m4f)")].split()
    assert abs(float(got[0]) - 0.300429) < 1e-5
