"""A study on a local pool of processes and on a real Dask cluster (a scheduler and two worker
processes on 127.0.0.1, started here): the same rows as in one process, and a worker killed in
the middle of the study does not lose a sample."""
import contextlib
import json
import multiprocessing
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from numpy.testing import assert_allclose

import tca_casadi as tc
from tca_casadi.studies.batch.study import Study

distributed = pytest.importorskip("distributed")

TEMPERATURES = ["bending.tca1.temperature", "bending.tca2.temperature", "bending.tca3.temperature"]
TIP = ["tip_x [m]", "tip_y [m]", "tip_z [m]"]


@contextlib.contextmanager
def _port_taken(port=8787):
    """Hold ``port`` on 127.0.0.1 (Dask's default dashboard port) if it is free, as another
    program might: the clusters below must not depend on it."""
    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", port))
        holder.listen()
    except OSError:                       # already taken by something else: as good
        pass
    try:
        yield
    finally:
        holder.close()


@pytest.fixture(scope="module")
def cluster():
    """A LocalCluster: its own scheduler and two single-threaded worker processes on 127.0.0.1,
    started while port 8787 is taken (the HTTP server on a free port: ``:0``)."""
    with _port_taken(), distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                                 host="127.0.0.1", dashboard_address=":0",
                                                 scheduler_port=0) as local:
        with distributed.Client(local) as client:
            client.wait_for_workers(2, timeout=60)
            yield local


def _study(scenarios, samples=40):
    sim = tc.Simulation.from_file(scenarios / "bending_module.yaml")
    return Study(sim, vary={p: [25, 125] for p in TEMPERATURES}, design="sobol", samples=samples, seed=5)


def test_serial_processes_and_dask_give_the_same_rows(scenarios, cluster):
    serial = _study(scenarios).run()
    pooled = _study(scenarios).run(workers=2)
    on_dask = _study(scenarios).run(scheduler=cluster.scheduler_address)
    for other in (pooled, on_dask):
        assert len(other.frame) == 40 and other.frame["converged"].all()
        assert_allclose(other.frame[TIP].to_numpy(float), serial.frame[TIP].to_numpy(float), rtol=0, atol=1e-9)
        tensions = [c for c in serial.frame.columns if c.endswith(".tension [N]")]
        assert_allclose(other.frame[tensions].to_numpy(float), serial.frame[tensions].to_numpy(float),
                        rtol=1e-8, atol=1e-13)
    assert pooled.info["ran_on"] == "processes: 2" and pooled.frame["worker"].nunique() == 2
    assert on_dask.info["ran_on"].startswith("dask: tcp://127.0.0.1:") and on_dask.info["workers"] == 2
    assert on_dask.frame["worker"].nunique() == 2


def _kill_one_when_started(kill, started):
    """``progress`` that kills a worker (``kill()``) once the first chunk is back."""
    def progress(fraction, text):
        if not started.is_set():
            started.set()
            kill()
    return progress


def test_a_killed_dask_worker_loses_no_sample(scenarios, cluster):
    client = distributed.Client(cluster.scheduler_address)
    try:
        pids = list(client.run(os.getpid).values())
        started = threading.Event()
        result = _study(scenarios, 160).run(scheduler=client,
                                            progress=_kill_one_when_started(lambda: os.kill(pids[0], signal.SIGKILL), started))
        assert started.is_set()
        failed = result.frame[~result.frame["converged"]]
        assert len(result.frame) == 160 and failed.empty, failed[["sample", "status", "message", "worker"]].to_string()
        assert sorted(result.frame["sample"]) == list(range(160))
        client.wait_for_workers(2, timeout=60)          # the nanny started a new one
        assert pids[0] not in client.run(os.getpid).values()
    finally:
        client.close()


def test_a_killed_pool_process_loses_no_sample(scenarios):
    def kill():
        workers = [p for p in multiprocessing.active_children() if p.name.startswith("SpawnProcess")]
        os.kill(workers[0].pid, signal.SIGKILL)

    started = threading.Event()
    result = _study(scenarios, 160).run(workers=2, progress=_kill_one_when_started(kill, started))
    assert started.is_set()
    assert len(result.frame) == 160 and result.frame["converged"].all()
    assert result.frame["worker"].nunique() >= 3            # the pool was started again
    serial = _study(scenarios, 160).run()
    assert_allclose(result.frame[TIP].to_numpy(float), serial.frame[TIP].to_numpy(float), rtol=0, atol=1e-9)
    checked = result.frame["balance [-]"].dropna()          # every 25th sample of a chunk and its last
    assert len(checked) >= 2 and np.all(checked < 1e-9)


