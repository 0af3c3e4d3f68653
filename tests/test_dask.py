"""Batch planning and atlases on a Dask distributed cluster (``--scheduler ADDRESS``): a real local cluster
with worker processes gives the same output, line by line, as a run in this process, with the same
resume and failure semantics. Skipped only if Dask distributed is not installed (it is in the test extra)."""

import json

import numpy as np
import pytest
from test_batch import check_lines, strip_times, write_csv

from rollplan import cli
from rollplan.errors import InputError
from rollplan.studies import executor
from rollplan.studies.atlas import compute_atlas, compute_atlases
from rollplan.studies.batch import read_output, run_batch

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module", autouse=True)
def distributed():
    """Dask distributed (every test here skips without it), imported when a test of this module runs: not by a
    run that only collects the module (the unit tier, -m "not slow")."""
    return pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster(distributed):
    """Two worker processes with one thread each, on this machine. A task is lost (KilledWorker) the first
    time its worker dies instead of the fourth (Dask's default), so the lost-task test restarts one worker,
    not three."""
    import dask

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                     silence_logs=50) as c:
        yield c.scheduler_address


@pytest.fixture(scope="module")
def local_run(tmp_path_factory):
    """The rows of test_batch run in this process, one by one: ``(result, lines without the solver times)``, the
    reference of the runs on the cluster."""
    folder = tmp_path_factory.mktemp("local")
    r = run_batch(write_csv(folder / "t.csv"), folder / "local.jsonl", jobs=1)
    return r, strip_times(read_output(folder / "local.jsonl"))


def test_batch_on_the_cluster_equals_a_local_run(tmp_path, cluster, local_run):
    csv_path = write_csv(tmp_path / "t.csv")
    remote = tmp_path / "dask.jsonl"
    r_local, local_lines = local_run
    r_dask = run_batch(csv_path, remote, scheduler=cluster)
    assert (r_dask.total, r_dask.planned, r_dask.failed, r_dask.failed_total) == \
        (r_local.total, r_local.planned, r_local.failed, r_local.failed_total) == (6, 6, 3, 3)
    lines = read_output(remote)
    check_lines(lines)   # same order, same failures with their reasons, plans on target
    assert strip_times(lines) == local_lines


def test_interrupted_local_run_resumed_on_the_cluster(tmp_path, cluster, local_run):
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "p.jsonl"

    def stop_after_two(done, total, failed):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(csv_path, out, progress=stop_after_two)
    kept = out.read_bytes()
    r = run_batch(csv_path, out, resume=True, scheduler=cluster)
    assert (r.skipped, r.planned, r.failed_total) == (2, 4, 3)
    assert out.read_bytes().startswith(kept)
    check_lines(read_output(out))
    assert strip_times(read_output(out)) == local_run[1]   # as a whole run in this process


def test_cli_batch_on_the_cluster(tmp_path, cluster, capsys):
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "p.jsonl"
    assert cli.main(["batch", str(csv_path), "--out", str(out), "--scheduler", cluster, "--quiet"]) == 1
    check_lines(read_output(out))
    assert "3 of 6 rows failed" in capsys.readouterr().err


def test_a_lost_task_is_a_failed_row(tmp_path, cluster):
    """A task whose worker dies is recorded as a failed row (never dropped); the others are planned."""
    with executor.Executor(scheduler=cluster) as ex:
        results = list(ex.map(_die_on_two, [1, 2, 3], on_error=lambda item, exc: ("failed", item,
                                                                                  type(exc).__name__)))
    assert results[0] == 1 and results[2] == 3
    assert results[1][:2] == ("failed", 2) and results[1][2] == "KilledWorker"


