"""Faults, not inputs (issue 34 item 3): what is on disk after an interrupt, a
signal, a full disk, a folder that cannot be written, two writers of one file
or a Dask worker killed mid-batch is each output whole (the bytes a clean run
writes, which load and, for X3D, parse) or absent, with no temporary file
left beside it, and the message names the file.

The conversions are real: a subprocess of the command line (``python -m cli``,
or ``-c`` with a slow disk: the file writes of the process done in small
chunks with a pause, so a signal lands while the temporary file is being
written), an in-process ``main`` with the low-level file write raising
ENOSPC or the file creation EACCES, a kernel file-size limit (RLIMIT_FSIZE:
every writer, usd-core's C++ one included, meets a real failing write), and a
Dask ``LocalCluster`` of worker processes, one of them SIGKILLed mid-batch.
"""

from __future__ import annotations

import ctypes
import errno
import io
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from lxml import etree
from needs import absent, need

import shadowgeo as sg
from cli.main import main
from shadowgeo.batch import ConvertOptions, convert_files
from shadowgeo.io.atomic import atomic_path, remove_stale

ROOT = Path(__file__).resolve().parents[1]
COURTYARD = ROOT / "examples" / "scenes" / "courtyard.x3d"
SAFE = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=True)
ENCODINGS = (".x3d", ".x3dz", ".x3dv", ".wrl", ".x3dj", ".glb", ".gltf", ".usda", ".usdc")

