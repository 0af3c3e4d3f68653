"""The scripts in scripts/ run on the package as it is (they are not part of the package's API)."""

import importlib
import json
import os
import shutil
import subprocess
import sys
import types
from pathlib import Path

import pytest
from conftest import cache_wide


def seed_host_build(builds, generated_c, tmp_path) -> None:
    """Start benchmark.py's kept host build of the default C planner (``bench_codegen.kept_folder`` in ``builds``) as a
    copy of the suite's shared build of the same sources (``generated_c``: its objects, with their times), when every
    file the script generates is byte for byte the fixture's: its ``make`` then links what is missing and compiles
    nothing."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        import bench_codegen
    finally:
        sys.path.pop(0)
    fresh = tmp_path / "generated"
    bench_codegen.codegen.generate(fresh, bench_codegen.codegen.DEFAULT_STEPS_PER_LEAF)
    folder = bench_codegen.kept_folder(fresh, str(builds), "host", bench_codegen.host_tools())
    same = all(p.is_dir() or ((generated_c.out / p.relative_to(fresh)).is_file()
                              and (generated_c.out / p.relative_to(fresh)).read_bytes() == p.read_bytes())
               for p in fresh.rglob("*"))
    if same and not folder.exists():
        shutil.copytree(generated_c.out, folder, symlinks=True)
    shutil.rmtree(fresh)


@pytest.mark.slow
def test_benchmark_script_runs(tmp_path, generated_c):
    """Every section once (--quick, without the JIT and the cold subprocesses), issue 28's among them: the speed-up
    of the rest-to-rest collocation over rockit (wall and CPU time, the optima's difference) and the wall time of
    `rollplan compare`, each with its budget row. A second run, as a program, with --only reruns two sections and
    keeps the others, each with the date of its own run. The C planner's host build starts from the suite's shared
    build of the same sources (:func:`seed_host_build`)."""
    with cache_wide("benchmark") as builds:     # the C planner's build kept with the tests' build cache
        seed_host_build(builds, generated_c, tmp_path)
        run_script_here("benchmark.py", tmp_path, "--quick", "--no-jit", "--no-cold", "--build-dir", str(builds))
        assert any((kept / "librollplan.a").is_file() for kept in builds.glob("host-*"))
    text = (tmp_path / "benchmarks.md").read_text()
    assert "evaluations/s" in text and "commit" in text and "speed-up" in text and "Profile" in text
    assert "## Budgets" in text and "Collocation planner" in text and "C planner" in text
    assert "load average at start" in text and "Many plans per call: rollplan.plan_many" in text
    assert "root_solver ipopt warm [ms]" in text
    assert (tmp_path / "benchmarks.json").stat().st_size > 0
    report = json.loads((tmp_path / "benchmarks.json").read_text())
    assert report["command"] == f"python scripts/benchmark.py --quick --no-jit --no-cold --build-dir {builds} " \
                                f"--out-dir {tmp_path}"     # the run's own arguments, not its caller's
    sections = {sec["function"]: sec for sec in report["sections"]}
    peer, comp = sections["section_peer"]["summary"], sections["section_compare"]["summary"]
    assert peer["speedup"] > 0 and peer["speedup_cpu"] > 0 and peer["relative_difference"] <= 1e-6
    assert comp["median_s"] > 0 and comp["cpu_median_s"] > 0
    budgets = [row["budget"] for row in sections["section_budgets"]["rows"]]
    assert any("faster than rockit" in b for b in budgets) and any("`rollplan compare`" in b for b in budgets)
    # as a program (its own entry point and imports: the default's section imports the tests' references)
    run_script("benchmark.py", tmp_path, "--quick", "--only", "memory", "fast_default")
    again = {sec["function"]: sec for sec in json.loads((tmp_path / "benchmarks.json").read_text())["sections"]}
    assert set(again) == set(sections)
    assert again["section_peer"] == sections["section_peer"] and again["section_memory"] != sections["section_memory"]
    assert again["section_fast_default"] != sections["section_fast_default"]


@pytest.mark.slow
def test_polish_ipopt_script_runs(tmp_path):
    """scripts/polish_ipopt.py writes the table of what IPOPT changes on the C planner's plans."""
    run_script_here("polish_ipopt.py", tmp_path, "--per-k", "1")
    text = (tmp_path / "polish_ipopt.md").read_text()
    assert "(a, b) changed by IPOPT" in text and "| targets | 7 |" in text
    report = json.loads((tmp_path / "polish_ipopt.json").read_text())
    assert report["summary"]["targets"] == 7 and len(report["rows"]) == 7


def run_script(name: str, out_dir, *args: str, timeout: float = 900) -> None:
    """Run scripts/NAME with ``args`` and ``--out-dir out_dir`` in a process of its own; fails on a nonzero exit."""
    script = Path(__file__).resolve().parent.parent / "scripts" / name
    subprocess.run([sys.executable, str(script), *args, "--out-dir", str(out_dir)], check=True, capture_output=True,
                   timeout=timeout)


def run_script_here(name: str, out_dir, *args: str) -> None:
    """Run scripts/NAME's ``main`` with ``args`` and ``--out-dir out_dir`` in this process (it shares the imports and
    the solvers the tests built before it: what the script measures is the same); fails on a nonzero exit."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        status = importlib.import_module(name.removesuffix(".py")).main([*args, "--out-dir", str(out_dir)])
    finally:
        sys.path.remove(str(Path(__file__).resolve().parent.parent / "scripts"))
    assert status in (0, None)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["basepoint_bench.py", "curve_families.py", "embedded_report.py", "polish_ipopt.py",
                                  "reconfiguration.py", "suite_report.py", "timing_table.py"])
def test_a_script_run_as_a_program_reads_its_own_arguments(name, tmp_path):
    """The scripts whose runs the tests make through ``main`` (:func:`run_script_here`, :func:`suite_report_here`),
    run as a user does:
    ``python scripts/NAME`` passes its arguments (without the program's name) to ``main`` and exits with its
    status (argparse's 2 for an unknown option, naming only that option), before the slow imports (numpy,
    rollplan: ``-X importtime`` lists what was imported)."""
    script = Path(__file__).resolve().parent.parent / "scripts" / name
    run = subprocess.run([sys.executable, "-X", "importtime", str(script), "--no-such-option"], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300, check=False)
    assert run.returncode == 2 and run.stderr.strip().endswith("unrecognized arguments: --no-such-option"), run.stderr
    assert not any(tmp_path.iterdir())
    imported = {line.rsplit("|", 1)[-1].strip() for line in run.stderr.splitlines() if line.startswith("import time:")}
    assert "encodings" in imported and not imported & {"numpy", "rollplan"}


@pytest.mark.slow
def test_timing_table_script_runs(tmp_path):
    run_script_here("timing_table.py", tmp_path, "--quick")
    text = (tmp_path / "timing.md").read_text()
    assert "of the shortest min-jerk duration under the same limits" in text and "| default (4.86) |" in text
    assert "## Convergence in the grid size" in text and (tmp_path / "timing.json").stat().st_size > 0
    assert f"command `python scripts/timing_table.py --quick --out-dir {tmp_path}`" in text   # not the caller's


@pytest.mark.slow
def test_reconfiguration_script_runs(tmp_path):
    run_script_here("reconfiguration.py", tmp_path, "--quick")
    text = (tmp_path / "reconfiguration.md").read_text()
    assert "## Turning in place" in text and "DOP853" in text and "## A route of five waypoints" in text
    assert "## Lengths against optimal control" in text and "--refine ratio" in text
    assert "### The new default on more random pairs\n\n1 pairs (--quick: the README example's, not random)" in text
    assert (tmp_path / "composed.png").stat().st_size > 0 and (tmp_path / "reconfiguration.json").stat().st_size > 0


@pytest.mark.slow
def test_closed_loop_script_runs(tmp_path):
    """The script end to end with one seed per case, one model error (each row of the Monte Carlo tables is one
    error; the torque plant's runs the smallest and largest, here the same, run once), one noise level of the issue's
    case and one plan of the torque-against-rate comparison (every section, fewer samples of each than even --quick),
    two figure eights instead of four in sections 1 to 3 (the closed loop still re-plans after the first and then
    corrects), MuJoCo at a 1 ms step (its closed loop tested in test_mujoco at that step). The process pools fork
    their workers (which inherit what the script has built), not spawn them."""
    scripts = Path(__file__).resolve().parent.parent / "scripts"
    run = ("import sys; sys.path.insert(0, sys.argv[1]); import closed_loop as c; c.ERRORS = (0.10,); "
           "c.NOISE_LEVELS = (1e-3,); c.STEPS = 2; c.TORQUE_CASES = c.TORQUE_CASES[:1]; c.MUJOCO_STEPS = (1,); "
           "c.BEYOND = c.BEYOND[:1]; c.MUJOCO_SETTINGS = {'timestep': 1e-3, 'solref': (2e-3, 1.0)}; "
           "import rollplan.studies.executor as ex; seen = []; pick = ex.start_method; "
           "ex.start_method = lambda: seen.append(pick()) or seen[-1]; "
           "sys.argv = [c.__file__] + sys.argv[2:]; c.main(); "
           "assert seen and set(seen) == {'fork'}, f'the pools started their workers by {seen}'")
    subprocess.run([sys.executable, "-c", run, str(scripts), "--seeds", "1", "--torque-seeds", "1", "--mujoco-seeds",
                    "1", "--out-dir", str(tmp_path)], check=True, capture_output=True, timeout=1800)
    text = (tmp_path / "closed_loop.md").read_text()
    assert "## 1. The issue's robot" in text and "## 2. Monte Carlo" in text and "## 3. Torque-driven" in text
    assert "## 4. The issue's robot closed loop" in text and "| torque plant | 1 |" in text
    data = json.loads((tmp_path / "closed_loop.json").read_text())
    assert [(r["kind"], r["error"]) for r in data["monte_carlo_torques"]] == [("k", 0.10), ("J_r", 0.10)]
    assert len(data["runs_torques"]) == 2 and len(data["runs_rates"]) == 4
    assert "settings {'timestep': 0.001" in text
    assert (tmp_path / "closed_loop.png").stat().st_size > 0 and (tmp_path / "closed_loop.json").stat().st_size > 0


@pytest.mark.slow
@pytest.mark.skipif(any(shutil.which(t) is None for t in ("arm-none-eabi-gcc", "qemu-system-arm", "make", "cc"))
                    and os.environ.get("ROLLPLAN_REQUIRE_EMBEDDED") != "1", reason="needs the ARM toolchain and QEMU")
def test_embedded_report_script_runs(tmp_path, monkeypatch):
    """The quick run, its builds kept with the tests' build cache (``--build-dir``): a run of the same package
    content and toolchain reuses them (the first one builds them). Its make compiles through the object store of
    tests/test_embedded.py's builds (the same sources and flags: each object compiled once per run)."""
    from test_codegen import object_store_tools

    for name, value in object_store_tools().items():   # make reads CC and ARM from the environment
        monkeypatch.setenv(name, value)
    with cache_wide("embedded-report") as builds:
        run_script_here("embedded_report.py", tmp_path, "--no-host", "--quick", "--build-dir", str(builds))
        for real in ("double", "float"):     # kept where --build-dir says
            assert any((kept / "build" / "m4f" / "bench_fw.elf").is_file() for kept in builds.glob(f"{real}-*"))
    text = (tmp_path / "embedded.md").read_text()
    assert "| double | m7 (mps2-an500) |" in text and "| float | m4f (mps2-an386) |" in text
    assert "Instructions per plan" in text and (tmp_path / "embedded.json").stat().st_size > 0
    data = json.loads((tmp_path / "embedded.json").read_text())
    for real in ("double", "float"):   # the paper's case counted on each board, a plan found (status 0)
        for board in ("m7", "m4f"):
            (row,) = data[real]["instructions"][board]
            assert row["target"] == [0.0, 1.0, 0.0, 1, 2.5] and row["status"] == 0
            assert 0 < row["certificate"] < row["plan"] < row["first_plan"]


def test_embedded_report_reuses_the_builds_of_the_same_sources(tmp_path, monkeypatch):
    """``--build-dir``: the builds of one generated content and toolchain are kept in a folder of their own, which a
    later run with the same sources and toolchain reuses (``make`` is run in it again: it rebuilds nothing) and
    another toolchain does not."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        import embedded_report
    finally:
        sys.path.pop(0)
    made = []
    monkeypatch.setattr(embedded_report, "make", lambda out, *goals: made.append(out))

    def generate(out, real):    # the sources rollplan codegen writes, in short
        out.mkdir()
        (out / "Makefile").write_text(f"all: # {real}\n")
        return types.SimpleNamespace(out=out, prefix="rollplan")

    monkeypatch.setattr(embedded_report.codegen, "generate", generate)
    tools = {"arm-none-eabi-gcc": "gcc 1", "qemu-system-arm": "qemu 1"}
    first = tmp_path / "first"
    first.mkdir()
    kept, prefix = embedded_report.build("double", first, str(tmp_path / "builds"), tools)
    assert kept.parent == tmp_path / "builds" and kept.name.startswith("double-") and prefix == "rollplan"
    # built under a temporary name, kept once the build succeeded
    assert (kept / "Makefile").is_file() and made == [kept.with_name(f"{kept.name}.part{os.getpid()}")]
    (kept / "built").touch()
    again = tmp_path / "again"
    again.mkdir()
    assert embedded_report.build("double", again, str(tmp_path / "builds"), tools)[0] == kept
    assert (kept / "built").exists() and made[1:] == [kept]
    other = tmp_path / "other"
    other.mkdir()
    assert embedded_report.build("double", other, str(tmp_path / "builds"), {**tools, "qemu-system-arm": "qemu 2"})[0] \
        not in (kept, other / "double")
    assert sorted(p.name.split("-")[0] for p in (tmp_path / "builds").iterdir()) == ["double", "double"]
    monkeypatch.setenv("CFLAGS", "-O0 -g")   # other make variables: another build
    flags = tmp_path / "flags"
    flags.mkdir()
    assert embedded_report.build("double", flags, str(tmp_path / "builds"), tools)[0] != kept

    def failing(out, *goals):
        raise subprocess.CalledProcessError(2, "make")

    monkeypatch.setattr(embedded_report, "make", failing)   # a failed (or stopped) build keeps nothing
    monkeypatch.setenv("CFLAGS", "-O1")
    failed = tmp_path / "failed"
    failed.mkdir()
    with pytest.raises(subprocess.CalledProcessError):
        embedded_report.build("double", failed, str(tmp_path / "builds"), tools)
    assert len(list((tmp_path / "builds").iterdir())) == 3


FAKE_TESTS = """import time
import pytest

def test_quick():
    pass

@pytest.mark.slow
def test_slow():
    time.sleep(0.3)

@pytest.mark.parametrize("x", [1, 2])
def test_param(x):
    assert x

@pytest.mark.skip(reason="shown as skipped")
def test_skipped():
    pass

def test_fails():
    assert False
"""


#: The fake suites use no plugin but pytest-xdist (``-n``): their runs skip loading the others (~0.25 s of CPU each).
NO_PLUGINS = ("-p", "no:hypothesispytest", "-p", "no:randomly")


def suite_report_here(monkeypatch, *args: str) -> int:
    """scripts/suite_report.py's ``main`` with ``args`` in this process (the script only starts the pytest runs it
    measures, each a process of its own; ``python scripts/suite_report.py`` reading its arguments is tested in
    :func:`test_a_script_run_as_a_program_reads_its_own_arguments`), its speed probe a tenth as long: the probe's
    seconds are still measured before and after each run and written to the report; its status."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        import suite_report
    finally:
        sys.path.pop(0)
    monkeypatch.setattr(suite_report, "PROBE_ITERATIONS", suite_report.PROBE_ITERATIONS // 10)
    return suite_report.main(list(args))


def test_the_reports_name_the_processor_and_what_chooses_the_blas_kernels(monkeypatch):
    """suite_report.processor (also benchmark.machine's): the model name of /proc/cpuinfo where it exists, its
    widest vector instructions, and OPENBLAS_CORETYPE when set (the kernels decide the solvers' round-off)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        import suite_report
    finally:
        sys.path.pop(0)
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
    plain = suite_report.processor()
    assert plain and "OPENBLAS_CORETYPE" not in plain
    if os.path.exists("/proc/cpuinfo"):
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            text = f.read()
        names = [line.split(":", 1)[1].strip() for line in text.splitlines() if line.startswith("model name")]
        assert not names or plain.startswith(names[0])
        assert ("avx2" in text.split()) <= ("avx" in plain)
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    assert suite_report.processor().endswith("OPENBLAS_CORETYPE=Haswell)")


def test_suite_report_names_failed_errored_and_skipped_tests(tmp_path):
    """The failed, errored and skipped tests of a run are named from pytest's JUnit XML (a failure in the test is
    failed, one in a fixture an error) and, when the run wrote no XML, from its -ra summary lines."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "scripts"))
    try:
        import suite_report
    finally:
        sys.path.pop(0)
    xml = tmp_path / "junit.xml"
    xml.write_text(
        '<testsuites><testsuite name="pytest">'
        '<testcase classname="tests.test_a" name="test_ok" time="0.1"/>'
        '<testcase classname="tests.test_a" name="test_bad[1]" time="0.2">'
        '<failure message="AssertionError: assert 1 == 2&#10;more">trace</failure></testcase>'
        '<testcase classname="tests.test_a.TestC" name="test_fixture" time="0.3">'
        '<error message="failed on setup with &quot;OSError: disk&quot;">trace</error></testcase>'
        '<testcase classname="tests.test_a" name="test_skip" time="0.0">'
        '<skipped type="pytest.skip" message="no compiler">skip</skipped></testcase>'
        '</testsuite></testsuites>')
    assert suite_report.parse_junit(xml) == [
        ("tests/test_a.py::test_ok", 0.1, "passed", ""),
        ("tests/test_a.py::test_bad[1]", 0.2, "failed", "AssertionError: assert 1 == 2"),
        ("tests/test_a.py::TestC::test_fixture", 0.3, "error", 'failed on setup with "OSError: disk"'),
        ("tests/test_a.py::test_skip", 0.0, "skipped", "no compiler")]
    out = ("....F\n=== short test summary info ===\nFAILED tests/test_a.py::test_bad[1] - assert 1 == 2\n"
           "ERROR tests/test_b.py::test_c\n1 failed, 1 error, 3 passed in 1.0s\n")
    assert suite_report.failures_in_output(out) == [("tests/test_a.py::test_bad[1]", "failed", "assert 1 == 2"),
                                                    ("tests/test_b.py::test_c", "error", "")]
    assert suite_report.render({"full": {
        "command": "c", "date": "d", "commit": "x", "tests": 3, "passed": 1, "failed": 2, "errors": 1, "skipped": 0,
        "wall_s": 1.0, "cpu_s": 1.0, "test_seconds": 1.0, "cores": 2, "jobs": "2", "load_start": [0, 0, 0],
        "load_end": [0, 0, 0], "slowest": [], "files": [], "skipped_tests": [],
        "failures": [["tests/test_a.py::test_bad[1]", "failed", "a | b"], ["tests/test_b.py::test_c", "error", ""]],
    }}).count("| `tests/test_a.py::test_bad[1]` | failed | a \\| b |") == 1


@pytest.mark.slow
def test_suite_report_writes_suite_md_from_its_own_run(tmp_path, monkeypatch):
    """scripts/suite_report.py runs each tier of a small suite whose counts are known (six tests: four pass,
    one of them slow, one is skipped, one fails) and writes suite.md from that run: the counts, the slowest
    test, the status, the speed probe before and after; a second run of one tier keeps the other tier's row."""
    tests = tmp_path / "fake"
    tests.mkdir()
    (tests / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow: slow\n")
    (tests / "test_fake.py").write_text(FAKE_TESTS)
    out = tmp_path / "out"
    status = suite_report_here(monkeypatch, "--jobs", "0", "--tests", str(tests), "--out-dir", str(out), "--",
                               *NO_PLUGINS)
    assert status == 1      # pytest's status: a test failed
    data = json.loads((out / "suite.json").read_text())
    assert (data["unit"]["tests"], data["unit"]["passed"], data["unit"]["failed"], data["unit"]["skipped"]) == \
        (5, 3, 1, 1)
    assert (data["full"]["tests"], data["full"]["passed"], data["full"]["failed"], data["full"]["skipped"]) == \
        (6, 4, 1, 1)
    assert data["full"]["slowest"][0][0] == "test_fake.py::test_slow" and data["full"]["slowest"][0][1] >= 0.3
    assert {n for n, _ in data["full"]["slowest"]} == {"test_fake.py::" + n for n in (
        "test_quick", "test_slow", "test_param[1]", "test_param[2]", "test_skipped", "test_fails")}
    assert data["full"]["wall_s"] >= 0.3 and data["unit"]["exit_status"] == 1
    assert data["full"]["command"].endswith(" ".join(NO_PLUGINS))     # the arguments after -- reach pytest
    text = (out / "suite.md").read_text()
    assert "| unit |" in text and "| full |" in text and "6 (4, 1, 1)" in text and "5 (3, 1, 1)" in text
    assert "`test_fake.py::test_slow`" in text and "scripts/suite_report.py" in text
    # the machine's speed before and after each tier: the loop's seconds, in the table
    for tier in ("unit", "full"):
        start, end = data[tier]["probe_s"]
        assert 0 < start < 60 and 0 < end < 60 and f"| {start:.2f} s, {end:.2f} s |" in text
    # the failed test is named, with its message, and so is the skipped one, with its reason
    for tier in ("unit", "full"):
        assert [n for n, _, _ in data[tier]["failures"]] == ["test_fake.py::test_fails"]
        assert data[tier]["failures"][0][1] == "failed" and "assert False" in data[tier]["failures"][0][2]
        assert data[tier]["skipped_tests"] == [["test_fake.py::test_skipped", "shown as skipped"]]
    assert "`test_fake.py::test_fails`" in text and "`test_fake.py::test_skipped` | shown as skipped" in text
    (tests / "test_fake.py").write_text(FAKE_TESTS.replace("assert False", "pass"))
    status = suite_report_here(monkeypatch, "--jobs", "0", "--tier", "unit", "--tests", str(tests), "--out-dir",
                               str(out), "--", *NO_PLUGINS)
    assert status == 0
    again = json.loads((out / "suite.json").read_text())
    assert again["full"] == data["full"] and (again["unit"]["passed"], again["unit"]["failed"]) == (4, 0)
    assert "6 (4, 1, 1)" in (out / "suite.md").read_text()


@pytest.mark.slow
def test_curve_families_script_runs_and_its_plans_land(tmp_path):
    """The study's quick run (the paper's case): every family's plan, from the planner or the script's own search,
    lands on the target when its figure eight is integrated by DOP853 along the leaves typed in tests/references.py
    (the printed (28)-(30)); the report names how each plan was found and what was concluded."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import references

    run_script_here("curve_families.py", tmp_path, "--quick")
    text = (tmp_path / "curve_families.md").read_text()
    assert "## Summary over the grid" in text and "## Conclusions" in text and "Non-stop with continuous" in text
    assert (tmp_path / "curve_families.png").stat().st_size > 1000
    rep = json.loads((tmp_path / "curve_families.json").read_text())
    assert rep["command"] == f"python scripts/curve_families.py --quick --out-dir {tmp_path}"   # not the caller's
    (row,) = rep["rows"]
    assert set(row["families"]) == {"circles", "viviani", "triangle", "square"}
    for name, f in row["families"].items():
        end = references.family_trace(name, f["a"], f["b"], row["k"], f["gamma"])
        assert abs(end[0] - 0.0) < 1e-8 and abs(end[1] - 1.0) < 1e-8, name
        assert abs(references.wrap(end[2])) < 1e-8, name
        assert f["source"] in ("planner", "search") and f["path_length"] > 0
    assert row["families"]["viviani"]["nonstop_continuous"] and not row["families"]["circles"]["nonstop_continuous"]
    if "search" in {f["source"] for f in row["families"].values()}:
        assert "## How the plans were found" in text


@pytest.mark.slow
def test_basepoint_bench_script_runs(tmp_path):
    run_script_here("basepoint_bench.py", tmp_path, "--quick")
    text = (tmp_path / "basepoint.md").read_text()
    assert "| README example |" in text and "| random 1 |" in text and "DOP853" in text
    assert "times of the first solve, which builds the solvers: not warm" in text    # --quick times no warm solve
    rows = json.loads((tmp_path / "basepoint.json").read_text())["rows"]
    assert all(r["any_length"] <= r["pole_length"] and r["dop853_residual"] <= 1e-9 for r in rows)


@pytest.mark.slow
def test_suite_report_measures_cold_by_default_and_warm_after_a_filling_run(tmp_path, monkeypatch):
    """A tier is measured cold (the tests' build cache off: ROLLPLAN_TEST_FRESH_CACHE set for the run) unless
    ``--warm``: then an unmeasured run comes first and both runs keep the build cache; the two measurements are
    kept under their own keys and both shown."""
    tests = tmp_path / "fake"
    tests.mkdir()
    (tests / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow: slow\n")
    log = tmp_path / "log"
    (tests / "test_env.py").write_text(
        "import os\n\ndef test_env():\n"
        f"    open({str(log)!r}, 'a').write(repr(os.environ.get('ROLLPLAN_TEST_FRESH_CACHE')) + '\\n')\n")
    out = tmp_path / "out"
    monkeypatch.setenv("ROLLPLAN_TEST_FRESH_CACHE", "1")
    for extra in ([], ["--warm"]):
        status = suite_report_here(monkeypatch, "--jobs", "0", "--tier", "unit", "--tests", str(tests), "--out-dir",
                                   str(out), *extra, "--", *NO_PLUGINS)
        assert status == 0
    assert log.read_text().splitlines() == ["'1'", "None", "None"]
    data = json.loads((out / "suite.json").read_text())
    assert (data["unit"]["cache"], data["unit, warm cache"]["cache"]) == ("fresh", "warm")
    text = (out / "suite.md").read_text()
    assert "| unit |" in text and "| unit, warm cache |" in text


@pytest.mark.parametrize("name", ["embedded_report.py", "reconfiguration.py"])
def test_a_quick_run_never_writes_over_the_full_results(tmp_path, name):
    """``--quick`` makes a partial report: without ``--out-dir`` it is refused in one line (exit 2) and nothing is
    written, so the full report in results/ is never replaced by a quick one."""
    script = Path(__file__).resolve().parent.parent / "scripts" / name
    run = subprocess.run([sys.executable, str(script), "--quick"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, check=False)
    assert run.returncode == 2 and len(run.stderr.strip().splitlines()) == 1 and "--out-dir" in run.stderr
    assert not any(tmp_path.iterdir())
