"""Kill a batch, resume it, check it; the same on Ray with a worker killed; throughput.

    python scripts/batch_check.py /tmp/bc --clips 20 --frames 30 --size 480x640

1. writes ``--clips`` generated videos (windows of one rendering of the demo scene);
2. local engine: starts ``motionbits batch``, kills it with SIGKILL at a random moment,
   runs the same command again and checks that every video has exactly one record (none
   redone, none missing), every output is complete and no partial output is left;
3. Ray engine (if installed): a fresh batch folder, a Ray worker killed with SIGKILL while
   it segments a video, the same checks;
4. throughput of an uninterrupted local run and of Ray, with the per-video cost split into
   decoding, flow, the rest of the segmenter and writing + start-up.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

from motionbits.video import iter_frames


def make_clips(folder: Path, n: int, frames: int, size: str) -> list[Path]:
    """``n`` videos of ``frames`` frames: windows of one rendering of the demo scene, each
    starting one frame later (rendering is the slow part)."""
    import cv2

    from motionbits.synth import demo_clip

    folder.mkdir(parents=True, exist_ok=True)
    h, w = (int(v) for v in size.split("x"))
    paths = [folder / f"clip{i:02d}.mp4" for i in range(n)]
    if all(p.exists() for p in paths):
        return paths
    rendered = demo_clip(n_frames=frames + n - 1, size=(h, w)).frames
    for i, path in enumerate(paths):
        writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), 10.0, (w, h))
        for f in rendered[i:i + frames]:
            writer.write(cv2.cvtColor(f, cv2.COLOR_RGB2BGR))
        writer.release()
    return paths


def records(out: Path) -> list[dict]:
    path = out / "batch.jsonl"
    return [json.loads(x) for x in path.read_text().splitlines()] if path.exists() else []


def check(out: Path, clips: list[Path], frames: int) -> str:
    recs = records(out)
    inputs = [r["input"] for r in recs]
    dup = len(inputs) - len(set(inputs))
    missing = {str(c.resolve()) for c in clips} - set(inputs)
    bad = []
    for r in recs:
        folder = Path(r["output"] or "-")
        ok = (r["status"] == "done" and r["frames"] == frames
              and json.loads((folder / "summary.json").read_text())["frames"] == frames
              and len(list((folder / "labels").glob("*.png"))) == frames
              and (folder / "overlay.mp4").stat().st_size > 0)
        if not ok:
            bad.append(r["input"])
    partial = (out / ".partial").exists()
    verdict = "OK" if not (dup or missing or bad or partial) else "FAILED"
    return (f"{verdict}: {len(recs)} records, {dup} redone, {len(missing)} missing, "
            f"{len(bad)} incomplete, partial folder left: {partial}")


def batch_cmd(inputs: Path, out: Path, engine: str, workers: int) -> list[str]:
    return [sys.executable, "-m", "motionbits.cli", "batch", str(inputs), "--out", str(out),
            "--engine", engine, "--workers", str(workers), "--quiet"]


def kill_ray_worker(killed: list, stop: threading.Event) -> None:
    import psutil

    while not stop.is_set() and not killed:
        for p in psutil.process_iter(["pid", "cmdline"]):
            cmd = p.info["cmdline"] or [""]
            if cmd[0].startswith("ray::segment_video_task"):
                time.sleep(random.uniform(0.5, 2.0))  # somewhere inside the video
                try:
                    os.kill(p.pid, signal.SIGKILL)
                    killed.append(p.pid)
                except ProcessLookupError:
                    continue
                return
        time.sleep(0.05)


def cost_breakdown(out: Path, clips: list[Path]) -> str:
    """Per-video seconds: decoding (timed here on the first clip), flow, the rest of the
    segmenter (summary.json), writing + start-up (the rest of the record's seconds)."""
    t0 = time.perf_counter()
    n = sum(1 for _ in iter_frames(clips[0]))
    decode = (time.perf_counter() - t0)
    flows, rests, totals = [], [], []
    for r in records(out):
        s = json.loads((Path(r["output"]) / "summary.json").read_text())["timings_ms"]
        seg = s["total_s"]
        flow = s["stages_median"]["flow"] * (r["frames"] - 1) / 1000
        flows.append(flow)
        rests.append(seg - flow)
        totals.append(r["seconds"])
    total = float(np.median(totals))
    flow, rest = float(np.median(flows)), float(np.median(rests))
    write = total - decode - flow - rest
    return (f"per video (median, {n} frames): {total:.2f} s = decode {decode:.2f} + flow {flow:.2f} "
            f"+ rest of the segmenter {rest:.2f} + writing and start-up {write:.2f}")


def run_timed(cmd: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(cmd, check=False, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("work", help="work folder")
    p.add_argument("--clips", type=int, default=20)
    p.add_argument("--frames", type=int, default=30)
    p.add_argument("--size", default="480x640")
    p.add_argument("--workers", type=int, default=os.cpu_count())
    p.add_argument("--seed", type=int, help="seed of the random kill moment")
    p.add_argument("--skip-throughput", action="store_true", help="only the kill checks")
    p.add_argument("--throughput-only", action="store_true", help="only the throughput runs")
    args = p.parse_args()
    rng = random.Random(args.seed)
    work = Path(args.work)
    clips = make_clips(work / "clips", args.clips, args.frames, args.size)
    n = len(clips)

    have_ray = importlib.util.find_spec("ray") is not None
    if not args.throughput_only:
        # 1. local: kill -9 at a random moment, resume, check
        out = work / "local_kill"
        subprocess.run(["rm", "-rf", str(out)], check=True)
        cmd = batch_cmd(work / "clips", out, "local", args.workers)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
        # somewhere in the first 70% of the batch's expected time (~0.35 s a frame here)
        delay = rng.uniform(3.0, 0.7 * n * args.frames * 0.35 / args.workers)
        time.sleep(delay)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        before = len(records(out))
        partial = len(list((out / ".partial").glob("*"))) if (out / ".partial").exists() else 0
        print(f"local: killed with SIGKILL after {delay:.1f} s: {before}/{n} recorded, "
              f"{partial} partial outputs on disk")
        t = run_timed(cmd)
        print(f"local: resumed in {t:.1f} s; {check(out, clips, args.frames)}")

        # 2. Ray: a worker killed mid-video
        if not have_ray:
            print("ray: not installed, skipped")
        else:
            out = work / "ray_kill"
            subprocess.run(["rm", "-rf", str(out)], check=True)
            killed, stop = [], threading.Event()
            killer = threading.Thread(target=kill_ray_worker, args=(killed, stop))
            killer.start()
            t = run_timed(batch_cmd(work / "clips", out, "ray", args.workers))
            stop.set()
            killer.join()
            print(f"ray: {len(killed)} worker killed with SIGKILL mid-video; batch took {t:.1f} s; "
                  f"{check(out, clips, args.frames)}")

    if args.skip_throughput:
        return 0
    # 3. throughput: an uninterrupted local run (Ray's run above had a worker killed, so
    # it is timed again too)
    for engine in ("local", "ray"):
        if engine == "ray" and not have_ray:
            continue
        out = work / f"{engine}_clean"
        subprocess.run(["rm", "-rf", str(out)], check=True)
        t = run_timed(batch_cmd(work / "clips", out, engine, args.workers))
        print(f"{engine} ({args.workers} workers): {n} videos x {args.frames} frames "
              f"{args.size} in {t:.1f} s = {3600 * n / t:.0f} videos/hour, "
              f"{n * args.frames / t:.2f} frames/s; {check(out, clips, args.frames)}")
        print(f"  {cost_breakdown(out, clips)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
