"""soadyn.sweep: run a sweep file's cases on Dask distributed (or in this process), resumably.

Also the `soadyn sweep` command: python3 -m soadyn sweep SWEEP.yaml [-o DIR] [--scheduler ADDRESS]
[--workers N] [--batch-size N] [--keep-logs] [--drop-bad-parts] [--force] [-q].

Output directory:
    DIR/sweep.lock       held (flock) by the sweep writing into DIR, its pid and sweep file inside:
                         a second sweep into DIR while one runs is refused, naming the first
    DIR/sweep.json       the sweep's fingerprint (sweep file, base scenario, soadyn version) and size
    DIR/parts/*.json     one file per finished batch, its rows (written atomically, by the worker
                         on an embedded cluster, else by this process)
    DIR/results.h5       the table, a row per case in case order (rebuilt at the end of each run);
                         one that is not a soadyn sweep's table is refused before anything is
                         written, unless --force
Every file is built under a new NAME.XXXXXXXX.tmp (O_EXCL | O_NOFOLLOW, a random name) and renamed
into place; the lock's holder removes the ones writers killed before their rename left.
    DIR/logs/case-N.h5   each case's run log, with --keep-logs (written by the worker)

A part this sweep did not write (not a JSON list of rows with exactly the result columns of the
right types, a case outside the sweep, more than _sweep_store.py's MAX_PART_BYTES) stops the sweep,
naming the part, its row and column: nothing is used or removed unasked.  --drop-bad-parts (drop_bad_parts=True)
sets each such part aside as NAME.bad, where no sweep reads it, and runs its cases again.
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import time
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from ._soadyn import Error
from ._batched import run_batch
from ._sweep_store import _lock, _open_store, _read_parts, _save_part, _table, check_results_path, write_results
from ._yaml_doc import printable
from .ensemble import Sweep


@dataclasses.dataclass
class SweepResult:
    """What soadyn.sweep returns: .table (column name -> numpy array, a row per case in case
    order), .path (results.h5), .ran (cases run now), .skipped (cases already done before),
    .failed (cases whose run did not complete), .wall_seconds."""

    table: Dict[str, np.ndarray]
    path: str
    ran: int
    skipped: int
    failed: int
    wall_seconds: float

    def __repr__(self):
        n = len(self.table["case"])
        return f"SweepResult({n} cases, {self.failed} failed, ran {self.ran}, skipped {self.skipped}, {self.path!r})"


# ---------------------------------------------------------------- batches and progress

def _batches(sw: Sweep, todo: List[int], size: Optional[int], nworkers: int = 1) -> List[List[int]]:
    """The cases in tasks of `size`, or with size None in guided sizes: each task a 1/(3 workers)
    share of the cases not yet given out, between 20 and 1000 (few tasks for the scheduler while
    much is left, small ones at the end so that no worker idles while another ends a long one).
    Cases that share a reference run (same values outside simulation.*) stay in one task."""
    def target(left: int) -> int:
        return size or min(1000, max(20, math.ceil(left / (3 * nworkers))))

    if sw.reference:
        groups: Dict[str, List[int]] = {}
        for i in todo:
            key = json.dumps({p: v for p, v in sw.cases[i].items() if not p.startswith("simulation.")}, sort_keys=True)
            groups.setdefault(key, []).append(i)
        units = list(groups.values())
    else:
        units = [[i] for i in todo]
    batches, cur, left = [], [], len(todo)
    for ids in units:
        cur += ids
        if len(cur) >= target(left):
            batches.append(cur)
            left -= len(cur)
            cur = []
    if cur:
        batches.append(cur)
    return batches


def _counts(rows: List[dict]) -> Tuple[int, int]:
    """(cases, cases whose run did not complete): what the progress line counts of a batch."""
    return len(rows), sum(1 for r in rows if not r["completed"])


class _Progress:
    def __init__(self, total: int, skipped: int, quiet: bool):
        self.total, self.done, self.failed, self.quiet = total, skipped, 0, quiet
        self.start, self.ran, self.last, self.first = time.monotonic(), 0, 0.0, None
        self.tty = sys.stderr.isatty()

    def add(self, ran: int, failed: int):
        self.done += ran
        self.ran += ran
        if self.first is None:
            self.first = (time.monotonic(), self.ran)
        self.failed += failed
        now = time.monotonic()
        if not self.quiet and (self.tty or now - self.last >= 2.0 or self.done == self.total):
            self.last = now
            el = now - self.start
            # the rate since the first batch came back (not counting the cluster's start)
            t1, n1 = self.first
            rate = (self.ran - n1) / (now - t1) if self.ran > n1 and now > t1 else self.ran / max(el, 1e-9)
            eta = (self.total - self.done) / rate if rate > 0 else math.nan
            width = 30
            bar = "#" * int(width * self.done / max(self.total, 1))
            line = (f"[{bar:<{width}}] {self.done}/{self.total} cases, {self.failed} failed, "
                    f"{el:.1f} s, ETA {eta:.0f} s")
            sys.stderr.write(("\r" + line + "   ") if self.tty else line + "\n")
            if self.tty and self.done == self.total:
                sys.stderr.write("\n")
            sys.stderr.flush()


# ---------------------------------------------------------------- the sweep

def sweep(path: str, out: Optional[str] = None, *, scheduler: Any = None, workers: Optional[int] = None,
          batch_size: Optional[int] = None, keep_logs: bool = False, quiet: bool = False,
          drop_bad_parts: bool = False, force: bool = False) -> SweepResult:
    """Run every case of a sweep file and return the table (see soadyn.ensemble for the format).

    out: the results directory (default SWEEP_STEM.results beside the current directory); cases
    already in it are skipped.  scheduler: None for an embedded Dask LocalCluster of `workers`
    processes (default: this machine's cores) with one thread each; an address such as
    'tcp://host:8786' or a distributed.Client for an existing cluster; 'serial' for a plain loop in
    this process without Dask.  batch_size: cases per Dask task (default: guided sizes, each a
    third of a worker's share of what is left, from at most 1000 down to 20).  keep_logs: each case's HDF5 log in out/logs/ (written by the worker:
    a remote cluster needs out on a shared file system; each case then runs alone, one
    soadyn.simulate, instead of with the task's cases that differ from it only in their initial
    state, which otherwise run as one library call: soadyn._batched).  drop_bad_parts: set aside (as NAME.bad)
    each part file in out/parts that this sweep did not write, instead of stopping at it.  Results
    are the same, bit for bit (CPU times aside), whichever way the cases run.  Raises soadyn.Error
    if out is in use by another sweep (out/sweep.lock), and, before anything is written, if
    out/results.h5 is not a soadyn sweep's table (unless force: then it is replaced; never an
    input of the sweep, a directory or a FIFO)."""
    sw = path if isinstance(path, Sweep) else Sweep(path)
    if out is None:
        out = os.path.basename(sw.path).rsplit(".yaml", 1)[0] + ".results"
    out = str(out)
    t0 = time.monotonic()
    check_results_path(sw, os.path.join(out, "results.h5"), force)  # before anything is touched
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        raise Error(f"{out}: cannot make the results directory: {e.strerror}") from None
    lock = _lock(sw, out)
    try:
        return _sweep_locked(sw, out, t0, scheduler, workers, batch_size, keep_logs, quiet, drop_bad_parts)
    finally:
        os.close(lock)  # the lock goes with it


def _sweep_locked(sw, out, t0, scheduler, workers, batch_size, keep_logs, quiet, drop_bad_parts) -> SweepResult:
    say = (lambda msg: None) if quiet else (lambda msg: print(printable(msg), file=sys.stderr, flush=True))
    try:
        done = _open_store(sw, out, drop_bad_parts, say)
    except OSError as e:
        raise Error(f"{e.filename or out}: {e.strerror}") from None
    skipped = len(done)
    todo = [i for i in range(len(sw.cases)) if i not in done]
    logs = os.path.abspath(os.path.join(out, "logs")) if keep_logs else None
    progress = _Progress(len(sw.cases), skipped, quiet)
    say(f"sweep {sw.path}: {len(sw.cases)} cases, {skipped} already done in {out}, {len(todo)} to run")

    def finish(rows):
        _save_part(out, rows)
        for r in rows:
            done[r["case"]] = r
        progress.add(*_counts(rows))

    def payload(ids):
        return (sw.scenario_text, os.path.abspath(sw.scenario_path), sw.settings,
                [(i, sw.cases[i]) for i in ids], sw.reference, logs)

    if todo and scheduler == "serial":
        for ids in _batches(sw, todo, batch_size or max(1, min(200, math.ceil(len(todo) / 8)))):
            finish(run_batch(*payload(ids)))
    elif todo:
        if _run_dask(sw, todo, payload, finish, progress, scheduler, workers, batch_size, say, out):
            done = _read_parts(out, len(sw.cases))  # the workers wrote the parts: the rows come from them
    table = _table(sw, done)
    results = os.path.join(out, "results.h5")
    write_results(sw, table, results)
    failed = int(np.sum(~table["completed"]))
    say(f"sweep done: {len(done)} cases ({failed} did not complete) in {out}/results.h5")
    return SweepResult(table, results, len(todo), skipped, failed, time.monotonic() - t0)


class _Task:
    """A batch's arguments in one object: Dask looks inside lists, tuples and dicts for futures,
    which on 200 cases is tens of thousands of calls on the client per task; it does not look in
    here.  With `out` (a worker on this machine) the worker writes the batch's part file itself,
    atomically, and returns only its counts (cases, failed): the client neither receives nor
    decodes rows while the workers run, and reads the parts once at the end."""

    def __init__(self, args, out: Optional[str] = None):
        self.args, self.out = args, out

    def __call__(self):
        rows = run_batch(*self.args)
        if not self.out:
            return rows
        _save_part(self.out, rows)
        return _counts(rows)


def _run_task(task: _Task):
    return task()


def _pin(cpu: int) -> None:
    os.sched_setaffinity(0, {cpu})


def _pin_workers(client) -> None:
    """Bind each worker of the embedded cluster to its own CPU, round robin over the CPUs this
    process may use: a worker the OS moves between CPUs (as the client's and scheduler's threads
    wake) runs its batches on cold caches (1 worker, 10 000 cases: 3.2-3.4 s pinned against
    3.6-5.2 s not).  Only for speed: where affinity cannot be set (or a worker is gone), the
    workers are left as they are."""
    if not hasattr(os, "sched_setaffinity"):
        return
    cpus = sorted(os.sched_getaffinity(0))
    for k, addr in enumerate(sorted(client.scheduler_info().get("workers", {}))):
        try:
            client.run(_pin, cpus[k % len(cpus)], workers=[addr])
        except Exception:  # noqa: BLE001  (any failure here only costs speed)
            return


QUIET_CLUSTER = {"distributed.worker.profile.enabled": False, "distributed.admin.system-monitor.interval": "2s",
                 "distributed.worker.memory.monitor-interval": "1s", "distributed.admin.tick.interval": "1s"}


def _dashboard(client) -> str:
    """The scheduler's web pages: Dask's live dashboard (/status) with bokeh 2.4 here, else its
    worker and task pages, which need no bokeh (Debian 12 packages no bokeh)."""
    if "dashboard" not in client.scheduler_info().get("services", {}):
        return "none (the scheduler serves no web pages)"
    link = client.dashboard_link
    try:
        import bokeh  # noqa: F401  (the live dashboard needs it)
        return link
    except ImportError:
        return (link.rsplit("/status", 1)[0] + "/info/main/workers.html (workers, their tasks and logs; the "
                "live charts need bokeh 2.4: pip install 'bokeh<3')")


def _run_dask(sw, todo, payload, finish, progress, scheduler, workers, batch_size, say, out) -> bool:
    """Run the batches on Dask; True if the workers wrote the parts themselves."""
    try:
        from distributed import Client, LocalCluster, as_completed
    except ImportError:
        raise Error("soadyn sweep runs on Dask: install python3-distributed (or use --scheduler serial)") from None
    import logging
    logging.getLogger("distributed").setLevel(logging.ERROR)
    cluster = None
    if scheduler is None:
        n = workers or os.cpu_count() or 1
        # the embedded cluster shares this machine's cores with the runs: no statistical profiler
        # sampling every worker's stack each 10 ms, system/memory monitors at 1-2 s, not 0.1-0.5 s,
        # and the event loop's health tick each second, not each 20 ms (it takes the GIL from the
        # runs: ~5 % of a worker's time on short runs)
        import dask
        with dask.config.set(QUIET_CLUSTER):
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                                   silence_logs=logging.ERROR)
        client = Client(cluster)
        _pin_workers(client)
    elif isinstance(scheduler, str):
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as e:
            raise Error(f"--scheduler {scheduler}: cannot reach the Dask scheduler: {e}") from None
    else:
        client = scheduler
    try:
        nworkers = max(1, len(client.scheduler_info().get("workers", {})))
        say(f"dashboard: {_dashboard(client)}")
        batches = _batches(sw, todo, batch_size, nworkers)
        say(f"{len(batches)} tasks of {min(map(len, batches))} to {max(map(len, batches))} cases on {nworkers} worker(s)")
        # the workers of a cluster on this machine (the embedded one, or a LocalCluster given as a
        # Client) share this file system: each writes its own parts
        same_machine = cluster is not None or isinstance(getattr(client, "cluster", None), LocalCluster)
        local = os.path.abspath(out) if same_machine else None
        fp = sw.fingerprint()
        # a task's key names its cases: a worker that dies has its tasks run again elsewhere
        # one map, not a submit per task: Dask reads the caller's source for each call it is given
        futures = client.map(_run_task, [_Task(payload(ids), local) for ids in batches],
                             key=[f"soadyn-sweep-{fp}-{ids[0]}-{len(ids)}" for ids in batches], retries=2, pure=False)
        # results gathered on the client's event loop as they come, not a round trip per future
        results = as_completed(futures, with_results=True)
        while True:
            try:
                fut, result = next(results)
            except StopIteration:
                return local is not None
            except Exception as e:  # e.g. a worker without soadyn: the finished batches are kept
                raise Error(f"a sweep task failed on a worker ({type(e).__name__}: {e}); "
                            f"finished cases are kept, run again to resume") from None
            if local:
                progress.add(*result)
            else:
                finish(result)
            fut.release()
    finally:
        if client is not scheduler:
            client.close()
        if cluster is not None:
            cluster.close()


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(prog="soadyn sweep", description="Run a sweep file's cases (on Dask) into DIR/results.h5; a stopped sweep resumes.")
    p.add_argument("sweep", help="the sweep file (YAML)")
    p.add_argument("-o", "--output", help="results directory (default: SWEEP.results); finished cases in it are skipped")
    p.add_argument("--scheduler", help="a Dask scheduler's address (tcp://HOST:8786), or 'serial' for a plain loop; default: an embedded LocalCluster")
    p.add_argument("--workers", type=int, help="LocalCluster worker processes (default: this machine's cores)")
    p.add_argument("--batch-size", type=int, help="cases per task (default: guided, from a third of each worker's share down to 20, at most 1000)")
    p.add_argument("--keep-logs", action="store_true", help="keep each case's HDF5 log in DIR/logs/")
    p.add_argument("--drop-bad-parts", action="store_true",
                   help="set aside (as NAME.bad) each DIR/parts file this sweep did not write and run its cases again, "
                        "instead of stopping at it")
    p.add_argument("--force", action="store_true",
                   help="replace a DIR/results.h5 that is not a soadyn sweep's table (never an input, a directory or a FIFO)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress output")
    a = p.parse_args(argv)
    for name in ("workers", "batch_size"):
        if getattr(a, name) is not None and getattr(a, name) < 1:
            p.error(f"--{name.replace('_', '-')}: expected a positive integer, got {getattr(a, name)}")
    try:
        r = sweep(a.sweep, a.output, scheduler=a.scheduler, workers=a.workers, batch_size=a.batch_size,
                  keep_logs=a.keep_logs, quiet=a.quiet, drop_bad_parts=a.drop_bad_parts, force=a.force)
    except Error as e:
        print(f"soadyn: error: {printable(str(e))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\nsoadyn: sweep interrupted; run the same command again to resume", file=sys.stderr)
        return 130
    return 0  # cases that did not complete are results (status column), not an error


if __name__ == "__main__":
    sys.exit(main())