# Run the command line with every file write of the process slowed to about
# 3 MB/s (16 KiB, then SLOW_DISK_PAUSE: 5 ms): a signal sent once the
# temporary file shows up lands while it is being written, and two writers
# overlap.
SLOW_DISK = """
import builtins, io, os, sys, time
real_open = io.open
class Slow:
    def __init__(self, handle):
        self.handle, self.began = handle, None
    def write(self, data):
        self.began = self.began or time.monotonic()
        data = memoryview(data).cast("B") if not isinstance(data, str) else data
        for start in range(0, len(data), 16384):
            self.handle.write(data[start:start + 16384])
            self.handle.flush()
            time.sleep(float(os.environ.get("SLOW_DISK_PAUSE", 0.005)))
        return len(data)
    def close(self):
        self.handle.close()
        if self.began and os.environ.get("SLOW_DISK_LOG"):  # when this file was written
            with real_open(os.environ["SLOW_DISK_LOG"], "a") as log:
                log.write(f"{self.began} {time.monotonic()}\\n")
    def __getattr__(self, name):
        return getattr(self.handle, name)
    def __enter__(self):
        return self
    def __exit__(self, *exc):
        self.close()
def slow_open(file, mode="r", *args, **kwargs):
    handle = real_open(file, mode, *args, **kwargs)
    return Slow(handle) if any(flag in mode for flag in "wax") else handle
builtins.open = io.open = slow_open
from cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def grid_scene(path: Path, n: int = 200, lift: float = 3.0) -> Path:
    """A wavy n x n grid (``2 n**2`` triangles) under a floating crate: about
    0.7 s to convert and 1.8 MB of X3D at n = 200."""
    side = [-10 + 20 * i / n for i in range(n + 1)]
    points = " ".join(f"{x:.6g} {0.3 * x * z / 100:.6g} {z:.6g}" for z in side for x in side)
    quads = " ".join(
        f"{a} {a + n + 1} {a + n + 2} {a + 1} -1"
        for a in (row * (n + 1) + column for row in range(n) for column in range(n))
    )
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n<X3D profile="Interchange" version="4.0">'
        '<Scene><DirectionalLight DEF="sun" direction="0.3 -1 0.2" shadows="true"/>'
        f'<Shape DEF="ground"><Appearance><Material/></Appearance><IndexedFaceSet solid="false" '
        f'coordIndex="{quads}"><Coordinate point="{points}"/></IndexedFaceSet></Shape>'
        f'<Transform translation="0 {lift} 0"><Shape DEF="crate"><Appearance><Material/>'
        '</Appearance><Box size="2 2 2"/></Shape></Transform></Scene></X3D>\n'
    )
    return path


def command(*args: object, slow: bool = False) -> list[str]:
    code = ["-c", SLOW_DISK] if slow else ["-m", "cli"]
    return [sys.executable, *code, *map(str, args)]


def run(
    *args: object, preexec: Callable[[], None] | None = None
) -> subprocess.CompletedProcess[str]:
    """The command line run to its end in a subprocess (``preexec`` in the
    child before it starts)."""
    return subprocess.run(
        command(*args),
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
        preexec_fn=preexec,
    )


def file_size_limit(size: int) -> Callable[[], None]:
    """A ``preexec`` making the kernel fail any write past ``size`` bytes
    (RLIMIT_FSIZE; EFBIG, as ENOSPC would fail it)."""

    def limited() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # else the signal ends the process
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))

    return limited


def start(
    *args: object, slow: bool = False, log: Path | None = None, pause: float = 0.005
) -> subprocess.Popen[str]:
    """The command line in a subprocess; with a slow disk, ``pause`` seconds
    after each 16 KiB, and ``log``: where it notes, a line a file, when it
    wrote (time.monotonic(), one clock for all processes)."""
    return subprocess.Popen(
        command(*args, slow=slow),
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "SLOW_DISK_LOG": str(log or ""), "SLOW_DISK_PAUSE": str(pause)},
    )


def catches_sigterm(pid: int) -> bool:
    """Whether the process has a handler for SIGTERM yet (``main`` is running)."""
    status = Path(f"/proc/{pid}/status")
    if not status.exists():
        return False
    for line in status.read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) >> (signal.SIGTERM - 1) & 1)
    return False


def wait_until(condition, process: subprocess.Popen[str], what: str, limit: float = 60) -> None:
    end = time.monotonic() + limit
    while not condition():
        if process.poll() is not None:
            pytest.fail(f"the conversion ended ({process.returncode}) before {what}")
        if time.monotonic() > end:
            process.kill()
            pytest.fail(f"no {what} within {limit} s")
        time.sleep(0.001)


def temporaries(folder: Path) -> list[str]:
    """Hidden files: what an atomic writer leaves when it is not cleaned up."""
    return sorted(str(p.relative_to(folder)) for p in folder.rglob(".*"))


def assert_whole(path: Path, expected: bytes) -> None:
    """``path`` holds what a clean run writes, opens, and for X3D parses."""
    assert path.read_bytes() == expected, f"{path} differs from a clean run's output"
    sg.load(path)
    if path.suffix == ".x3d":
        etree.parse(str(path), SAFE)


def assert_whole_or_absent(path: Path, expected: bytes) -> None:
    if path.exists():
        assert_whole(path, expected)
    assert not temporaries(path.parent), temporaries(path.parent)


@pytest.fixture(scope="module")
def big(tmp_path_factory) -> dict[str, Path | bytes]:
    """A ~1 s conversion, and what a clean run writes for it as .x3d and .glb."""
    folder = tmp_path_factory.mktemp("big")
    scene = grid_scene(folder / "grid.x3d")
    outputs: dict[str, Path | bytes] = {"scene": scene}
    for suffix in (".x3d", ".glb"):
        assert main(["convert", str(scene), str(folder / f"clean{suffix}")]) == 0
        outputs[suffix] = (folder / f"clean{suffix}").read_bytes()
    return outputs


def need_proc() -> None:
    if not Path(f"/proc/{os.getpid()}/status").exists():
        absent("the signal tests read /proc/PID/status (Linux) to know when main() is running")


# -- SIGINT, SIGTERM and SIGHUP -------------------------------------------------------------

# SIGHUP (a closed terminal or ssh session) is handled as SIGTERM is: exit 129.
SIGNALS = [signal.SIGINT, signal.SIGTERM, signal.SIGHUP]


@pytest.mark.parametrize("signum", SIGNALS, ids=[s.name for s in SIGNALS])
def test_a_signal_at_random_points_leaves_the_output_whole_or_absent(tmp_path, big, signum):
    need_proc()
    rng = random.Random(3400 + signum)  # fixed: the same points on every run
    for attempt, delay in enumerate(rng.uniform(0.0, 0.5) for _ in range(3)):
        out = tmp_path / f"run{attempt}" / "grid.x3d"
        process = start("convert", big["scene"], out)
        wait_until(lambda pid=process.pid: catches_sigterm(pid), process, "main() running")
        time.sleep(delay)
        process.send_signal(signum)
        _, stderr = process.communicate(timeout=120)
        assert "Traceback" not in stderr, stderr
        assert process.returncode in (0, 128 + signum), (delay, process.returncode, stderr)
        if process.returncode == 0:  # finished before the signal
            assert_whole(out, big[".x3d"])
        else:
            last = "interrupted" if signum == signal.SIGINT else f"stopped by {signum.name}"
            assert stderr.splitlines()[-1] == f"shadowgeo: {last}", stderr
        assert_whole_or_absent(out, big[".x3d"])


@pytest.mark.parametrize("suffix", [".x3d", ".glb"])
@pytest.mark.parametrize("signum", SIGNALS, ids=[s.name for s in SIGNALS])
def test_a_signal_while_the_output_is_written_removes_the_temporary_file(
    tmp_path, big, signum, suffix
):
    need_proc()
    out = tmp_path / f"grid{suffix}"
    process = start("convert", big["scene"], out, slow=True)
    wait_until(
        lambda: any(p.stat().st_size for p in tmp_path.glob(f".grid{suffix}.*")),
        process,
        "temporary file with bytes in it",
    )
    process.send_signal(signum)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, stderr
    assert "Traceback" not in stderr, stderr
    assert not out.exists()  # written at 3 MB/s: far from done
    assert temporaries(tmp_path) == []


def test_sigkill_mid_write_leaves_a_hidden_temporary_that_the_next_run_removes(tmp_path, big):
    """SIGKILL cannot be caught: the temporary file stays (never the output),
    and the next run writing that output removes it."""
    out = tmp_path / "grid.x3d"
    process = start("convert", big["scene"], out, slow=True)
    wait_until(lambda: temporaries(tmp_path), process, "temporary file")
    process.kill()
    process.wait(timeout=60)
    assert not out.exists() and len(temporaries(tmp_path)) == 1
    assert main(["convert", str(big["scene"]), str(out)]) == 0
    assert_whole_or_absent(out, big[".x3d"])
    assert out.exists()


# -- a full disk ----------------------------------------------------------------------------


class FullDisk:
    """A file object whose writes fail with ENOSPC once ``room`` bytes are in."""

    def __init__(self, handle, room: int) -> None:
        self.handle, self.room = handle, room

    def write(self, data) -> int:
        size = len(data)
        if size > self.room:
            self.handle.write(data[: self.room])  # a partial file on disk, as a full disk leaves
            self.handle.flush()
            self.room = 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.room -= size
        return int(self.handle.write(data))

    def __getattr__(self, name):
        return getattr(self.handle, name)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.handle.close()


@pytest.fixture
def full_disk(monkeypatch):
    """Every file opened for writing takes 100 bytes, then ENOSPC."""
    real_open = io.open

    def opener(file, mode="r", *args, **kwargs):
        handle = real_open(file, mode, *args, **kwargs)
        return FullDisk(handle, 100) if any(flag in mode for flag in "wax") else handle

    monkeypatch.setattr("builtins.open", opener)
    monkeypatch.setattr(io, "open", opener)


@pytest.mark.parametrize("suffix", [s for s in ENCODINGS if not s.startswith(".usd")])
def test_a_full_disk_is_one_line_naming_the_file_and_leaves_nothing(
    capsys, tmp_path, full_disk, suffix
):
    """(usd-core writes in C++, past Python's open: see the file-size limit below.)"""
    out = tmp_path / "out" / f"courtyard{suffix}"
    code = main(["convert", str(COURTYARD), str(out)])
    stderr = capsys.readouterr().err
    assert code == 1
    assert stderr.splitlines() == [
        f"shadowgeo convert: {out}: cannot write: No space left on device"
    ]
    assert not out.exists() and temporaries(tmp_path) == []


def test_a_full_disk_leaves_the_file_it_would_replace_as_it_was(capsys, tmp_path, full_disk):
    out = tmp_path / "courtyard.glb"
    out.write_bytes(b"the previous run's output")
    assert main(["convert", str(COURTYARD), str(out)]) == 1
    assert "No space left on device" in capsys.readouterr().err
    assert out.read_bytes() == b"the previous run's output"
    assert temporaries(tmp_path) == []


def test_a_full_disk_under_the_sun_study_and_a_batch(capsys, tmp_path, full_disk):
    out = tmp_path / "map.x3d"
    assert main(["sun", str(COURTYARD), str(out), "--at", "51.5,-0.12"]) == 1
    assert capsys.readouterr().err.splitlines()[-1] == (
        f"shadowgeo sun: {out}: cannot write: No space left on device"
    )
    jobs = [(COURTYARD, tmp_path / "batch" / "courtyard.glb")]
    (outcome,) = convert_files(jobs, ConvertOptions())
    assert outcome.error == f"{jobs[0][1]}: cannot write: No space left on device"
    assert not out.exists() and not jobs[0][1].exists() and temporaries(tmp_path) == []


def test_the_library_save_turns_a_full_disk_into_an_error_naming_the_output(tmp_path, full_disk):
    scene = sg.load(COURTYARD)
    out = tmp_path / "courtyard.glb"
    with pytest.raises(sg.SceneError) as raised:
        sg.save(scene, out)
    assert str(raised.value) == f"{out}: cannot write: No space left on device"
    assert isinstance(raised.value.__cause__, OSError)  # the cause is kept for a debugger
    assert not out.exists() and temporaries(tmp_path) == []


def test_the_library_save_into_a_missing_folder_names_the_output(tmp_path):
    # the temporary file beside it is what the system refuses: the error names the output
    out = tmp_path / "no such folder" / "courtyard.x3d"
    with pytest.raises(sg.SceneError, match="cannot write: No such file or directory") as raised:
        sg.save(sg.load(COURTYARD), out)
    assert raised.value.path == str(out) and str(raised.value).startswith(f"{out}: ")


@pytest.mark.parametrize("suffix", ENCODINGS)
def test_a_write_the_kernel_refuses_leaves_nothing_in_every_encoding(tmp_path, suffix):
    """RLIMIT_FSIZE makes the kernel fail the write past 1 KiB (EFBIG, "File
    too large", as ENOSPC would fail it), in every writer, usd-core's too."""
    out = tmp_path / f"courtyard{suffix}"
    done = run("convert", COURTYARD, out, preexec=file_size_limit(1024))
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"shadowgeo convert: {out}: cannot write: File too large"
    ] or done.stderr.splitlines() == [
        f"shadowgeo convert: {out}: cannot write: Error occurred writing file: File too large"
    ], done.stderr
    assert not out.exists() and temporaries(tmp_path) == []


