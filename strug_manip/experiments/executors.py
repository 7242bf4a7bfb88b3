"""Where a bench sweep's episodes run: local worker processes (the default) or Ray tasks.

Both executors run ``run_task(task, overrides, n_particles)`` for every task and hand
each finished record to the driver's ``record`` callback as it arrives, so the driver
alone appends to ``results.jsonl``; both keep a bounded number of tasks in flight.
An episode is a pure function of its (domain, solver, seed) under a simulation budget,
so both give the same records (wall times aside).

Local workers are ``python -m strug_manip.experiments.executors`` processes that read
one task per line on stdin and answer one JSON record per line. They use no
multiprocessing primitives (so a killed driver leaves no semaphores behind), ignore
Ctrl-C (the driver stops them), and end with their driver: the kernel kills them when
it dies (``PR_SET_PDEATHSIG`` on Linux) and, as a fallback, a thread polls the parent
pid every 0.2 s.
"""

from __future__ import annotations

import contextlib
import ctypes
import json
import os
import selectors
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import IO, Any

from planners.errors import ConfigError, PlannersError
from strug_manip.experiments.task import run_task

Task = tuple[str, str, int]
Record = Callable[[dict[str, Any]], None]

#: Valid values of ``strug bench --executor``.
EXECUTORS = ("local", "ray")
#: Object store of a local Ray instance [bytes]: episodes return small records.
RAY_OBJECT_STORE = 256 * 1024**2


def run_local(
    todo: Sequence[Task],
    overrides: dict[str, Any],
    n_particles: int,
    workers: int,
    record: Record,
    objects: Sequence[str] = (),
) -> None:
    """Run ``todo`` in ``workers`` local processes, one task in flight each
    (``objects``: real object folders, as :func:`~strug_manip.experiments.task.run_task`)."""
    procs = [_start_worker(overrides, n_particles, objects) for _ in range(workers)]
    sel = selectors.DefaultSelector()
    queue, busy = list(reversed(todo)), 0
    try:
        for proc in procs:
            if queue:
                _send(proc, queue.pop())
                sel.register(proc.stdout, selectors.EVENT_READ, proc)
                busy += 1
        while busy:
            for key, _ in sel.select():
                proc = key.data
                record(_receive(proc))
                if queue:
                    _send(proc, queue.pop())
                else:
                    sel.unregister(proc.stdout)
                    busy -= 1
    except BaseException:  # Ctrl-C, a failed episode: stop at once
        sel.close()
        _stop(procs, grace=0.0)
        raise
    sel.close()
    _stop(procs, grace=2.0)


def _start_worker(
    overrides: dict[str, Any], n_particles: int, objects: Sequence[str]
) -> subprocess.Popen:
    cmd = [sys.executable, "-m", "strug_manip.experiments.executors", str(os.getpid())]
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    setup = {"overrides": overrides, "n_particles": n_particles, "objects": list(objects)}
    proc.stdin.write(json.dumps(setup) + "\n")
    return proc


def _send(proc: subprocess.Popen, task: Task) -> None:
    proc.stdin.write(json.dumps(list(task)) + "\n")
    proc.stdin.flush()


def _receive(proc: subprocess.Popen) -> dict[str, Any]:
    line = proc.stdout.readline()
    if not line:
        raise RuntimeError(f"a bench worker (pid {proc.pid}) died with exit code {proc.wait()}")
    reply = json.loads(line)
    if "error" in reply:
        if reply["strug_error"]:
            raise ConfigError(reply["error"])
        raise RuntimeError(f"a bench worker failed:\n{reply['traceback']}")
    return reply["record"]


def _stop(procs: list[subprocess.Popen], grace: float) -> None:
    """End the workers: EOF on stdin ends an idle one; kill what is left after ``grace`` [s]."""
    for proc in procs:
        with contextlib.suppress(OSError):
            proc.stdin.close()
    deadline = time.monotonic() + grace
    for proc in procs:
        try:
            proc.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:  # still inside an episode (Ctrl-C, an error)
            proc.kill()
            proc.wait()
        with contextlib.suppress(OSError):
            proc.stdout.close()


