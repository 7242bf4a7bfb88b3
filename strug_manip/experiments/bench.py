"""Table I runs: every (domain, solver, seed) episode, in worker processes or on Ray, resumable.

Results are appended to ``OUT/results.jsonl`` one line per finished episode, written
and fsync'ed as soon as the episode ends, so a crash or a Ctrl-C loses only the
episodes still running. ``OUT/run.json`` records the settings; ``--resume`` checks
that they match, drops a torn last line, and runs only the missing triples, so no
finished episode is lost or repeated. Tables (``table.md``, ``table.csv``,
``table.png``) are rewritten at the end from everything in ``results.jsonl``.
Episodes run in the driver (``workers=1``), in local worker processes, or as Ray tasks
(:mod:`strug_manip.experiments.executors`); the driver alone writes the results.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from planners.errors import ConfigError, UnknownNameError, check_positive_int
from planners.solvers import SOLVERS
from strug_manip.domains import (
    domain_class,
)
from strug_manip.experiments.episode import DEFAULT_PARTICLES
from strug_manip.experiments.executors import EXECUTORS, run_local, run_ray
from strug_manip.experiments.records import read_jsonl
from strug_manip.experiments.table import summarize, to_markdown, write_csv, write_png
from strug_manip.experiments.task import check_solver, planner_of, run_task, solver_config
from strug_manip.objects.loader import object_folders

RESULTS = "results.jsonl"
SETTINGS = "run.json"


@dataclass(frozen=True)
class BenchSpec:
    """What one bench run covers.

    Attributes:
        domains: canonical domain names, or ``package.module:Class`` for a user's own.
        solvers: solver names (:data:`~strug_manip.experiments.task.SOLVER_NAMES`: the
            planners', and ``oracle`` on the manipulation tasks).
        seeds: number of seeds; seeds are ``first_seed`` .. ``first_seed + seeds - 1``.
        overrides: solver config fields set for every solver that has them
            (e.g. ``{"sims": 2000}``); a field no chosen solver has is an error.
        n_particles: belief size.
        first_seed: the first seed (a range no tuning used, e.g. to report on).
        objects: real object folders (PartNet-Mobility) the manipulation tasks act on
            instead of generated cabinets; each episode's seed draws one and its target.
    """

    domains: tuple[str, ...]
    solvers: tuple[str, ...]
    seeds: int
    overrides: dict[str, Any] = field(default_factory=dict)
    n_particles: int = DEFAULT_PARTICLES
    first_seed: int = 0
    objects: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not self.domains:
            raise ConfigError("choose at least one domain")
        if not self.solvers:
            raise ConfigError("choose at least one solver")
        for d in self.domains:
            domain_class(d)
        for s in self.solvers:
            for d in self.domains:
                check_solver(d, s)
        check_positive_int("seeds", self.seeds)
        check_positive_int("n_particles", self.n_particles)
        check_positive_int("first_seed", self.first_seed, allow_zero=True)
        for o in self.objects:
            object_folders(o)  # names a missing folder now, not in a worker
        for s in self.solvers:  # validate every config once, up front
            solver_config(s, self.overrides)
        fields = {f for s in self.solvers for f in SOLVERS[planner_of(s)].field_names()}
        for key in self.overrides:
            if key not in fields:
                raise UnknownNameError("solver config field", key, sorted(fields))

    def settings(self) -> dict[str, Any]:
        """What must match for two runs to share a results file."""
        out = {"overrides": self.overrides, "n_particles": self.n_particles}
        return {**out, "objects": list(self.objects)} if self.objects else out

    def tasks(self) -> list[tuple[str, str, int]]:
        """Every (domain, solver, seed), seeds innermost-last so early rows fill first."""
        seeds = range(self.first_seed, self.first_seed + self.seeds)
        return [(d, s, k) for k in seeds for d in self.domains for s in self.solvers]


#: The fields of a record that measure wall time (they differ between equal runs).
TIMING_FIELDS = ("seconds", "plan_seconds_median", "report")
#: The fields every line of ``results.jsonl`` has.
RECORD_FIELDS = ("domain", "solver", "seed", "return")


def load_results(out: Path) -> list[dict[str, Any]]:
    """The finished records in ``out/results.jsonl``; a torn last line is dropped.

    Raises:
        ConfigError: a line before the last is not JSON, or a line is not a bench record
            (another program's file).
    """
    path = out / RESULTS
    records = read_jsonl(path)
    for i, rec in enumerate(records):
        if not isinstance(rec, dict) or any(k not in rec for k in RECORD_FIELDS):
            raise ConfigError(
                f"{path}: line {i + 1} is not a bench episode record (fields "
                f"{', '.join(RECORD_FIELDS)}); is this another program's file? "
                "Choose another --out"
            )
    return records


def _load_settings(path: Path) -> Any:
    try:
        return json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(
            f"--resume: {path} is not a bench run's settings (not JSON: {exc}); "
            "remove it to adopt this run's settings, or choose another --out"
        ) from None


def _prepare(out: Path, spec: BenchSpec, resume: bool) -> list[dict[str, Any]]:
    out.mkdir(parents=True, exist_ok=True)
    settings_path, results_path = out / SETTINGS, out / RESULTS
    records = load_results(out)
    if records and not resume:
        raise ConfigError(
            f"{results_path} already holds {len(records)} episodes; pass --resume to continue "
            "that run or choose another --out"
        )
    if resume and settings_path.exists():
        old = _load_settings(settings_path)
        if old != spec.settings():
            raise ConfigError(
                f"--resume: {settings_path} was written with settings {old}, but this run asks "
                f"for {spec.settings()}; use the same settings or another --out"
            )
    settings_path.write_text(json.dumps(spec.settings(), indent=1) + "\n")
    # Rewrite without any torn line so that appends start on a fresh line.
    tmp = results_path.with_suffix(".tmp")
    tmp.write_text("".join(json.dumps(r) + "\n" for r in records))
    os.replace(tmp, results_path)
    return records


def run_bench(
    spec: BenchSpec,
    out: Path,
    *,
    workers: int = 1,
    resume: bool = False,
    progress: bool = True,
    executor: str = "local",
    address: str | None = None,
) -> dict[str, dict[str, dict[str, float]]]:
    """Run every missing episode of ``spec`` into ``out`` and write the tables.

    Args:
        spec: the sweep.
        out: the run's directory.
        workers: episodes at once (``local``: processes; 1 runs them in this process;
            ``ray``: the local instance's CPUs, and the tasks in flight are ``2 * workers``).
        resume: keep the finished episodes of ``out`` and run the rest.
        progress: show a progress bar on stderr.
        executor: ``"local"`` (worker processes) or ``"ray"`` (Ray tasks).
        address: with ``"ray"``, a cluster to join; ``None`` starts Ray locally.

    Returns:
        ``{domain: {solver: {"mean", "stderr", "n"}}}`` over the spec's triples.
    """
    check_positive_int("workers", workers)
    if executor not in EXECUTORS:
        raise UnknownNameError("executor", executor, EXECUTORS)
    records = _prepare(out, spec, resume)
    wanted = spec.tasks()
    done = {(r["domain"], r["solver"], r["seed"]) for r in records}
    todo = [t for t in wanted if t not in done]
    bar = _progress(len(wanted), len(wanted) - len(todo), progress)
    with (out / RESULTS).open("a") as sink:

        def record(rec: dict[str, Any]) -> None:
            sink.write(json.dumps(rec) + "\n")
            sink.flush()
            os.fsync(sink.fileno())
            records.append(rec)
            bar.update(1)

        if not todo:
            pass
        elif executor == "ray":
            run_ray(todo, spec.overrides, spec.n_particles, workers, record, address, spec.objects)
        elif workers == 1:
            for task in todo:
                record(run_task(task, spec.overrides, spec.n_particles, spec.objects))
        else:
            run_local(todo, spec.overrides, spec.n_particles, workers, record, spec.objects)
    bar.close()
    wanted_set = set(wanted)
    mine = [r for r in records if (r["domain"], r["solver"], r["seed"]) in wanted_set]
    summary = summarize(mine)
    write_tables(summary, out)
    if any("success" in r for r in mine):
        (out / "success.md").write_text(success_table(mine))
    return summary


def success_table(records: list[dict[str, Any]]) -> str:
    """Markdown, for the records that have ``success`` (the manipulation tasks): per
    domain and solver, the episodes that earned the task's +10, the median planning
    time per step and episode wall time [s], and the mean simulations run per decision
    (fewer than the budget where a search stops once settled, ``stop_decided``)."""
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for r in records:
        if "success" in r:
            groups.setdefault((r["domain"], r["solver"]), []).append(r)
    lines = ["| domain | solver | success | median plan s/step | median episode s | "
             "mean sims/decision |", "|---|---|---|---|---|---|"]  # fmt: skip
    for (d, s), rs in sorted(groups.items()):
        ok = sum(bool(r["success"]) for r in rs)
        plan = statistics.median(r.get("plan_seconds_median", 0.0) for r in rs)
        wall = statistics.median(r["seconds"] for r in rs)
        sims = statistics.mean(r["mean_sims"] for r in rs)
        rate = f"{ok}/{len(rs)} ({ok / len(rs):.0%})"
        lines.append(f"| {d} | {s} | {rate} | {plan:.2f} | {wall:.1f} | {sims:.1f} |")
    return "\n".join(lines) + "\n"


def write_tables(summary: dict[str, dict[str, dict[str, float]]], out: Path) -> None:
    """``table.md``, ``table.csv`` and ``table.png`` in ``out``."""
    (out / "table.md").write_text(to_markdown(summary))
    write_csv(summary, out / "table.csv")
    write_png(summary, out / "table.png")


class _NoBar:
    def update(self, n: int) -> None:
        pass

    def close(self) -> None:
        pass


def _progress(total: int, initial: int, enabled: bool) -> Any:
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        unit="episode",
        file=sys.stderr,
        dynamic_ncols=True,
        smoothing=0.05,
        mininterval=0.5,
        desc=f"episodes ({time.strftime('%H:%M')} start)",
    )
