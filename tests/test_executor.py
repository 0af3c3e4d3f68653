"""The executor (rollplan.studies.executor): results in the order of the items, in this process or in
local worker processes; bad options refused before any work; without Dask installed, --scheduler names the
extra to install. The Dask backend is tested in ``tests/test_dask.py``."""

import os
import sys

import pytest
from conftest import run_program

from rollplan.errors import InputError
from rollplan.studies.executor import DASK_EXTRA, Executor, map_in_order


def _square_slowly_first(x):
    import time

    time.sleep(0.2 if x == 0 else 0.0)   # the first item finishes last
    return x * x, os.getpid()


@pytest.mark.parametrize("jobs", [1, 2])
def test_results_in_input_order(jobs):
    seen = []
    out = map_in_order(_square_slowly_first, range(8), jobs=jobs, progress=lambda *a: seen.append(a))
    assert [r for r, _ in out] == [x * x for x in range(8)]
    assert seen[-1] == ("tasks", 8, 8) and len(seen) == 8
    pids = {pid for _, pid in out}
    assert (pids == {os.getpid()}) if jobs == 1 else (os.getpid() not in pids)


def test_empty_and_single_item():
    assert map_in_order(_square_slowly_first, [], jobs=2) == []
    assert map_in_order(_square_slowly_first, [3], jobs=2)[0][0] == 9


def _fail_on_three(x):
    if x == 3:
        raise ValueError("three")
    return x


@pytest.mark.parametrize("jobs", [1, 2])
def test_an_escaping_exception_stops_the_run(jobs):
    with pytest.raises(ValueError, match="three"):
        map_in_order(_fail_on_three, range(6), jobs=jobs)


@pytest.mark.parametrize("kwargs, match", [({"jobs": 0}, "jobs = 0"), ({"jobs": 1.5}, "jobs = 1.5"),
                                           ({"scheduler": ""}, "scheduler"), ({"scheduler": 8786}, "scheduler")])
def test_bad_options(kwargs, match):
    with pytest.raises(InputError, match=match):
        Executor(**kwargs)


def test_scheduler_without_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)   # import distributed -> ImportError
    with pytest.raises(InputError) as err, Executor(scheduler="tcp://127.0.0.1:8786"):
        pass
    assert DASK_EXTRA in str(err.value) and "\n" not in str(err.value)


def test_no_fork_while_other_threads_run():
    """Forking a process that runs other threads (e.g. a Dask client's) can deadlock the workers: spawn then."""
    import multiprocessing
    import threading

    from rollplan.studies.executor import start_method

    stop = threading.Event()
    t = threading.Thread(target=stop.wait, daemon=True)
    t.start()
    try:
        assert start_method() == "spawn"
        with Executor(2) as ex:
            assert list(ex.map(abs, [-1, -2, 3])) == [1, 2, 3]
    finally:
        stop.set()
        t.join()
    if "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1:
        assert start_method() == "fork"


_FIRST_HERE = """
import os
from rollplan.studies.executor import Executor, start_method

BUILT = []

def build_lazily(x):
    if not BUILT:   # what an item builds lazily, once per process (e.g. the tables of its k)
        BUILT.append(os.getpid())
    return x, os.getpid(), BUILT[0]

def fail_on_three(x):
    if x == 3:
        raise ValueError("three")
    return x

if __name__ == "__main__":
    assert start_method() == "fork", start_method()
    with Executor(2, first_here=True) as ex:
        out = list(ex.map(build_lazily, range(7)))
    assert [x for x, _, _ in out] == list(range(7)), out
    assert out[0][1] == os.getpid() and all(pid != os.getpid() for _, pid, _ in out[1:]), out
    assert {built for _, _, built in out} == {os.getpid()}, out
    try:
        with Executor(2, first_here=True) as ex:
            list(ex.map(fail_on_three, range(6)))
    except ValueError as e:
        assert "three" in str(e)
    else:
        raise AssertionError("no ValueError")
    print("ok")
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork start method: Linux only")
def test_first_item_here_and_the_forked_workers_share_what_it_built(tmp_path):
    """first_here: item 0 runs in the parent before the fork; the workers get the rest and find built what it
    built (nothing is built twice). Run in a fresh interpreter: the test process itself may run other threads
    (then the executor rightly spawns instead of forking)."""
    done = run_program(tmp_path, "first_here.py", _FIRST_HERE)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


def test_chunk_size():
    from rollplan.studies.executor import CHUNK_SECONDS, chunk_size

    assert chunk_size(None, 1000, 2) == 1                      # unknown item time: one at a time
    assert chunk_size(2 * CHUNK_SECONDS, 1000, 2) == 1         # long items: one at a time
    assert chunk_size(CHUNK_SECONDS / 5, 1000, 2) == 5         # short ones: CHUNK_SECONDS of work
    assert chunk_size(1e-9, 160, 2) == 10                      # at most an eighth of a worker's share
    assert chunk_size(1e-9, 3, 2) == chunk_size(0.0, 3, 2) == chunk_size(float("nan"), 3, 2) == 1