# -- a folder that cannot be written --------------------------------------------------------


def test_a_read_only_output_folder_is_one_line_naming_the_file(tmp_path):
    """chmod 0o555. Root writes there anyway (CAP_DAC_OVERRIDE), so as root
    the command runs with that capability dropped, where the kernel refuses
    as it does for anyone else."""
    folder = tmp_path / "read-only"
    folder.mkdir()
    folder.chmod(0o555)
    out = folder / "courtyard.glb"
    try:
        done = run(
            "convert",
            COURTYARD,
            out,
            preexec=without_root_override if os.geteuid() == 0 else None,
        )
    finally:
        folder.chmod(0o755)
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines() == [
        f"shadowgeo convert: {out}: cannot write: the folder {folder} is not writable"
    ]
    assert list(folder.iterdir()) == []


def without_root_override() -> None:
    """Drop CAP_DAC_OVERRIDE and CAP_DAC_READ_SEARCH from the bounding set
    (prctl PR_CAPBSET_DROP) before exec: root then meets file permissions."""
    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (1, 2):
        if libc.prctl(24, capability, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), "prctl(PR_CAPBSET_DROP) refused")


@pytest.fixture
def refused_creation(monkeypatch, tmp_path):
    """Creating a file under ``tmp_path / "refused"`` fails with EACCES, as in
    a folder the user may not write (even as root); checking it first with
    os.access still says yes, so the write itself meets the refusal."""
    real_open = os.open
    folder = tmp_path / "refused"
    folder.mkdir()

    def opener(path, flags, *args, **kwargs):
        if flags & os.O_CREAT and Path(path).parent == folder:
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES), str(path))
        return real_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", opener)
    return folder