def test_a_lost_scheduler_fails_the_run_not_the_rows(tmp_path, distributed):
    """When the scheduler went away mid-run, every pending row was written as failed ('scheduler-connection-lost')
    and --resume never planned them again; now the run stops with ExecutorError (the CLI: exit 4, finished lines
    kept for --resume) and no row is recorded as failed.

    What is lost is the client's connection to the scheduler, over TCP as with a remote cluster; where the worker
    runs does not matter, so it is a thread of this process (no worker process to start). Its rows sleep 0.5 s:
    long enough to be pending when the scheduler closes (a few ms after the first row), short enough that the
    worker's own shutdown does not wait for them long."""
    import time

    import dask

    failed = []
    with dask.config.set({"distributed.comm.timeouts.connect": "1s"}), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                                     dashboard_address=None, silence_logs=50) as c, \
            executor.Executor(scheduler=c.scheduler_address) as ex, \
            pytest.raises(executor.ExecutorError, match="scheduler"):
        for i, _ in enumerate(ex.map(time.sleep, [0.05] + [0.5] * 5,
                                     on_error=lambda item, exc: failed.append((item, exc)))):
            if i == 0:
                c.sync(c.scheduler.close)   # the scheduler goes away while five rows are pending
    assert failed == []


def _die_on_two(x):
    if x == 2:
        import os

        os._exit(1)   # the worker process dies (as on a segfault)
    return x


def test_atlas_sweep_on_the_cluster_equals_local(cluster):
    here = compute_atlases([1.0, 2.5], steps=2, resolution=7)
    there = compute_atlases([1.0, 2.5], steps=2, resolution=7, scheduler=cluster)
    for a, b in zip(here, there):
        assert a.k == b.k and a.fold_cells == b.fold_cells
        for name in ("h", "eta", "det", "shift_total", "turn_total"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
    one = compute_atlas(2.5, steps=2, resolution=7, scheduler=cluster)
    assert np.array_equal(one.h, here[1].h)


def test_cli_atlas_sweep_on_the_cluster(tmp_path, cluster):
    out, js = str(tmp_path / "atlas_k{k}.png"), str(tmp_path / "atlas_k{k}.json")
    assert cli.main(["atlas", "--k", "1", "2.5", "--resolution", "5", "--out", out, "--json", js,
                     "--scheduler", cluster]) == 0
    for k in ("1", "2.5"):
        assert (tmp_path / f"atlas_k{k}.png").stat().st_size > 10000
        assert json.loads((tmp_path / f"atlas_k{k}.json").read_text())["k"] == float(k)


def test_unreachable_scheduler_is_bad_input(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(executor, "CONNECT_TIMEOUT", 0.3)   # nothing listens: refused at once
    with pytest.raises(InputError, match="cannot be reached"):
        run_batch(write_csv(tmp_path / "t.csv"), tmp_path / "p.jsonl", scheduler="tcp://127.0.0.1:9")
    assert not (tmp_path / "p.jsonl").exists()   # refused before the output was touched
    assert cli.main(["batch", str(tmp_path / "t.csv"), "--out", str(tmp_path / "p.jsonl"),
                     "--scheduler", "tcp://127.0.0.1:9"]) == 2
    err = capsys.readouterr().err
    assert "cannot be reached" in err and len(err.strip().splitlines()) == 1


def test_closed_loop_monte_carlo_on_the_cluster_equals_local(cluster):
    """The closed-loop study's Monte Carlo (issue 13) is a map of one function over cases: on the cluster it
    gives the same runs, in the same order, as in this process (deterministic seeds, same arithmetic)."""
    from rollplan.studies.closed_loop import run_cases

    cases = [{"kind": kind, "error": 0.05, "seed": seed, "noise": 0.0, "plant": "rates", "steps": 2,
              "piece_duration": 2.0} for kind, seed in (("k", 0), ("J_r", 1))]
    here = run_cases(cases, workers=1)
    there = run_cases(cases, scheduler=cluster)
    for a, b in zip(here, there, strict=True):
        assert a["failed"] is None and b["failed"] is None
        assert (a["kind"], a["seed"], a["open"], a["closed"], a["estimated_k"]) == \
            (b["kind"], b["seed"], b["open"], b["closed"], b["estimated_k"])
        assert a["closed"] < 0.05 * a["open"]   # the feedback works on the cluster as here
