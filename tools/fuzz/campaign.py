"""The campaign: mutants and geometry cases run on the pool, recorded in
results.jsonl, each failing signature's first input shrunk into its folder
under ``--out/failures/``, and the summary written; or the failures of an
earlier results.jsonl replayed and shrunk."""

from __future__ import annotations

import json
import math
import random
import re
import signal
import sys
import time
from collections import Counter, defaultdict
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from .geometry import geometry_case, geometry_reproducer
from .inputs import (
    CITY_ENCODINGS,
    CITY_REFERENCE_TEMPLATE,
    CITY_TEMPLATES,
    ENCODINGS,
    KNOWN,
    REFERENCE_TEMPLATE,
    TEMPLATES,
)
from .mutate import mutate
from .pool import Pool
from .resume import RESULTS, ResumeRefused, plan_of, recorded, run_key, save_plan
from .shrink import shrink_case, shrink_input


def converter_tasks(seeds, encodings, count: int, seed: int, first: int = 0, done=frozenset()):
    """``count`` mutants per encoding, interleaved, from index ``first`` (mutant
    ``i`` is the same whatever chunk it is run in), but those whose
    (encoding, index) is in ``done``."""
    plans = [e for e in encodings if seeds.get(e)]
    for index in range(first, first + count):
        for encoding in plans:
            if (encoding, index) not in done:
                yield converter_task(seeds, encoding, index, seed)