def test_a_folder_refusing_the_write_is_one_line_naming_the_file(
    capsys, tmp_path, refused_creation
):
    out = refused_creation / "courtyard.x3d"
    assert main(["convert", str(COURTYARD), str(out)]) == 1
    assert capsys.readouterr().err.splitlines() == [
        f"shadowgeo convert: {out}: cannot write: Permission denied"
    ]
    jobs = [(COURTYARD, refused_creation / "courtyard.glb")]
    (outcome,) = convert_files(jobs, ConvertOptions())
    assert outcome.error == f"{jobs[0][1]}: cannot write: Permission denied"
    assert list(refused_creation.iterdir()) == [] and temporaries(tmp_path) == []


# -- two writers of one file ----------------------------------------------------------------


def test_two_processes_writing_one_file_leave_one_of_them_whole(tmp_path):
    """Two conversions of different scenes into one output, their writes
    slowed to 0.5 MB/s so that they overlap (checked): the output is one of
    the two, byte for byte. Written in place, it would be a mix of both."""
    scenes = [grid_scene(tmp_path / f"grid{lift}.x3d", n=100, lift=lift) for lift in (2, 4)]
    expected = []
    for scene in scenes:
        assert main(["convert", str(scene), str(tmp_path / f"{scene.stem}.out.x3d")]) == 0
        expected.append((tmp_path / f"{scene.stem}.out.x3d").read_bytes())
    assert expected[0] != expected[1]
    folder = tmp_path / "both"
    folder.mkdir()
    out, log = folder / "out.x3d", tmp_path / "writes.log"
    # on a loaded machine one process may start late: slower writes, again
    for pause in (0.03, 0.1, 0.3):
        log.unlink(missing_ok=True)
        processes = [
            start("convert", scene, out, slow=True, log=log, pause=pause) for scene in scenes
        ]
        for process in processes:
            _, stderr = process.communicate(timeout=300)
            assert process.returncode == 0, stderr
        (first, first_end), (second, second_end) = (
            map(float, line.split()) for line in log.read_text().splitlines()
        )
        if first < second_end and second < first_end:
            break
    assert first < second_end and second < first_end, "the writes did not overlap"
    assert out.read_bytes() in expected
    assert_whole_or_absent(out, out.read_bytes())
    assert sorted(p.name for p in folder.iterdir()) == ["out.x3d"]


