"""``motionbits batch``: inputs, the journal, resuming after kill -9, killed workers, Ray."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from motionbits.batch import Journal, expand_inputs, run_batch
from motionbits.synth import demo_clip

REPO = Path(__file__).resolve().parents[1]
OPTIONS = {"nodes": 100, "max_side": 64}  # tiny grids: each clip takes well under a second


def write_clip(folder: Path, frames: int = 4, seed: int = 0, size=(48, 64)) -> Path:
    """A generated clip as a folder of PNG frames."""
    folder.mkdir(parents=True)
    for i, f in enumerate(demo_clip(n_frames=frames, size=size, seed=seed).frames):
        cv2.imwrite(str(folder / f"{i:03d}.png"), cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
    return folder


def records(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / "batch.jsonl").read_text().splitlines()]


def assert_complete(out: Path, inputs: list[Path], bad: list[Path] = ()) -> None:
    """Every input recorded exactly once (nothing redone), every output complete."""
    recs = records(out)
    by_input = {}
    for r in recs:
        assert r["input"] not in by_input, f"{r['input']} recorded twice"
        by_input[r["input"]] = r
    assert set(by_input) == {str(p.resolve()) for p in [*inputs, *bad]}
    for p in bad:
        r = by_input[str(p.resolve())]
        assert r["status"] == "failed" and r["error"] and r["output"] is None
    for p in inputs:
        r = by_input[str(p.resolve())]
        assert r["status"] == "done", r
        folder = Path(r["output"])
        assert folder == out / p.name
        summary = json.loads((folder / "summary.json").read_text())
        assert summary["frames"] == r["frames"] == len(list(p.iterdir()))
        assert len(list((folder / "labels").glob("*.png"))) == r["frames"]
        assert (folder / "overlay.mp4").stat().st_size > 0
    assert not (out / ".partial").exists()
    expected = {"batch.jsonl", *(p.name for p in inputs)}
    assert {q.name for q in out.iterdir()} == expected


def test_expand_inputs(tmp_path):
    a = write_clip(tmp_path / "set1" / "a", frames=2)
    b = write_clip(tmp_path / "set2" / "deep" / "a", frames=2)  # same stem as a
    (tmp_path / "set2" / "v.mp4").write_bytes(b"x")
    (tmp_path / "set2" / "notes.md").write_text("not a video")
    lst = tmp_path / "list.txt"
    lst.write_text("# clips\nset1/a\n\nmissing.mp4  # fails in the batch, not here\n")
    items = expand_inputs([str(lst), str(tmp_path / "set2"), str(tmp_path / "set1" / "*")])
    paths = [it.path for it in items]
    assert paths == [str(a), str(tmp_path / "missing.mp4"), str(b), str(tmp_path / "set2" / "v.mp4")]
    names = [it.name for it in items]
    assert names[1:] == ["missing", names[2], "v"] and names[0] != names[2]
    assert names[0].startswith("a-") and names[2].startswith("a-")
    with pytest.raises(FileNotFoundError, match="input not found: nope.mp4"):
        expand_inputs(["nope.mp4"], cwd=tmp_path)
    with pytest.raises(ValueError, match="no file matches"):
        expand_inputs(["*.avi"], cwd=tmp_path)


def test_list_files_that_name_themselves(tmp_path):
    """Was: RecursionError (a traceback) for a list naming itself or lists naming each other."""
    a = write_clip(tmp_path / "a", frames=2)
    (tmp_path / "self.txt").write_text("self.txt\n")
    (tmp_path / "one.txt").write_text("a\ntwo.txt\n")
    (tmp_path / "two.txt").write_text("one.txt\n")
    for name in ("self.txt", "one.txt"):
        with pytest.raises(ValueError, match=f"list file .*{name} names itself"):
            expand_inputs([name], cwd=tmp_path)
    assert [it.path for it in expand_inputs(["a"], cwd=tmp_path)] == [str(a)]
    # a glob in a list skips the list itself ("*" = everything else in its folder)
    b = write_clip(tmp_path / "sub" / "b", frames=2)
    (tmp_path / "sub" / "all.list").write_text("*\n")
    assert [it.path for it in expand_inputs([str(tmp_path / "sub" / "all.list")])] == [str(b)]


def test_a_binary_list_file_is_named(tmp_path):
    (tmp_path / "videos.txt").write_bytes(b"\xff\xfe\x00 not text")  # was: "'utf-8' codec can't decode ..."
    with pytest.raises(ValueError, match="list file .*videos.txt is not text"):
        expand_inputs(["videos.txt"], cwd=tmp_path)


def test_journal_cuts_a_torn_line(tmp_path):
    j = Journal(tmp_path / "batch.jsonl")
    j.append({"input": "/a", "status": "failed", "error": "x"})
    j.append({"input": "/a", "status": "done", "output": "/o/a", "frames": 3})
    with open(tmp_path / "batch.jsonl", "ab") as f:
        f.write(b'{"input": "/b", "sta')  # killed mid-write
    j2 = Journal(tmp_path / "batch.jsonl")
    assert j2.torn == len(b'{"input": "/b", "sta')
    assert j2.status("/a") == "done" and j2.status("/b") is None
    j2.append({"input": "/b", "status": "done"})
    assert [json.loads(x)["input"] for x in (tmp_path / "batch.jsonl").read_text().splitlines()] \
        == ["/a", "/a", "/b"]


def test_batch_resumes_after_kill_9(tmp_path):
    rng = np.random.default_rng()
    clips = [write_clip(tmp_path / "in" / f"clip{i}", frames=6, seed=i) for i in range(6)]
    bad = tmp_path / "in" / "broken.mp4"
    bad.write_text("not a video")
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "motionbits.cli", "batch", str(tmp_path / "in"), "--out",
           str(out), "--workers", "2", "--nodes", "100", "--max-side", "64", "--quiet"]
    env = dict(os.environ, PYTHONPATH=str(REPO))
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    kill_after = int(rng.integers(1, 4))  # records on disk before the kill
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and proc.poll() is None:
        if (out / "batch.jsonl").exists() and len(records(out)) >= kill_after:
            break
        time.sleep(0.02)
    assert proc.poll() is None, "the batch ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    first = records(out)
    assert 1 <= len(first) < 7
    res = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert res.returncode == 1, res.stdout + res.stderr  # 1: a video failed
    done_first = sum(r["status"] == "done" for r in first)
    assert f"{6 - done_first} done" in res.stdout
    assert f"{len(first)} already recorded" in res.stdout
    assert records(out)[:len(first)] == first
    assert_complete(out, clips, [bad])


def _kill_one(match, started: threading.Event, killed: list, timeout: float = 60) -> None:
    """Kill -9 the first process whose command line satisfies ``match``."""
    import psutil

    deadline = time.monotonic() + timeout
    started.wait(timeout)
    while time.monotonic() < deadline and not killed:
        for p in psutil.process_iter(["pid", "cmdline"]):
            try:
                if match(p):
                    os.kill(p.pid, signal.SIGKILL)
                    killed.append(p.pid)
                    return
            except (psutil.Error, ProcessLookupError):
                pass
        time.sleep(0.02)


def test_local_pool_survives_a_killed_worker(tmp_path):
    import psutil

    clips = [write_clip(tmp_path / "in" / f"c{i}", frames=12, seed=i) for i in range(4)]
    out = tmp_path / "out"
    me = os.getpid()
    killed: list[int] = []
    started = threading.Event()

    def busy_worker(p) -> bool:  # a pool worker while a video is being written
        return (bool(p.info["cmdline"]) and "spawn_main" in " ".join(p.info["cmdline"])
                and p.ppid() == me and any((out / ".partial").glob("*/labels/*.png")))

    killer = threading.Thread(target=_kill_one, args=(busy_worker, started, killed))
    killer.start()
    started.set()
    report = run_batch(expand_inputs([str(tmp_path / "in")]), str(out), OPTIONS, workers=2,
                       quiet=True)
    killer.join()
    assert killed, "no worker was caught while running"
    assert report.done == 4 and report.failed == 0
    assert_complete(out, clips)
    assert psutil.pid_exists(killed[0]) is False or psutil.Process(killed[0]).status() == "zombie"


def _take(lock) -> None:
    """Take ``lock`` (a multiprocessing lock) and return, leaving it held."""
    lock.acquire()


def test_a_progress_lock_left_held_does_not_hang_a_worker_at_exit():
    """A worker killed while writing progress leaves the queue's lock held for good; a
    worker that wrote to that queue then waited at exit for its feeder thread, and the
    pool's shutdown with it (CI hung so once, under load). Here a process takes the lock
    and exits; a pool worker set up as the batch's are reports progress and must still
    exit."""
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    from motionbits.batch.local import _init_worker, _report

    ctx = mp.get_context("spawn")
    progress = ctx.Queue()
    holder = ctx.Process(target=_take, args=(progress._wlock,))  # exits holding the lock
    holder.start()
    holder.join(60)
    ex = ProcessPoolExecutor(1, mp_context=ctx, initializer=_init_worker, initargs=(progress,))
    ex.submit(_report, "clip", 1, 2).result(timeout=60)
    workers = list(ex._processes.values())
    closed = threading.Thread(target=ex.shutdown, daemon=True)
    closed.start()
    closed.join(30)
    hung = closed.is_alive()
    for p in workers:  # leave nothing behind if it hung
        p.kill()
    assert not hung, "the pool's shutdown waited on a worker stuck at exit"


def test_ray_batch_survives_a_killed_worker(tmp_path):
    pytest.importorskip("ray", reason="the ray extra is not installed")
    clips = [write_clip(tmp_path / "in" / f"c{i}", frames=12, seed=i) for i in range(4)]
    out = tmp_path / "out"
    killed: list[int] = []
    started = threading.Event()

    def ray_task(p) -> bool:  # Ray titles a worker ray::<task> while it runs one
        return bool(p.info["cmdline"]) and p.info["cmdline"][0].startswith("ray::segment_video_task")

    killer = threading.Thread(target=_kill_one, args=(ray_task, started, killed, 120))
    killer.start()
    started.set()
    report = run_batch(expand_inputs([str(tmp_path / "in")]), str(out), OPTIONS, engine="ray",
                       workers=2, quiet=True)
    killer.join()
    assert killed, "no Ray worker was caught while running"
    assert report.done == 4 and report.failed == 0
    assert_complete(out, clips)