def run_ray(
    todo: Sequence[Task],
    overrides: dict[str, Any],
    n_particles: int,
    workers: int,
    record: Record,
    address: str | None = None,
    objects: Sequence[str] = (),
) -> None:
    """Run ``todo`` as Ray tasks, at most ``2 * workers`` in flight (``ray.wait``).

    Args:
        objects: real object folders (:func:`~strug_manip.experiments.task.run_task`).
        address: a Ray cluster to join (e.g. ``"ray://head:10001"`` or ``"auto"``);
            ``None`` starts a local instance with ``workers`` CPUs. Cluster nodes need
            strug-manip (and a user domain's module) installed.
    """
    try:
        import ray
    except ImportError:
        raise ConfigError(
            "--executor ray needs Ray: pip install 'strug-manip[ray]' (or: pip install ray)"
        ) from None
    if address is None:
        kwargs: dict[str, Any] = {
            "num_cpus": workers,
            "include_dashboard": False,
            "object_store_memory": RAY_OBJECT_STORE,
        }
    else:
        _check_reachable(address)
        kwargs = {"address": address}
    try:
        ray.init(log_to_driver=False, configure_logging=False, **kwargs)
    except (ConnectionError, ValueError, RuntimeError) as exc:
        raise ConfigError(f"--address {address}: cannot start or reach Ray ({exc})") from None
    try:
        remote = ray.remote(num_cpus=1, max_retries=0)(run_task)
        queue, pending = list(reversed(todo)), []
        while queue or pending:
            while queue and len(pending) < 2 * workers:
                pending.append(remote.remote(queue.pop(), overrides, n_particles, objects))
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                record(_ray_result(ray, ref))
    finally:
        ray.shutdown()


def _check_reachable(address: str, timeout: float = 5.0) -> None:
    """Fail fast on a ``HOST:PORT`` (or ``ray://HOST:PORT``) that nothing listens on:
    Ray itself would retry for minutes. ``auto`` and other forms are left to Ray."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit() or not host:
        return
    try:
        socket.create_connection((host, int(port)), timeout=timeout).close()
    except OSError as exc:
        raise ConfigError(
            f"--address {address}: no Ray cluster answers there ({exc.strerror or exc})"
        ) from None


def _ray_result(ray: Any, ref: Any) -> dict[str, Any]:
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError as exc:
        cause = getattr(exc, "cause", None)
        if isinstance(cause, PlannersError):
            raise ConfigError(str(cause)) from None
        raise


# --- the worker side -------------------------------------------------------------------


def _die_with(parent: int) -> None:
    """End this process when ``parent`` ends (it is then re-parented)."""
    with contextlib.suppress(OSError, AttributeError):
        pr_set_pdeathsig = 1
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL))

    def watch() -> None:
        while True:
            if os.getppid() != parent:
                os._exit(1)
            time.sleep(0.2)

    if os.getppid() != parent:  # it died before prctl
        os._exit(1)
    threading.Thread(target=watch, daemon=True, name="parent-watch").start()


def _serve(requests: IO[str], replies: IO[str]) -> None:
    setup = json.loads(requests.readline())
    for line in requests:
        task = tuple(json.loads(line))
        try:
            reply: dict[str, Any] = {
                "record": run_task(
                    task, setup["overrides"], setup["n_particles"], tuple(setup["objects"])
                )
            }
        except Exception as exc:
            import traceback

            reply = {
                "error": str(exc),
                "strug_error": isinstance(exc, PlannersError),
                "traceback": traceback.format_exc(),
            }
        replies.write(json.dumps(reply) + "\n")
        replies.flush()


def _worker_main(parent: int) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the driver handles Ctrl-C
    _die_with(parent)
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "w")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # a stray print must not corrupt replies
    _serve(sys.stdin, replies)


if __name__ == "__main__":
    _worker_main(int(sys.argv[1]))