def test_remove_stale_removes_only_the_temporaries_of_dead_writers_here(tmp_path):
    target = tmp_path / "scene.glb"
    ended = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True
    )
    dead_pid = int(ended.stdout)
    with atomic_path(target) as ours:  # a live writer's: this process
        host = ours.name.split(".")[-2].split("-")[0]
        other_host = "0" * 8 if host != "0" * 8 else "1" * 8
        dead = tmp_path / f".scene.glb.{host}-{dead_pid}-0123abcd.glb"
        elsewhere = tmp_path / f".scene.glb.{other_host}-{dead_pid}-0123abcd.glb"
        usd_core = tmp_path / f".scene.glb.{host}-{dead_pid}-0123abcd.HOpbJl"  # usd-core's own
        other_file = tmp_path / f".other.glb.{host}-{dead_pid}-0123abcd.glb"
        for path in (dead, usd_core, elsewhere, other_file):
            path.write_bytes(b"half")
        assert sorted(remove_stale([target])) == sorted([dead, usd_core])
        assert ours.exists() and elsewhere.exists() and other_file.exists()
    assert not ours.exists() and target.exists()


# -- a Dask worker killed mid-batch ---------------------------------------------------------


@pytest.mark.parametrize("tries", [3, 0], ids=["retried", "reported"])
def test_a_worker_killed_mid_batch_is_retried_or_its_file_reported(tmp_path, tries):
    """A LocalCluster of two worker processes; once the first file is done,
    a worker busy converting is SIGKILLed. With Dask's allowed-failures at 3
    (its default) its task is run again elsewhere and every file is written;
    at 0 that file is reported as failed, naming it, and is whole or absent."""
    need("dask")
    import dask
    from dask.distributed import Client, LocalCluster

    scenes = [grid_scene(tmp_path / f"in{index}.x3d", n=100, lift=2 + index) for index in range(4)]
    expected = {}
    for scene in scenes:
        clean = tmp_path / "clean" / f"{scene.stem}.glb"
        assert main(["convert", str(scene), str(clean)]) == 0
        expected[scene.stem] = clean.read_bytes()
    jobs = [(scene, tmp_path / "out" / f"{scene.stem}.glb") for scene in scenes]
    killed: list[int] = []
    with dask.config.set({"distributed.scheduler.allowed-failures": tries}):
        with (
            LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):

            def kill_a_busy_worker(done: int, total: int) -> None:
                if killed:
                    return
                busy = [address for address, keys in client.processing().items() if keys]
                if busy:
                    pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
                    os.kill(pid, signal.SIGKILL)
                    killed.append(pid)

            outcomes = convert_files(
                jobs, ConvertOptions(), scheduler=client, progress=kill_a_busy_worker
            )
    assert killed, "no worker was busy when the first file finished: nothing was killed"
    failed = [outcome for outcome in outcomes if not outcome.ok]
    if tries:
        assert failed == []
    else:
        assert len(failed) >= 1
        for outcome in failed:
            assert f"not converted to {outcome.target}" in outcome.error
            assert "KilledWorker" in outcome.error
    for outcome in outcomes:
        if outcome.ok:
            assert_whole(outcome.target, expected[outcome.source.stem])
        assert_whole_or_absent(outcome.target, expected[outcome.source.stem])