def test_cli_on_the_cluster(scenarios, cluster, tmp_path, capsys):
    """``tca-casadi study --scheduler ADDRESS``: the same command on the cluster."""
    from tca_casadi.cli import main
    code = main(["study", str(scenarios / "bending_module.yaml"), "--vary", "bending.tca2.temperature=25:125:4",
                 "--vary", "bending.tca3.temperature=25:125:3", "--scheduler", cluster.scheduler_address,
                 "-o", str(tmp_path), "--quiet", "--no-plot"])
    assert code == 0
    assert "12 samples (grid), 12 converged" in capsys.readouterr().out
    info = __import__("json").loads((tmp_path / "study.json").read_text())
    assert info["ran_on"] == f"dask: {cluster.scheduler_address}" and info["workers"] == 2


@contextlib.contextmanager
def _dask_command_line_cluster(directory, workers=2):
    """A scheduler and ``workers`` single-threaded workers started by the ``dask`` command line
    as a user would (on 127.0.0.1, free ports, while 8787 is taken); yields the address."""
    dask = [sys.executable, "-m", "distributed.cli.dask_scheduler"]
    file = directory / "scheduler.json"
    processes = []
    with _port_taken():
        try:
            processes.append(subprocess.Popen(
                [*dask, "--host", "127.0.0.1", "--port", "0", "--dashboard-address", ":0",
                 "--scheduler-file", str(file)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            deadline = time.monotonic() + 60
            while not file.exists() and time.monotonic() < deadline:
                time.sleep(0.1)
            address = json.loads(file.read_text())["address"]
            for _ in range(workers):
                processes.append(subprocess.Popen(
                    [sys.executable, "-m", "distributed.cli.dask_worker", address, "--nthreads", "1",
                     "--host", "127.0.0.1", "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            with distributed.Client(address, timeout="30s") as client:
                client.wait_for_workers(workers, timeout=60)
            yield address
        finally:
            for process in reversed(processes):
                process.terminate()
            for process in processes:
                process.wait(timeout=30)


def test_cli_in_a_fresh_process_on_a_cluster_started_by_the_dask_command(scenarios, tmp_path):
    """The user's way: ``dask scheduler`` and two ``dask worker`` processes, then ``tca-casadi
    study --scheduler`` in a fresh process (no default client left by any other test): the
    rows equal the serial run's."""
    command = [sys.executable, "-m", "tca_casadi.cli", "study", str(scenarios / "bending_module.yaml"),
               "--vary", "bending.tca2.temperature=25:125:4", "--vary", "bending.tca3.temperature=25:125:3",
               "--quiet", "--no-plot"]
    serial = subprocess.run([*command, "-o", str(tmp_path / "serial")], capture_output=True, text=True)
    assert serial.returncode == 0, serial.stderr
    with _dask_command_line_cluster(tmp_path) as address:
        run = subprocess.run([*command, "--scheduler", address, "-o", str(tmp_path / "dask")],
                             capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "12 samples (grid), 12 converged" in run.stdout
    info = json.loads((tmp_path / "dask" / "study.json").read_text())
    assert info["ran_on"] == f"dask: {address}" and info["workers"] == 2
    import pandas
    on_dask = pandas.read_parquet(tmp_path / "dask" / "study.parquet").sort_values("sample")
    alone = pandas.read_parquet(tmp_path / "serial" / "study.parquet").sort_values("sample")
    assert on_dask["worker"].nunique() == 2
    assert_allclose(on_dask[TIP].to_numpy(float), alone[TIP].to_numpy(float), rtol=0, atol=1e-12)


def test_a_cluster_without_workers_loses_the_samples_instead_of_hanging():
    """A scheduler whose workers are all gone (never started here): after the wait the chunks
    come back lost, with the reason, and nothing is left running."""
    from tca_casadi.studies.batch.executors import run_dask
    with _port_taken(), distributed.LocalCluster(n_workers=0, host="127.0.0.1",
                                                 dashboard_address=":0", scheduler_port=0) as alone:
        lost, done = [], []
        start = time.monotonic()
        run_dask([("chunk", 1), ("chunk", 2)], lambda chunk, rows: done.append(chunk), alone.scheduler_address,
                 lambda chunk, reason: lost.append((chunk, reason)), no_worker_timeout=2)
        waited = time.monotonic() - start
    assert not done and sorted(chunk for chunk, _ in lost) == [("chunk", 1), ("chunk", 2)]
    assert all("had no worker for 2 s" in reason and "dask worker tcp://127.0.0.1:" in reason for _, reason in lost)
    assert 2 <= waited < 30
