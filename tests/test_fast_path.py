"""The fast path (default) against the exact reference computation (``exact=True``)."""

import numpy as np
import pytest

from motionbits import MotionBitsConfig, segment_video
from motionbits.eval import adjusted_rand_index
from motionbits.synth import demo_clip


@pytest.fixture(scope="module")
def both_paths():
    size = (240, 320)
    clip = demo_clip(n_frames=8, size=size)
    config = MotionBitsConfig(n_nodes=2500, max_side=max(size))
    fast = list(segment_video(clip.frames, config))
    exact = list(segment_video(clip.frames, config.with_(exact=True)))
    return fast, exact


def test_fast_path_agrees_with_exact_at_grid_and_pixel_level(both_paths):
    fast, exact = both_paths
    # frame 0 has no flow and a MotionBit is shown once it has moved in two frames
    for f, e in zip(fast[2:], exact[2:]):
        assert f.node_labels.any(), "the clip must have moving bodies for this to test anything"
        assert adjusted_rand_index(f.node_labels, e.node_labels) >= 0.99
        assert adjusted_rand_index(f.labels, e.labels) >= 0.99


def test_exact_path_is_deterministic():
    clip = demo_clip(n_frames=4, size=(120, 160))
    config = MotionBitsConfig(n_nodes=900, max_side=160, exact=True)
    a = [r.labels for r in segment_video(clip.frames, config)]
    b = [r.labels for r in segment_video(clip.frames, config)]
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_segmenters_on_two_threads_give_what_each_gives_alone():
    """Each segmenter has its own second thread (memories, camera motion); two streams
    segmented at once, on two threads (a demo serving two users), give the label maps and
    twists each gives alone -- and so does each with its second thread's work run inline
    (where OpenCV may use one thread only, as in ``motionbits batch``'s workers)."""
    from concurrent.futures import ThreadPoolExecutor

    import cv2

    from motionbits.synth import demo_clip

    config = MotionBitsConfig(n_nodes=2500, max_side=320)
    clips = [demo_clip(n_frames=6, size=(240, 320), seed=s).frames for s in (0, 1)]

    def run(frames):
        return [(r.labels, [b.twist for b in r.motionbits]) for r in segment_video(frames, config)]

    alone = [run(c) for c in clips]
    with ThreadPoolExecutor(2) as pool:
        together = list(pool.map(run, clips))
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        inline = [run(c) for c in clips]
    finally:
        cv2.setNumThreads(threads)
    assert any(labels.any() for labels, _ in alone[0])
    for a, *others in zip(alone, together, inline):
        for b in others:
            for (la, ta), (lb, tb) in zip(a, b):
                np.testing.assert_array_equal(la, lb)
                np.testing.assert_array_equal(np.array(ta), np.array(tb))


def test_an_error_in_a_frame_waits_for_the_second_thread(monkeypatch):
    """When a step of the main thread fails, the second thread's work for that frame has
    ended by the time the error reaches the caller: a reset() after it is not overwritten."""
    import threading
    import time

    import motionbits.segmenter as seg_module
    from motionbits import MotionBitsSegmenter
    from motionbits.synth import demo_clip

    frames = demo_clip(n_frames=4, size=(240, 320)).frames
    seg = MotionBitsSegmenter(MotionBitsConfig(n_nodes=2500, max_side=320))
    for f in frames[:2]:
        seg.update(f)
    done = threading.Event()
    remember = seg._remember

    def slow_remember(*args):
        time.sleep(0.3)
        out = remember(*args)
        done.set()
        return out

    def failing(*args, **kwargs):
        raise RuntimeError("a step failed")

    monkeypatch.setattr(seg, "_remember", slow_remember)
    monkeypatch.setattr(seg_module, "flat_link_candidates", failing)  # after the memories start
    with pytest.raises(RuntimeError, match="a step failed"):
        seg.update(frames[2])
    assert done.is_set()


def test_a_task_queued_behind_other_work_runs_in_the_caller_that_needs_it():
    """``Task.result()`` runs the task in the calling thread when the second thread has
    not started it (busy with earlier work), once; a task it already ran is waited for."""
    import threading
    from concurrent.futures import ThreadPoolExecutor

    from motionbits.second_thread import Task

    release = threading.Event()
    ran_in = []

    def record(x):
        ran_in.append(threading.current_thread().name)
        return 2 * x

    with ThreadPoolExecutor(max_workers=1, thread_name_prefix="second") as ex:
        busy = ex.submit(release.wait)  # the second thread's earlier work
        task = Task(ex, record, 21)
        assert task.result() == 42 and ran_in == [threading.current_thread().name]
        release.set()
        busy.result()
        assert task.result() == 42 and len(ran_in) == 1  # not run again
        done = Task(ex, record, 1)
        ex.submit(int).result()  # the queue is empty: the second thread ran it
        assert done.result() == 2 and ran_in[-1].startswith("second")


def test_a_task_that_fails_raises_in_the_caller():
    from concurrent.futures import ThreadPoolExecutor

    from motionbits.second_thread import Task, _Inline

    def fail():
        raise ValueError("bad input")

    with ThreadPoolExecutor(max_workers=1) as ex:
        task = Task(ex, fail)
        ex.submit(int).result()
        with pytest.raises(ValueError, match="bad input"):
            task.result()
    with pytest.raises(ValueError, match="bad input"):  # inline
        Task(_Inline(), fail).result()