def test_a_worker_killed_in_a_sun_study_on_dask_is_one_line_naming_the_day(capsys):
    """Several days of ``shadowgeo sun`` on a cluster whose worker is SIGKILLed
    while it studies a day, Dask's allowed-failures at 0: one line naming the
    day, exit 1, no traceback (sun writes no file over several days)."""
    need("dask")
    import threading

    import dask
    from dask.distributed import Client, LocalCluster

    killed: list[int] = []
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with (
            LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):

            def kill_a_busy_worker() -> None:
                end = time.monotonic() + 60
                while not killed and time.monotonic() < end:
                    busy = [address for address, keys in client.processing().items() if keys]
                    if busy:
                        pid = client.run(os.getpid, workers=busy[:1])[busy[0]]
                        os.kill(pid, signal.SIGKILL)
                        killed.append(pid)
                    time.sleep(0.02)

            killer = threading.Thread(target=kill_a_busy_worker)
            killer.start()
            code = main(
                [
                    "sun",
                    str(COURTYARD),
                    "--at",
                    "51.5,-0.12",
                    "--date",
                    "2026-03-21",
                    "--days",
                    "3",
                    "--every",
                    "20",
                    "--scheduler",
                    cluster.scheduler_address,
                ]
            )
            killer.join()
    stderr = capsys.readouterr().err
    assert killed, "no worker was busy: nothing was killed"
    assert code == 1, stderr
    assert "Traceback" not in stderr
    assert stderr.splitlines()[-1].startswith("shadowgeo sun: the Dask worker studying 2026-03-2")


