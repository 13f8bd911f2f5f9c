"""The pool: forked workers, killed and replaced on a hang or a crash."""

from __future__ import annotations

import contextlib
import os
import time
from dataclasses import dataclass, field
from multiprocessing import get_context
from multiprocessing.connection import wait

from .results import failure
from .worker import cpu_seconds, worker_main


@dataclass
class Worker:
    process: object
    connection: object
    task: dict | None = None
    started: float = 0.0
    cpu_started: float = 0.0
    runs: int = 0


@dataclass
class Pool:
    jobs: int
    time_budget: float
    memory_bytes: int
    max_runs: int = 100
    workers: list[Worker] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.context = get_context("fork")
        self.workers = [self._start() for _ in range(self.jobs)]

    def _start(self) -> Worker:
        parent, child = self.context.Pipe()
        process = self.context.Process(
            target=worker_main,
            args=(child, self.memory_bytes, self.time_budget, os.getpid()),
            daemon=True,
        )
        process.start()
        child.close()
        return Worker(process, parent)

    def _replace(self, worker: Worker) -> None:
        if worker.process.is_alive():
            worker.process.kill()
        worker.process.join(5)
        worker.connection.close()
        self.workers[self.workers.index(worker)] = self._start()

    def run(self, tasks):
        """Yield (task, result) for every task, ``jobs`` at a time, in completion order."""
        pending = iter(tasks)
        exhausted = False
        while True:
            for worker in list(self.workers):
                if worker.task is None and not exhausted:
                    task = next(pending, None)
                    if task is None:
                        exhausted = True
                        break
                    worker.task, worker.started = task, time.monotonic()
                    worker.cpu_started = cpu_seconds(worker.process.pid)
                    worker.connection.send(task)
            busy = [w for w in self.workers if w.task is not None]
            if not busy:
                return
            # The worker's own alarm counts CPU seconds; past 1.5 times the
            # budget in CPU (stuck in C code), or three times the budget plus
            # a minute of wall clock (blocked, using no CPU: a hang), it is
            # killed. The wall-clock margin lets a busy shared machine slow a
            # run down without its being called hung.
            hard_cpu = self.time_budget * 1.5 + 10
            hard_wall = self.time_budget * 3 + 60
            ready = wait([w.connection for w in busy], 1.0)
            for worker in busy:
                task = worker.task
                if worker.connection in ready:
                    try:
                        result = worker.connection.recv()
                    except (EOFError, OSError):
                        code = worker.process.exitcode
                        worker.process.join(1)
                        code = worker.process.exitcode if code is None else code
                        result = failure(f"worker crash (exit {code})", "the worker died")
                        result["seconds"] = time.monotonic() - worker.started
                        worker.task = None
                        self._replace(worker)
                        yield task, result
                        continue
                    worker.task = None
                    worker.runs += 1
                    if worker.runs >= self.max_runs or not result["ok"]:
                        self._replace(worker)  # a fresh process after any failure
                    yield task, result
                elif (
                    over_cpu := cpu_seconds(worker.process.pid) - worker.cpu_started > hard_cpu
                ) or time.monotonic() - worker.started > hard_wall:
                    result = failure(
                        "timeout (hard kill, no Python frame)" if over_cpu else "hang (wall clock)",
                        "killed",
                    )
                    result["seconds"] = time.monotonic() - worker.started
                    worker.task = None
                    self._replace(worker)
                    yield task, result

    def map(self, tasks: list[dict]) -> list[dict]:
        """Results in the order of ``tasks``."""
        for index, task in enumerate(tasks):
            task["slot"] = index
        results: list[dict] = [{}] * len(tasks)
        for task, result in self.run(tasks):
            results[task["slot"]] = result
        return results

    def close(self) -> None:
        for worker in self.workers:
            with contextlib.suppress(OSError, BrokenPipeError):
                worker.connection.send(None)
        for worker in self.workers:
            worker.process.join(5)
            if worker.process.is_alive():
                worker.process.kill()
