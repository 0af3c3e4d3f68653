"""Progress on stderr (rollplan.progress): tqdm bars on a terminal, periodic plain lines otherwise (a log
file holds readable lines, no carriage returns), nothing for short work, and reports from deep loops."""

import io
import re
import time

from rollplan.progress import Progress, report, reporting


def test_plain_lines_when_the_stream_is_not_a_terminal():
    buf = io.StringIO()
    with Progress(stream=buf, interval=0.0, unit="targets") as progress:
        for i in range(4):
            progress("batch", i, 3 if i < 3 else 3, failed=1)
    text = buf.getvalue()
    assert "\r" not in text
    lines = text.splitlines()
    assert lines[0].startswith("batch: 0/3 targets (0%), 1 failed")
    assert lines[-1].startswith("batch: 3/3 targets (100%), 1 failed") and "elapsed" in lines[-1]
    assert any("left" in line for line in lines[1:-1])   # an estimate of the time left
    assert sum(line.startswith("batch: 3/3") for line in lines) == 1   # the last line once


def test_plain_lines_are_periodic():
    buf = io.StringIO()
    progress = Progress(stream=buf, interval=3600.0)
    for i in range(101):
        progress("sweep", i, 100)
    progress.close()
    lines = buf.getvalue().splitlines()
    assert [line.split(" (")[0] for line in lines] == ["sweep: 0/100", "sweep: 100/100"]   # the first and the last


def test_short_work_shows_nothing():
    buf = io.StringIO()
    with Progress(stream=buf, delay=60.0) as progress:
        for i in range(11):
            progress("quick", i, 10)
    assert buf.getvalue() == ""


def test_delay_then_lines():
    buf = io.StringIO()
    with Progress(stream=buf, delay=0.05, interval=0.0) as progress:
        progress("slow", 0, 2)
        time.sleep(0.08)
        progress("slow", 1, 2)
        progress("slow", 2, 2)
    assert re.findall(r"slow: (\d)/2", buf.getvalue()) == ["1", "2"]


def test_tqdm_bar_on_a_terminal():
    buf = io.StringIO()
    with Progress(stream=buf, terminal=True) as progress:
        progress("h(k) sweep", 1, 3)
        time.sleep(0.15)   # tqdm redraws at most every 0.1 s
        progress("h(k) sweep", 3, 3)
    text = buf.getvalue()
    assert "h(k) sweep: " in text and "3/3" in text and "\r" in text


def test_disabled_shows_nothing():
    buf = io.StringIO()
    with Progress(stream=buf, enabled=False) as progress:
        progress("x", 1, 1)
    assert buf.getvalue() == ""


def test_a_label_started_again_is_a_new_report():
    buf = io.StringIO()
    with Progress(stream=buf, interval=3600.0) as progress:
        for _ in range(2):
            for i in range(3):
                progress("trace", i + 1, 3)
    assert re.findall(r"trace: (\d)/3", buf.getvalue()) == ["1", "3", "1", "3"]


def test_report_reaches_the_installed_progress_only():
    report("nobody", 1, 2)   # nothing installed: nothing happens
    buf = io.StringIO()
    with reporting(Progress(stream=buf, interval=0.0)):
        report("deep loop", 2, 2)
    report("nobody", 2, 2)
    assert buf.getvalue().startswith("deep loop: 2/2 (100%)")


def test_the_cvodes_trace_of_many_steps_reports(planner):
    buf = io.StringIO()
    with reporting(Progress(stream=buf, interval=0.0)):
        planner.cvodes.final(0.3, 0.3, 2.5, 0.0, 3)
    assert re.findall(r"CVODES trace, steps: (\d)/3", buf.getvalue()) == ["1", "2", "3"]


def test_tqdm_bar_on_a_terminal_waits_for_its_delay():
    """On a terminal the bar too shows only once the work has gone on for the delay (tqdm's own delay): none for
    work shorter than it, a bar after it."""
    quick, slow = io.StringIO(), io.StringIO()
    for buf, seconds in ((quick, 0.05), (slow, 0.6)):
        with Progress(stream=buf, terminal=True, delay=0.3) as progress:
            t0 = time.monotonic()
            i = 0
            while time.monotonic() - t0 < seconds:
                progress("sweep", i, 10**6)
                i += 1
                time.sleep(0.01)
    assert quick.getvalue() == ""
    assert "sweep: " in slow.getvalue() and "\r" in slow.getvalue()