def _distributed_level() -> int:
    """The least effective level of the loggers a worker's shutdown writes to."""
    import logging

    names = ("distributed.worker", "tornado.application", "asyncio")
    return min(logging.getLogger(name).getEffectiveLevel() for name in names)


def test_a_local_clusters_workers_log_only_critical_and_a_users_cluster_is_left_alone():
    """The workers of a LocalCluster started here, and this process while it
    runs, log nothing below CRITICAL from Dask or its event loop: under an
    interrupt a worker's heartbeat can fail while the cluster shuts down
    (CI, once), or tornado report a callback's exception (a full run here),
    and either ERROR traceback reads as a crash after the one line saying
    the run was stopped. The levels come back after; a cluster the user runs
    keeps its levels."""
    need("dask")
    import logging

    from dask.distributed import Client, LocalCluster

    from shadowgeo.parallel import client_for

    before_here = _distributed_level()
    with client_for("local", workers=1) as client:
        assert set(client.run(_distributed_level).values()) == {logging.CRITICAL}
        assert _distributed_level() == logging.CRITICAL  # and here, while it runs
    assert _distributed_level() == before_here
    with (
        LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        Client(cluster) as own,
    ):
        before = set(own.run(_distributed_level).values())
        with client_for(own) as client:
            assert client is own
        assert set(own.run(_distributed_level).values()) == before != {logging.CRITICAL}


def test_sigterm_mid_batch_on_a_local_cluster_leaves_whole_files_and_no_worker(tmp_path):
    """SIGTERM to a batch on a LocalCluster of two worker processes once its
    first file is written: exit 143, each output whole or absent, no
    temporary file, and no worker left running (to write after the exit)."""
    need("dask")
    need_proc()
    import psutil

    scene = grid_scene(tmp_path / "grid.x3d", n=100)
    assert main(["convert", str(scene), str(tmp_path / "clean.x3d")]) == 0
    expected = (tmp_path / "clean.x3d").read_bytes()
    inputs = tmp_path / "in"
    inputs.mkdir()
    # 24 files: on a loaded machine the batch must still be running when the
    # signal lands, and the workers get 30 s to be reaped (it failed once in a full run)
    for index in range(24):
        shutil.copy(scene, inputs / f"scene{index}.x3d")
    out = tmp_path / "out"
    process = start("convert", inputs, out, "--workers", "2")
    wait_until(lambda: list(out.glob("*.x3d")), process, "a first output", limit=120)
    workers = psutil.Process(process.pid).children(recursive=True)
    process.send_signal(signal.SIGTERM)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 143, stderr
    assert stderr.splitlines()[-1] == "shadowgeo: stopped by SIGTERM"
    assert "Traceback" not in stderr
    _, alive = psutil.wait_procs(workers, timeout=30)  # (a loaded machine is slow to reap)
    assert alive == [], f"workers still running after the exit: {alive}"
    written = sorted(out.glob("*.x3d"))
    assert 1 <= len(written) < 24
    for path in written:
        assert_whole(path, expected)
    assert temporaries(out) == []


def test_a_png_the_kernel_refuses_is_one_line_and_no_truncated_file(tmp_path):
    """``render`` under RLIMIT_FSIZE: VTK's PNG writer does not raise, it only
    sets an error code; the truncated picture must not be renamed into place."""
    done = run("render", COURTYARD, tmp_path / "can.png", "--size", "320x240")
    if done.returncode != 0:
        absent(f"render does not work here: {done.stderr.strip().splitlines()[-1:]}")
    out = tmp_path / "out" / "courtyard.png"
    out.parent.mkdir()
    done = run("render", COURTYARD, out, "--size", "320x240", preexec=file_size_limit(2048))
    assert done.returncode == 1, done.stderr
    assert done.stderr.splitlines()[-1].startswith(f"shadowgeo render: {out}: cannot write: ")
    assert "Traceback" not in done.stderr
    assert list(out.parent.iterdir()) == []