def converter_task(seeds, encoding: str, index: int, seed: int) -> dict:
    """Mutant ``index`` of ``encoding``: the same for the same seed files and ``seed``."""
    rng = random.Random(f"{seed}:{encoding}:{index}")
    pool = seeds[encoding]
    name, data = pool[rng.randrange(len(pool))]
    others = [d for _, d in rng.sample(pool, min(3, len(pool)))]
    try:
        mutant, ops = mutate(data, encoding, rng, others)
    except Exception as error:  # noqa: BLE001 - a mutator's own limit must not end the campaign
        mutant, ops = data[: len(data) // 2], [f"bytes:truncate (mutator: {type(error).__name__})"]
    city = encoding in CITY_ENCODINGS
    templates = CITY_TEMPLATES if city else TEMPLATES
    template = rng.randrange(len(templates))
    reference = template == (CITY_REFERENCE_TEMPLATE if city else REFERENCE_TEMPLATE)
    return {
        "kind": "convert",
        "encoding": encoding,
        "index": index,
        "seed_file": name,
        "ops": ops,
        "data": mutant,
        "suffix": ENCODINGS[encoding],
        "argv": list(templates[template]),
        "reference": reference,
    }


def known_signatures(pool: Pool) -> dict[str, list[str]]:
    """Signatures of the findings already filed (README in ../shared/findings/robustness),
    so the summary can say which failures are known."""
    tasks = []
    for path in sorted((KNOWN / "api").glob("*.py")):
        tasks.append({"kind": "script", "source": path.read_text(), "known": f"api/{path.name}"})
    for path in sorted((KNOWN / "cli").glob("*.x3d")):
        for template in (TEMPLATES[0], TEMPLATES[REFERENCE_TEMPLATE], TEMPLATES[4]):
            tasks.append(
                {
                    "kind": "convert",
                    "encoding": "x3d",
                    "data": path.read_bytes(),
                    "suffix": ".x3d",
                    "argv": list(template),
                    "reference": False,
                    "known": f"cli/{path.name}",
                }
            )
    found: dict[str, list[str]] = defaultdict(list)
    for task, result in pool.run(tasks):
        if result["signature"] and task["known"] not in found[result["signature"]]:
            found[result["signature"]].append(task["known"])
    return found


def slug(text: str) -> str:
    return re.sub(r"[^\w.-]+", "_", text).strip("_")[:90]


def replay(args, seeds, pool: Pool) -> int:
    """Shrink the failures a results.jsonl recorded (e.g. of a campaign that was stopped)."""
    first: dict[str, dict] = {}
    by_signature: Counter = Counter()
    counts: dict[str, Counter] = defaultdict(Counter)
    for line in args.replay.read_text().splitlines():
        entry = json.loads(line)
        group = entry.get("encoding", "geometry")
        counts[group]["runs"] += 1
        counts[group][f"exit {entry.get('code')}" if entry["ok"] else "FAIL"] += 1
        if entry["ok"]:
            continue
        signature = entry["signature"]
        by_signature[signature] += 1
        counts[group][signature] += 1
        if signature in first:
            continue
        if "case" in entry:
            task = {"kind": "geometry", "case": geometry_case(args.seed, entry["case"])}
        else:
            task = converter_task(seeds, entry["encoding"], entry["index"], args.seed)
        result = pool.map([dict(task)])[0]
        if result.get("signature") != signature:
            print(f"not reproduced: {signature} (now {result.get('signature')})", file=sys.stderr)
        task.pop("slot", None)
        first[signature] = dict(task, result=dict(result, detail=entry.get("detail", "")))
    known = {} if args.no_known else known_signatures(pool)
    rows = write_failures(args, pool, first, by_signature, known)
    summary = summary_table(counts, rows, 0.0, args)
    (args.out / "summary.md").write_text(summary)
    print(summary)
    return 1 if by_signature else 0


class Interrupted(Exception):
    """SIGINT or SIGTERM reached the campaign: stop, keep what is recorded."""

    def __init__(self, signum: int) -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


@dataclass
class Tally:
    """Runs per group and exit, failures per signature, and each signature's
    first failing task (with its result), over every recorded run."""

    counts: dict[str, Counter] = field(default_factory=lambda: defaultdict(Counter))
    first: dict[str, dict] = field(default_factory=dict)
    by_signature: Counter = field(default_factory=Counter)

    def add(self, entry: dict, task: Callable[[], dict]) -> None:
        """Count ``entry`` (a line of results.jsonl); ``task()`` gives its task
        when it is the first failure of its signature."""
        group = entry.get("encoding", "geometry")
        self.counts[group]["runs"] += 1
        self.counts[group][f"exit {entry.get('code')}" if entry["ok"] else "FAIL"] += 1
        if entry["ok"]:
            return
        signature = entry["signature"]
        self.by_signature[signature] += 1
        self.counts[group][signature] += 1
        if signature not in self.first:
            self.first[signature] = task()


def earlier_task(entry: dict, seeds, seed: int) -> dict:
    """The task of a recorded failing run, made again (mutants and cases are
    the same for the same seed), with the result it had."""
    if "case" in entry:
        task = {"kind": "geometry", "case": geometry_case(seed, entry["case"])}
    else:
        task = converter_task(seeds, entry["encoding"], entry["index"], seed)
    result = {k: v for k, v in entry.items() if k in ("ok", "signature", "detail", "code")}
    return dict(task, result={"detail": "", **result})


def results_entry(task: dict, result: dict) -> dict:
    """The line of results.jsonl for one run: the task without its data, and the result."""
    entry = {k: v for k, v in task.items() if k not in ("data", "case", "slot")}
    if "case" in task:
        entry.update(case=task["case"]["index"], kind=task["case"]["kind"])
    entry.update({k: v for k, v in result.items() if k != "detail"})
    if not result["ok"]:
        entry["detail"] = result["detail"][-600:]
    return entry


def campaign(args, encodings, seeds, pool: Pool) -> int:
    """Run what ``args.out`` has not recorded yet of this campaign (all of it
    in a new folder), then shrink the failures and write the summary of every
    recorded run. Returns 1 when a run failed, 2 when the folder holds runs of
    another campaign, 128 + the signal's number when SIGINT or SIGTERM stopped it."""
    if args.replay:
        return replay(args, seeds, pool)
    started = time.monotonic()
    plan = plan_of(args, encodings, seeds)
    try:
        earlier, wall_before = recorded(args.out, plan)
    except ResumeRefused as error:
        print(f"fuzz.py: {error}", file=sys.stderr)
        return 2
    if getattr(args, "resume", False) and not earlier:
        print(f"fuzz.py: nothing to resume in {args.out}", file=sys.stderr)
        return 2
    save_plan(args.out, plan, wall_before)
    known = {} if args.no_known else known_signatures(pool)
    tally = Tally()
    for entry in earlier:
        tally.add(entry, lambda entry=entry: earlier_task(entry, seeds, args.seed))
    done = {run_key(entry) for entry in earlier}
    try:
        with _signals_interrupt(), (args.out / RESULTS).open("a") as log:
            _run_remaining(args, encodings, seeds, pool, tally, done, log)
    except Interrupted as interrupt:
        save_plan(args.out, plan, wall_before + time.monotonic() - started)
        recorded_runs = sum(c["runs"] for c in tally.counts.values())
        print(
            f"\nfuzz.py: stopped by {interrupt}; {recorded_runs} runs kept in "
            f"{args.out / RESULTS}; go on with the same command (or --resume)",
            file=sys.stderr,
        )
        return 128 + interrupt.signum
    save_plan(args.out, plan, wall_before + time.monotonic() - started)
    if not args.quiet:
        print(file=sys.stderr)
    rows = write_failures(args, pool, tally.first, tally.by_signature, known)
    summary = summary_table(tally.counts, rows, time.monotonic() - started + wall_before, args)
    (args.out / "summary.md").write_text(summary)
    print(summary)
    return 1 if tally.by_signature else 0


@contextmanager
def _signals_interrupt() -> Iterator[None]:
    """Inside the block SIGINT and SIGTERM raise :class:`Interrupted`."""

    def interrupt(signum, frame):
        raise Interrupted(signum)

    previous = {s: signal.signal(s, interrupt) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def _run_remaining(args, encodings, seeds, pool: Pool, tally: Tally, done: set, log) -> None:
    """The runs not in ``done``, each added to ``tally`` and written to ``log``
    (flushed: a kill loses only the runs in flight)."""
    started = time.monotonic()
    total = args.inputs * len([e for e in encodings if seeds.get(e)]) + args.geometry
    progress = [len(done)]

    def record(task, result):
        entry = results_entry(task, result)
        tally.add(entry, lambda: dict(task, result=result))
        log.write(json.dumps(entry, default=str) + "\n")
        log.flush()
        progress[0] += 1
        if not args.quiet and (progress[0] % 25 == 0 or not result["ok"]):
            rate = (progress[0] - len(done)) / max(time.monotonic() - started, 1e-9)
            failures = sum(tally.by_signature.values())
            print(
                f"\r[{progress[0]}/{total}] {rate:5.1f} runs/s, {failures} failures, "
                f"{len(tally.by_signature)} signatures",
                end="",
                file=sys.stderr,
                flush=True,
            )

    deadline = [started + 60 * args.max_minutes if args.max_minutes else math.inf]

    def stop_now(signum, frame):  # SIGUSR1: start no more runs, shrink and summarise
        deadline[0] = 0.0

    signal.signal(signal.SIGUSR1, stop_now)

    def until_deadline(tasks):
        for task in tasks:
            if time.monotonic() > deadline[0]:
                return
            yield task

    # Geometry first when both run: it is quick, and a deadline then cuts mutants.
    cases = (
        {"kind": "geometry", "case": geometry_case(args.seed, i)}
        for i in range(args.geometry)
        if ("geometry", i) not in done
    )
    for task, result in pool.run(until_deadline(cases)):
        record(task, result)
    mutants = converter_tasks(seeds, encodings, args.inputs, args.seed, args.first_index, done)
    for task, result in pool.run(until_deadline(mutants)):
        record(task, result)


def write_failures(args, pool: Pool, first, by_signature, known) -> list[list[str]]:
    rows = []
    for number, (signature, count) in enumerate(by_signature.most_common(), start=1):
        task = first[signature]
        folder = args.out / "failures" / f"{number:02d}_{slug(signature)}"
        folder.mkdir(parents=True, exist_ok=True)
        result = task["result"]
        tries = args.shrink_tries if not signature.startswith("timeout") else 8
        if task["kind"] == "geometry":
            (folder / "original.py").write_text(geometry_reproducer(task["case"]))
            small = shrink_case(pool, task["case"], signature, tries)
            (folder / "smallest.py").write_text(geometry_reproducer(small))
            smallest = f"{len(small['faces'])} faces"
            run = f"python {folder.name}/smallest.py"
        else:
            suffix = task["suffix"]
            (folder / f"original{suffix}").write_bytes(task["data"])
            small_data = shrink_input(pool, task, signature, tries)
            (folder / f"smallest{suffix}").write_bytes(small_data)
            smallest = f"{len(small_data)} bytes"
            argv = [
                f"smallest{suffix}" if a == "IN" else ("out" + a[3:] if a.startswith("OUT") else a)
                for a in task["argv"]
            ]
            run = "shadowgeo " + " ".join(argv)
        note = {k: v for k, v in task.items() if k not in ("data", "result", "slot", "case")}
        if "case" in task:
            note.update({k: task["case"][k] for k in ("seed", "index", "kind", "light_kind")})
        (folder / "README.txt").write_text(
            f"signature: {signature}\nruns failing this way: {count}\nreproduce: {run}\n"
            f"task: {json.dumps(note, default=str)}\n\n{result['detail']}\n"
        )
        also = ", ".join(known.get(signature, [])) or "-"
        rows.append([str(number), signature, str(count), smallest, run, also])
    return rows


def summary_table(counts, rows, seconds: float, args) -> str:
    lines = [
        f"# shadowgeo fuzz: seed {args.seed}, {args.inputs} mutants per encoding, "
        f"{args.geometry} geometry cases, {seconds:.0f} s, jobs {args.jobs}, "
        f"budget {args.time_budget:g} s / {args.memory_budget:g} GiB",
        "",
        "| encoding | runs | exit 0 | exit 1 | exit 2 | failures |",
        "|---|---|---|---|---|---|",
    ]
    for group in sorted(counts):
        c = counts[group]
        lines.append(
            f"| {group} | {c['runs']} | {c['exit 0']} | {c['exit 1']} | {c['exit 2']} "
            f"| {c['FAIL']} |"
        )
    lines += ["", "| # | signature | runs | smallest | reproduce | known finding |"]
    lines.append("|---|---|---|---|---|---|")
    lines += ["| " + " | ".join(row) + " |" for row in rows] or ["| - | no failures | | | | |"]
    per = [
        f"| {group} | {sig} | {n} |"
        for group in sorted(counts)
        for sig, n in counts[group].most_common()
        if sig not in ("runs", "FAIL") and not sig.startswith("exit ")
    ]
    if per:
        lines += ["", "| encoding | signature | runs |", "|---|---|---|", *per]
    return "\n".join(lines) + "\n"
