"""Where a study's chunks run: in this process, on a local pool of processes, or on a Dask
cluster. Each runner calls ``done(rows)`` with a chunk's rows as soon as it finishes.

* **serial**: the chunks in order, in this process (progress after every sample).
* **processes** (``--workers K``): a pool of K fresh (spawned) processes. A worker that dies
  breaks the pool; the pool is started again and the unfinished chunks resubmitted (up to
  :data:`RETRIES` times), so the study completes.
* **dask** (``--scheduler ADDRESS``, or ``$DASK_SCHEDULER_ADDRESS``): ``Client(address)``; the
  scheduler reruns the tasks of a worker that dies on the others. An address that does not
  answer within :data:`CONNECT_TIMEOUT` is bad input; a cluster with no worker left for
  :data:`NO_WORKER_TIMEOUT` loses the unfinished samples instead of hanging.

A chunk that cannot be finished even so comes back as one failure row per sample (status
``lost``, with the reason): no sample is ever missing from a study.
"""
import os
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool

from ...errors import ScenarioError, flag
from .worker import solve_chunk, solve_chunk_from

#: times a local pool is restarted after a worker died
RETRIES = 3
#: seconds to wait for a Dask scheduler to answer
CONNECT_TIMEOUT = 5
#: seconds a Dask study waits while its cluster has no worker at all before the unfinished
#: samples are lost (failure rows that say so) instead of waiting for ever
NO_WORKER_TIMEOUT = 120
#: seconds between looks at a Dask cluster's workers while no task finishes
POLL_INTERVAL = 1.0


def executor_of(workers=None, scheduler=None):
    """``(kind, description)`` of where a study runs: ``serial``, ``processes`` or ``dask``."""
    if workers is not None and scheduler is not None:
        raise ScenarioError(f"study: give {flag('--workers')} or {flag('--scheduler')}, not both")
    if workers is not None and workers < 1:
        raise ScenarioError(f"study: {flag('--workers')} {workers}; give at least 1")
    scheduler = scheduler or (None if workers else os.environ.get("DASK_SCHEDULER_ADDRESS"))
    if scheduler is not None:
        return "dask", scheduler
    if workers and workers > 1:
        return "processes", workers
    return "serial", 1


def run_serial(chunks, done, on_sample=None):
    """The chunks in this process, in order; a chunk whose first sample follows the last one
    solved (``Chunk.after``: the next in its group, not skipped by ``resume``) starts from
    its answer, as the samples within a chunk do, instead of cold from the reference state
    (a cold start is 3 % of the bending module's temperature box)."""
    last, answer = None, None
    for chunk in chunks:
        start = answer if chunk.ids and chunk.after is not None and chunk.after == last else None
        rows, answer = solve_chunk_from(chunk, progress=on_sample, start=start)
        last = chunk.ids[-1] if chunk.ids else None
        done(chunk, rows)


def run_processes(chunks, done, workers, lost):
    """The chunks on a pool of ``workers`` spawned processes; ``lost(chunk, reason)`` for a
    chunk that could not be run."""
    import multiprocessing
    pending = list(chunks)
    for attempt in range(RETRIES + 1):
        if not pending:
            return
        with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
            futures = {pool.submit(solve_chunk, chunk): chunk for chunk in pending}
            broken = []
            while futures:
                finished, _ = wait(futures, return_when=FIRST_COMPLETED)
                for future in finished:
                    chunk = futures.pop(future)
                    try:
                        rows = future.result()
                    except BrokenProcessPool:
                        broken.append(chunk)
                        continue
                    except Exception as exc:      # a bug in a worker: said in the chunk's rows
                        lost(chunk, f"{type(exc).__name__}: {exc}")
                        continue
                    done(chunk, rows)
        pending = broken
    for chunk in pending:
        lost(chunk, f"a worker process died {RETRIES + 1} times running these samples (from a Python "
                    "script, guard the code that starts the study with if __name__ == '__main__':)")


def connect(scheduler):
    """A ``dask.distributed.Client`` of the scheduler at ``scheduler`` (an address, or a Client
    given by the caller); ScenarioError if it does not answer within :data:`CONNECT_TIMEOUT`."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise ScenarioError(f"study {flag('--scheduler')} needs dask.distributed: pip install 'tca_casadi[studies]'") from None
    if isinstance(scheduler, Client):
        return scheduler, False
    try:
        return Client(scheduler, timeout=f"{CONNECT_TIMEOUT}s", set_as_default=False), True
    except (OSError, TimeoutError, ValueError) as exc:
        raise ScenarioError(f"study: no Dask scheduler answers at {scheduler!r} within {CONNECT_TIMEOUT} s "
                            f"({type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else 'no reply'})") from None


def run_dask(chunks, done, scheduler, lost, no_worker_timeout=None):
    """The chunks as tasks on a Dask cluster. A task whose result cannot be had (its worker
    died after computing it, or the scheduler gave up on it: KilledWorker) is submitted again,
    up to :data:`RETRIES` times; then ``lost(chunk, reason)``. A cluster left without a single
    worker for ``no_worker_timeout`` seconds (default :data:`NO_WORKER_TIMEOUT`) loses the
    unfinished chunks, with that reason, instead of waiting for ever."""
    import time
    timeout = NO_WORKER_TIMEOUT if no_worker_timeout is None else no_worker_timeout
    client, owned = connect(scheduler)
    try:
        futures = {client.submit(solve_chunk, chunk, pure=False): chunk for chunk in chunks}
        attempts, alone_since, looked = {}, None, time.monotonic()
        while futures:
            finished = [future for future in futures if future.done()]
            if not finished:
                time.sleep(0.01)
                if time.monotonic() - looked < POLL_INTERVAL:
                    continue
                looked = time.monotonic()
                alone_since = None if client.nthreads() else (alone_since or time.monotonic())
                if alone_since is not None and time.monotonic() - alone_since >= timeout:
                    for future, chunk in futures.items():
                        future.cancel()
                        lost(chunk, f"Dask: the scheduler had no worker for {timeout:g} s (start workers "
                                    f"with: dask worker {_address(client)})")
                    return
                continue
            for future in finished:
                chunk = futures.pop(future)
                try:
                    rows = future.result()
                except Exception as exc:          # the cluster's failures, whatever their class
                    attempts[id(chunk)] = attempts.get(id(chunk), 0) + 1
                    if attempts[id(chunk)] <= RETRIES:
                        futures[client.submit(solve_chunk, chunk, pure=False)] = chunk
                    else:
                        lost(chunk, f"Dask: {type(exc).__name__}: {exc}")
                    continue
                done(chunk, rows)
    finally:
        if owned:
            client.close()


def _address(client):
    """The scheduler's address, for messages."""
    return getattr(client, "scheduler", None) and client.scheduler.address or "ADDRESS"


def describe(kind, target):
    """Where it ran, for study.json: ``serial``, ``processes: 2``, ``dask: tcp://...``."""
    if kind == "serial":
        return "serial"
    if kind == "processes":
        return f"processes: {target}"
    address = getattr(target, "scheduler", None)
    address = getattr(address, "address", None) or str(target)
    return f"dask: {address}"
