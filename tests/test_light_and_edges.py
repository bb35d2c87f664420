"""A change of light is not motion, and a mask ends at its body's edge (issue "Only what
moved": moving shadows, halos on flat backgrounds)."""

import cv2
import numpy as np
import pytest
from scipy import ndimage

from motionbits import MotionBitsConfig, segment_video
from motionbits.completion import FirstLook
from motionbits.evidence import gradient_magnitude, static_residual
from motionbits.flow import DISFlow, normalize_contrast
from motionbits.masks import hide_edgeless, snap_to_edges, trim_flat_background
from motionbits.retirement import (OLD_SHADOW_SHARE, SHADOW_AGE, SHADOW_SHARE, CarriedBodies,
                                   retire_shadows)
from motionbits.revealed import StaticMemory, grey_change
from motionbits.shadows import BODY_SHARE, cast_shadows, trim_shadows
from motionbits.synth.planar import Body, Polygon, render_planar_clip

SIZE = (240, 320)
CONFIG = MotionBitsConfig(n_nodes=2500, max_side=max(SIZE))


def _texture(seed: int, scale: int = 4) -> np.ndarray:
    """(240, 320, 3) uint8 random colour texture, smooth over ``scale`` px."""
    noise = np.random.default_rng(seed).uniform(0, 255, (SIZE[0] // scale, SIZE[1] // scale, 3))
    tex = cv2.resize(noise.astype(np.float32), SIZE[::-1], interpolation=cv2.INTER_CUBIC)
    return np.clip(40 + 0.7 * tex, 0, 255).astype(np.uint8)


def _shadow(center: tuple[float, float], radius: float, depth: float, soft: float = 8.0
            ) -> np.ndarray:
    """(240, 320) float32 brightness gain: 1 - depth inside a disk whose penumbra is a
    logistic of scale ``soft`` px."""
    yy, xx = np.mgrid[:SIZE[0], :SIZE[1]]
    r = np.hypot(xx - center[0], yy - center[1])
    return (1 - depth / (1 + np.exp((r - radius) / soft))).astype(np.float32)


def _gray(img: np.ndarray) -> np.ndarray:
    return cv2.cvtColor(img, cv2.COLOR_RGB2GRAY).astype(np.float32)


def test_static_residual_explains_a_shadow_not_a_new_texture():
    base = _texture(0)
    shaded = np.clip(base * _shadow((160, 120), 50, 0.5)[..., None], 0, 255).astype(np.uint8)
    replaced = base.copy()
    replaced[70:170, 110:210] = _texture(1)[70:170, 110:210]
    yy, xx = np.mgrid[:SIZE[0], :SIZE[1]]
    inside = np.hypot(xx - 160, yy - 120) < 30
    for new, small in ((shaded, True), (replaced, False)):
        plain = np.abs(_gray(new) - _gray(base))[inside].mean()
        relit = static_residual(_gray(new), _gray(base), 19.0)[inside].mean()
        assert relit <= plain + 1e-4
        if small:  # the shadow darkens by up to 50%: tens of grey levels, nearly all explained
            assert plain > 20 and relit < 0.2 * plain, (plain, relit)
        else:  # another texture: no smooth gain explains it
            assert relit > 0.6 * plain, (plain, relit)


def test_normalised_frames_do_not_see_a_shadow():
    base = cv2.cvtColor(_texture(0), cv2.COLOR_RGB2GRAY)
    gain = _shadow((130, 120), 50, 0.5)
    shaded = np.clip(base * gain, 0, 255).astype(np.uint8)
    inside = gain < 0.7
    grey = np.abs(shaded.astype(np.float32) - base)[inside].mean()
    norm = np.abs(normalize_contrast(shaded).astype(np.float32) - normalize_contrast(base))
    assert grey > 40 and norm[inside].mean() < 0.1 * grey, (grey, norm[inside].mean())


def _moved_share(flow: np.ndarray) -> float:
    return float((np.hypot(flow[..., 0], flow[..., 1]) > 0.5).mean())


def test_dis_flow_does_not_follow_a_hard_shadow_and_finds_the_body():
    """A hard-edged shadow (penumbra ~2 px) jumps 15 px over a static texture while a
    textured square moves 8 px: the flow is ~0 under the shadow and 8 px on the body.
    Plain DIS (``normalize=False``) on the same frames follows the shadow's edge."""
    base = _texture(0)
    a, b = base.copy(), base.copy()
    a[150:210, 200:260] = b[150:210, 208:268] = _texture(2)[150:210, 200:260]
    a = np.clip(a * _shadow((110, 100), 50, 0.6, soft=2)[..., None], 0, 255).astype(np.uint8)
    b = np.clip(b * _shadow((125, 100), 50, 0.6, soft=2)[..., None], 0, 255).astype(np.uint8)
    static = np.ones(SIZE, bool)
    static[140:220, 190:285] = False
    robust, plain = DISFlow()(a, b), DISFlow(normalize=False)(a, b)
    assert _moved_share(robust[static]) < 0.005 < 0.02 < _moved_share(plain[static])
    body = robust[160:200, 210:250]
    assert np.abs(np.median(body, axis=(0, 1)) - (8, 0)).max() < 0.2


def test_plain_dis_flow_is_opencvs_and_the_frame_cache_sees_in_place_changes():
    a, b = _texture(0), _texture(1)
    gray = [cv2.cvtColor(f, cv2.COLOR_RGB2GRAY) for f in (a, b)]
    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    np.testing.assert_array_equal(DISFlow(normalize=False)(a, b), dis.calc(*gray, None))
    flow = DISFlow()
    still = flow(a, a.copy())
    assert _moved_share(still) == 0
    shifted = np.roll(a, 4, axis=1)
    a[:] = shifted  # the same array, new content: not the remembered frame any more
    moved = flow(a, b)
    np.testing.assert_array_equal(moved, DISFlow()(shifted, b))


def test_the_flow_of_a_pair_does_not_depend_on_the_calls_before():
    """OpenCV's DIS object starts a call without an initial flow from the last initial
    flow it was given (seen with opencv-python-headless 5.1): a backend that gave one
    object both kinds of call would make a pair's flow depend on the stream's history."""
    base = _texture(7)
    a, b = base, np.roll(base, (2, 6), axis=(0, 1))
    far = np.roll(base, 40, axis=1)  # another pair first, with large displacements
    for normalize in (True, False):
        fresh = DISFlow(normalize=normalize)(a, b)
        used = DISFlow(normalize=normalize)
        used(a, far), used(far, a), used(b, a)
        np.testing.assert_array_equal(used(a, b), fresh)


def _shadow_clip(n_frames: int = 12) -> list[np.ndarray]:
    base = _texture(5, scale=16)
    return [np.clip(base * _shadow((70 + 9 * t, 120), 50, 0.55)[..., None], 0, 255)
            .astype(np.uint8) for t in range(n_frames)]


@pytest.mark.parametrize("relight_sigma, expect_marks", [(3.0, False), (0.0, True)])
def test_moving_shadow_on_texture_is_not_a_motionbit(relight_sigma, expect_marks):
    """A soft shadow (penumbra ~30 px) sweeping 9 px/frame over a static texture: with the
    light-change test (``relight_sigma``, off by default) it is never a MotionBit; comparing
    grey levels only, it is (hard-edged shadows still are, see docs/reading_the_paper.md,
    "A change of light need not be motion")."""
    config = CONFIG.with_(relight_sigma=relight_sigma)
    shown = [len(r.motionbits) for r in segment_video(_shadow_clip(), config)]
    assert (max(shown) > 0) == expect_marks, shown


def _remembered(base: np.ndarray, labels: np.ndarray | None = None) -> StaticMemory:
    """A static memory that saw ``base`` standing still, with the MotionBits ``labels``
    (none by default) at rest on it."""
    memory = StaticMemory(SIZE, tolerance=10.0, covered=20.0)
    gray = _gray(base)
    memory.observe(base, gray, np.zeros(SIZE, np.float32))
    memory.update(base, gray, grey_change(gray, gray), np.ones(SIZE, bool),
                  np.zeros(SIZE, np.int32) if labels is None else labels)
    return memory


def _shadow_and_body(base: np.ndarray) -> np.ndarray:
    """``base`` under a hard shadow (centre (100, 120), radius 40, half the light) with a
    body of another texture over rows 100:160, columns 200:280."""
    cur = np.clip(base * _shadow((100, 120), 40, 0.5, soft=2)[..., None], 0, 255)
    cur = cur.astype(np.uint8)
    cur[100:160, 200:280] = _texture(7)[100:160, 200:280]
    return cur


def _observing_shadow_and_body() -> tuple[StaticMemory, np.ndarray]:
    """A memory that saw a texture standing still, after observing the frame of
    :func:`_shadow_and_body` on it; and that frame."""
    base = _texture(0)
    memory = _remembered(base)
    cur = _shadow_and_body(base)
    gray = _gray(cur)
    memory.observe(cur, gray, np.abs(gray - _gray(base)))
    return memory, cur


def test_memory_sees_a_cast_shadow_not_a_body():
    memory, cur = _observing_shadow_and_body()
    shadow = memory.shadowed(cur, (slice(0, SIZE[0]), slice(0, SIZE[1])))
    yy, xx = np.mgrid[:SIZE[0], :SIZE[1]]
    core = np.hypot(xx - 100, yy - 120) < 35
    lit = np.hypot(xx - 100, yy - 120) > 50
    lit[100:160, 200:280] = False
    assert shadow[core].mean() > 0.95
    assert shadow[100:160, 200:280].mean() < 0.05  # the body's colours are not the table's
    assert not shadow[lit].any()  # the lit table looks as remembered: no shadow
    # a box of the image: the same answer there
    box = (slice(90, 170), slice(60, 260))
    np.testing.assert_array_equal(memory.shadowed(cur, box), shadow[box])
    # under a moving camera the test reads the memory carried along the static world
    # (here a camera that did not move: the same answer)
    ys, xs = np.mgrid[:SIZE[0], :SIZE[1]].astype(np.float32)
    memory.observe(cur, _gray(cur), np.zeros(SIZE, np.float32), np.stack([xs, ys], -1))
    np.testing.assert_array_equal(memory.shadowed(cur, box), shadow[box])


def test_young_moving_cast_shadows_are_retired_bodies_and_others_kept():
    memory, cur = _observing_shadow_and_body()
    labels = np.zeros(SIZE, np.int32)
    labels[95:145, 75:125] = 1  # on the shadow, moving
    labels[100:160, 200:280] = 2  # the body, moving
    labels[150:160, 75:125] = 3  # on the shadow's lower edge, standing still
    first_moved = {1: 8, 2: 8, 3: 8}
    out = retire_shadows(labels, cur, memory, {1, 2}, first_moved, frame_index=10)
    assert set(np.unique(out)) == {0, 2, 3}
    np.testing.assert_array_equal(out[labels != 1], labels[labels != 1])
    assert set(np.unique(retire_shadows(labels, cur, memory, {1, 2, 3}, first_moved, 10))) == {0, 2}
    assert retire_shadows(labels, cur, memory, set(), first_moved, 10) is labels
    # a MotionBit that has moved for more than SHADOW_AGE frames is a shadow only if more
    # than OLD_SHADOW_SHARE of it looks shadowed (a wall shadow seen lit only later) ...
    old = {1: 1, 2: 8, 3: 8}
    assert retire_shadows(labels, cur, memory, {1, 2}, old, 1 + SHADOW_AGE) is not labels
    assert set(np.unique(retire_shadows(labels, cur, memory, {1, 2}, old, 2 + SHADOW_AGE))) == {
        0, 2, 3}
    # ... one half on the shadow, half on the lit table is a body once it is older
    half = np.zeros(SIZE, np.int32)
    half[95:145, 75:110] = 1
    half[95:145, 150:200] = 1
    share = memory.shadowed(cur, (slice(0, SIZE[0]), slice(0, SIZE[1])))[half == 1].mean()
    assert SHADOW_SHARE < share < OLD_SHADOW_SHARE
    assert retire_shadows(half, cur, memory, {1}, old, 1 + SHADOW_AGE).max() == 0
    assert retire_shadows(half, cur, memory, {1}, old, 2 + SHADOW_AGE) is half


def test_a_cast_shadow_retired_keeps_the_body_it_carried():
    """One MotionBit holds a body that moved 4 px to the right and a stretch of the
    shadow beside it (more than SHADOW_SHARE of it): the shadow goes, the body stays, its
    id kept. Where the MotionBit's motion does not explain the body better than standing
    still, or what is left is lit table as remembered, the whole MotionBit goes."""
    memory, cur = _observing_shadow_and_body()
    labels = np.zeros(SIZE, np.int32)
    labels[95:145, 75:125] = 1  # the shadow's core
    labels[100:160, 200:280] = 1  # the body
    body = labels == 1
    body[:, :200] = False
    prev = cur.copy()
    prev[100:160, 196:276] = cur[100:160, 200:280]  # one frame ago, 4 px to the left
    shift = (-4.0, 0.0)  # backward translation: from 4 px to the left
    cell = (5.0, 5.0)

    def carried(t: tuple[float, float]) -> CarriedBodies:
        return CarriedBodies(cell, _gray(cur), _gray(prev), np.array([1]), np.zeros(1),
                             np.array([t]), evidence=3.0)

    share = memory.shadowed(cur, (slice(0, SIZE[0]), slice(0, SIZE[1])))[labels == 1].mean()
    assert share > SHADOW_SHARE
    kept = retire_shadows(labels, cur, memory, {1}, {1: 8}, 10, carried(shift)) == 1
    assert not kept[~body].any() and kept[body].mean() > 0.9
    assert retire_shadows(labels, cur, memory, {1}, {1: 8}, 10).max() == 0  # no test
    # a body its motion does not explain (it stood still) is not kept
    assert retire_shadows(labels, cur, memory, {1}, {1: 8}, 10, carried((0.0, 0.0))).max() == 0
    # nor the lit table beside the shadow (it looks as remembered) ...
    table = np.zeros(SIZE, np.int32)
    table[95:145, 75:125] = 1
    table[180:230, 40:120] = 1
    assert retire_shadows(table, cur, memory, {1}, {1: 8}, 10, carried(shift)).max() == 0
    # ... nor what shows the remembered colour under more light, even moving with it (a
    # body of the table's look is retired with its shadow, as before)
    base = _texture(0)
    lit, lit_prev = cur.copy(), prev.copy()
    lit[180:230, 40:120] = np.clip(1.4 * base[180:230, 40:120], 0, 255).astype(np.uint8)
    lit_prev[180:230, 36:116] = lit[180:230, 40:120]
    memory = _remembered(base)
    memory.observe(lit, _gray(lit), np.abs(_gray(lit) - _gray(base)))
    assert memory.changed()[180:230, 40:120].mean() > 0.5
    assert retire_shadows(table, lit, memory, {1}, {1: 8}, 10, CarriedBodies(
        cell, _gray(lit), _gray(lit_prev), np.array([1]), np.zeros(1), np.array([shift]),
        evidence=3.0)).max() == 0


def test_a_body_at_rest_that_a_shadow_passes_over_is_not_taken_for_a_shadow():
    """A body at rest is remembered with its id. A shadow passing over it dims it (and the
    flow may follow the shadow's edge across it: it reads as moving), but it is the body:
    its MotionBit is not retired, its mark not trimmed. The same MotionBit where the memory
    holds the table is a shadow."""
    base = _texture(0)
    labels = np.zeros(SIZE, np.int32)
    labels[95:145, 75:125] = 1  # inside the shadow's disk
    cur = np.clip(base * _shadow((100, 120), 40, 0.5, soft=2)[..., None], 0, 255)
    cur = cur.astype(np.uint8)
    gray = _gray(cur)
    for rested, kept in ((None, False), (labels, True)):
        memory = _remembered(base, rested)
        memory.observe(cur, gray, np.abs(gray - _gray(base)))
        retired = retire_shadows(labels, cur, memory, {1}, {1: 8}, frame_index=10)
        trimmed = trim_shadows(labels, cast_shadows(memory, cur, labels))
        assert (retired is labels) == kept and (trimmed is labels) == kept
        if not kept:
            assert retired.max() == 0 and trimmed.max() == 0


def _marks_on_shadow_and_body() -> np.ndarray:
    """Mark 1: the body of :func:`_shadow_and_body` and a square of the shadow beside it;
    mark 2: a strip inside the shadow only."""
    labels = np.zeros(SIZE, np.int32)
    labels[100:160, 200:280] = 1
    labels[100:140, 90:130] = 1
    labels[142:152, 85:115] = 2
    return labels


def test_marks_shown_leave_out_the_cast_shadow_beside_their_body():
    memory, cur = _observing_shadow_and_body()
    labels = _marks_on_shadow_and_body()
    shadows = cast_shadows(memory, cur, labels)
    out = trim_shadows(labels, shadows)
    assert (labels[labels == 1].size - 4800) / labels[labels == 1].size < BODY_SHARE
    assert (out[100:160, 200:280] == 1).all()  # the body keeps its mark
    assert (out[105:135, 95:125] == 0).all()  # its shadow does not
    assert not (out == 2).any()  # a mark on the shadow only is not shown
    # nothing labelled: nothing to look at
    assert cast_shadows(memory, cur, np.zeros(SIZE, np.int32)) is None
    assert trim_shadows(labels, None) is labels


def test_a_shadow_inside_a_mark_leaves_no_hole():
    """A cast shadow lies beside its body: shadowed pixels the mark encloses stay in it."""
    memory, cur = _observing_shadow_and_body()
    labels = np.zeros(SIZE, np.int32)
    labels[70:170, 50:300] = 1  # the whole shadow inside one mark, with the body
    out = trim_shadows(labels, cast_shadows(memory, cur, labels))
    np.testing.assert_array_equal(out, labels)


def test_a_shadow_that_stood_still_is_told_by_the_scene_first_seen():
    """A shadow that stood still long enough is in the memory's look; the scene as first
    seen (``FirstLook``) still shows the table lit there."""
    base = _texture(0)
    cur = _shadow_and_body(base)
    shaded = np.clip(base * _shadow((100, 120), 40, 0.5, soft=2)[..., None], 0, 255)
    memory = _remembered(shaded.astype(np.uint8))  # learnt the shadow
    gray = _gray(cur)
    memory.observe(cur, gray, np.zeros(SIZE, np.float32))
    first = FirstLook(SIZE, covered=20.0, tolerance=10.0)
    first.update(base, np.ones(SIZE, bool), np.zeros(SIZE, np.int32))
    labels = _marks_on_shadow_and_body()
    assert trim_shadows(labels, cast_shadows(memory, cur, labels)) is labels
    out = trim_shadows(labels, cast_shadows(memory, cur, labels, first))
    assert (out[100:160, 200:280] == 1).all()
    assert (out[105:135, 95:125] == 0).all()
    assert not (out == 2).any()


def test_on_a_flat_table_a_dimmed_look_is_not_trimmed():
    """On a flat table a body's flat face of the table's hue, darker, would pass for a
    shadow: without texture under it, the marks stay as they are."""
    base = np.empty((*SIZE, 3), np.uint8)
    base[:] = (150, 120, 90)
    memory = _remembered(base)
    cur = _shadow_and_body(base)
    gray = _gray(cur)
    memory.observe(cur, gray, np.abs(gray - _gray(base)))
    labels = _marks_on_shadow_and_body()
    core = np.zeros(SIZE, bool)
    core[105:135, 95:125] = True
    assert memory.shadowed(cur, (slice(0, SIZE[0]), slice(0, SIZE[1])))[core].mean() > 0.95
    np.testing.assert_array_equal(trim_shadows(labels, cast_shadows(memory, cur, labels)),
                                  labels)


def test_a_moving_shadow_leaves_no_mark_of_its_own(monkeypatch):
    """On the soft shadow sweeping a texture, no MotionBit shown after its first frames
    lies inside the shadow; without retiring cast shadows the marks shown still leave it
    out (``trim_shadows``); without either, the shadow's mark is not shown as it stands
    as first seen, darker (``FirstLook.as_first_seen``); without all three, one mark lies
    in it."""
    clip = _shadow_clip()

    def inside_shadow() -> list[float]:
        shares = []
        for t, r in enumerate(segment_video(clip, CONFIG)):
            dark = _shadow((70 + 9 * t, 120), 50, 0.55) < 0.85
            shares += [dark[r.labels == m.id].mean() for m in r.motionbits if t >= 4]
        return shares

    assert max(inside_shadow(), default=0.0) < 0.6
    monkeypatch.setattr("motionbits.retirement.SHADOW_SHARE", 1.0)
    assert max(inside_shadow(), default=0.0) < 0.6
    monkeypatch.setattr("motionbits.segmenter.trim_shadows", lambda shown, shadows: shown)
    assert max(inside_shadow(), default=0.0) < 0.6
    monkeypatch.setattr(FirstLook, "as_first_seen",
                        lambda self, labels, rgb, moved=(): np.zeros(0, int))
    assert max(inside_shadow()) > 0.9


def test_a_textured_body_passes_the_light_test():
    body = Body((Polygon.rect(40, 80, 110, 150, texture_seed=3),), velocity=(6.0, 0.0))
    clip = render_planar_clip([body], size=SIZE, n_frames=12, seed=2)
    last = list(segment_video(clip.frames, CONFIG.with_(relight_sigma=3.0)))[-1]
    assert len(last.motionbits) == 1
    truth = clip.labels[-1] == 1
    pred = last.labels == last.motionbits[0].id
    assert (pred & truth).sum() / (pred | truth).sum() > 0.8


def test_snap_trims_a_halo_on_a_flat_background_and_adds_nothing():
    frame = np.full(SIZE + (3,), 200, np.uint8)
    frame[60:180, 100:220] = (180, 40, 40)  # a flat red body on a flat grey table
    frame[100:110, 220:300] = (180, 40, 40)  # with a thin arm, 10 px wide
    body = np.all(frame == (180, 40, 40), axis=2)
    halo = cv2.dilate(body.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0  # 4 px overhang
    labels = np.where(halo, 3, 0).astype(np.int32)
    out = snap_to_edges(labels, frame, band=7)
    assert set(np.unique(out)) <= {0, 3}
    assert not (out[~halo] > 0).any()  # nothing added
    got = out == 3
    assert (got & body).sum() / (got | body).sum() > 0.97
    assert got[100:110, 280:295].all()  # the thin arm keeps its pixels
    assert (snap_to_edges(labels, frame, band=0) == labels).all()


def test_edgeless_masks_are_hidden_bodies_kept():
    """A mask on a flat table that looks like the table around it is hidden; a body's
    mask, whose outline is an image edge, is kept -- also a mask one side of which runs
    along an edge only."""
    rng = np.random.default_rng(0)
    gray = np.full((120, 160), 200, np.float32) + rng.normal(0, 1.5, (120, 160)).astype(np.float32)
    gray[20:60, 20:60] = 90  # a flat dark body on the flat table
    gray[70:110, 100:150] -= 25 * (np.arange(50) / 50)[None, :]  # a soft shadow: a gentle ramp
    labels = np.zeros((120, 160), np.int32)
    labels[20:60, 20:60] = 1  # the body
    labels[75:105, 105:140] = 2  # inside the shadow's ramp
    labels[20:60, 60:75] = 3  # a strip right of the body: an edge along one side of it
    labels[5:15, 100:120] = 4  # flat table
    out = hide_edgeless(labels, gradient_magnitude(gray))
    assert set(np.unique(out)) == {0, 1, 3}
    assert (out[labels == 1] == 1).all() and (out[labels == 3] == 3).all()
    none = labels.copy()
    none[labels > 1] = 0
    assert hide_edgeless(none, gradient_magnitude(gray)) is none


def test_overhangs_onto_a_flat_table_are_trimmed_bodies_kept():
    """A mask that spills across no edge onto a flat table (a soft shadow, smeared flow)
    loses the spill; the body's flat faces, closed by its edges, stay whole -- also the
    part of a body whose mask covers only some of it."""
    rgb = np.full((240, 320, 3), (225, 225, 220), np.float32)  # a flat white table
    # a soft shadow below where the red body stands: no edge anywhere
    yy, xx = np.mgrid[:240, :320]
    rgb *= (1 - 0.2 * np.exp(-((yy - 80) ** 2 + (xx - 50) ** 2) / (2 * 15.0 ** 2)))[..., None]
    rgb = rgb.astype(np.uint8)
    rgb[30:70, 30:70] = (200, 40, 40)  # a flat red body
    rgb[30:70, 90:130] = (40, 40, 200)  # a flat blue body
    labels = np.zeros((240, 320), np.int32)
    labels[30:80, 25:75] = 1  # the red body and the shadow's spill around it
    labels[30:50, 90:130] = 2  # half of the blue body
    out = trim_flat_background(labels, rgb)
    assert (out[30:70, 30:70] == 1).all()
    # the spill, but for the pixels next to the body's edge (no flat region)
    far = ndimage.distance_transform_edt(~((labels == 1) & (rgb[..., 0] == 200))) > 6
    assert not (out[(labels == 1) & far] > 0).any()
    assert (out[labels == 2] == 2).all()  # the blue body's region is half in its mask
    nothing = np.zeros_like(labels)
    assert trim_flat_background(nothing, rgb) is nothing


def test_overhangs_of_several_bodies_onto_one_flat_table_are_all_trimmed():
    """Three bodies moved over one white table, each mask spilling onto a fifth of it:
    together they cover most of the table (before, the spill stayed where the table was
    less than 80% background, as on ``02_cups.mp4``), each only a small part."""
    rgb = np.full((240, 320, 3), (225, 225, 220), np.uint8)
    labels = np.zeros((240, 320), np.int32)
    for i, x in enumerate((20, 120, 220)):
        rgb[100:140, x + 20:x + 60] = ((200, 40, 40), (40, 200, 40), (40, 40, 200))[i]
        labels[60:200, x:x + 80] = i + 1  # the body and its spill all round
    out = trim_flat_background(labels, rgb)
    for i, x in enumerate((20, 120, 220)):
        body = np.zeros_like(labels, bool)
        body[100:140, x + 20:x + 60] = True
        assert (out[body] == i + 1).all()
        spill = (labels == i + 1) & (ndimage.distance_transform_edt(~body) > 4)
        assert not (out[spill] > 0).any(), i


def test_a_spill_over_a_third_of_a_plain_table_is_trimmed():
    """Fast motion smears one body's flow over a large part of a plain white table that
    reaches the image border (a third of it on 02_cups.mp4): more than a halo's share of
    the table, still not the body's. A large flat body that its mask mostly covers keeps its mask."""
    rgb = np.full((240, 320, 3), (225, 225, 220), np.uint8)  # a flat white table
    rgb[100:140, 140:180] = (200, 40, 40)  # a red cup
    body = np.zeros((240, 320), bool)
    body[100:140, 140:180] = True
    labels = np.zeros((240, 320), np.int32)
    labels[40:240, 60:260] = 1  # the cup and a spill over a third of the table
    assert (labels[rgb[..., 1] == 225] > 0).mean() > 0.4
    out = trim_flat_background(labels, rgb)
    assert (out[body] == 1).all()
    assert not (out[(labels == 1) & (ndimage.distance_transform_edt(~body) > 4)] > 0).any()
    # the same mask on a large flat green board (a body) that it covers 70% of: kept
    board = rgb.copy()
    board[40:240, 60:260] = (40, 160, 40)
    board[100:140, 140:180] = (200, 40, 40)
    partial = labels.copy()
    partial[180:240, 60:260] = 0
    assert (trim_flat_background(partial, board)[partial > 0] == 1).mean() > 0.95


def test_a_flat_face_mostly_inside_its_mask_is_completed_a_half_one_is_not():
    """A flat body whose mask has gaps (its flow read no motion in patches) gets the gaps;
    one whose mask covers only half of it is not grown where the face reaches the image
    border (half is no evidence that the rest moved), and the flat table around a body is
    never taken."""
    rgb = np.full((240, 320, 3), (225, 225, 220), np.uint8)  # a flat white table
    rgb[40:200, 30:70] = (120, 40, 160)  # a long flat purple link
    rgb[0:120, 200:240] = (40, 160, 40)  # a flat green body entering at the top
    labels = np.zeros((240, 320), np.int32)
    labels[40:200, 30:70] = 1
    labels[60:80, 30:50] = 0  # gaps reaching the link's outline: no hole to fill
    labels[150:175, 45:70] = 0
    labels[0:60, 200:240] = 2  # half of the green body
    labels[200:210, 30:70] = 1  # and a little spill of the link onto the table
    out = trim_flat_background(labels, rgb)
    assert (out[44:196, 34:66] == 1).all()  # all but the link's outline (not flat)
    assert (out[0:120, 200:240] == 2).sum() == (labels == 2).sum()
    table = rgb[..., 1] == 225
    far = ndimage.distance_transform_edt(table) > 4  # beyond the bodies' outlines
    assert not out[far].any()  # nothing of the table, the spill trimmed


def test_a_closed_face_partly_in_a_mask_seen_whole_is_completed():
    """A block seen whole whose flow read motion on its side and on a part of its flat
    front only: the front is closed by its edges and not much larger than the mask, so
    the mask takes it. Not where the mask reaches the image border (an arm crossing a
    table square), covers under a third of the front, or is under half of the front."""
    rgb = np.full((240, 320, 3), (225, 225, 220), np.uint8)  # a flat white table
    rgb[40:140, 40:120] = (150, 60, 40)  # a flat brown front, closed by its edges
    rgb[40:140, 120:180] = (90, 30, 20)  # the block's darker side
    front = np.zeros((240, 320), bool)
    front[40:140, 40:120] = True
    labels = np.zeros((240, 320), np.int32)
    labels[40:140, 120:140] = 1  # the side's near part ...
    labels[40:80, 40:120] = 1  # ... and 40% of the front
    out = trim_flat_background(labels, rgb)
    assert (out[44:136, 44:116] == 1).all()  # all but its outline (not flat)
    assert not out[rgb[..., 1] == 225].any()  # not the table
    arm = labels.copy()
    arm[0:40, 70:90] = 1  # the same mask reaching the top border: an arm
    assert not trim_flat_background(arm, rgb)[front & (labels == 0)].any()
    little = np.zeros_like(labels)
    little[40:140, 120:180] = 1  # the whole side and a fifth of the front
    little[40:60, 40:120] = 1
    assert not trim_flat_background(little, rgb)[front & (little == 0)].any()
    alone = np.zeros_like(labels)
    alone[40:80, 40:120] = 1  # 40% of the front and nothing else: the front is 2.5x it
    assert not trim_flat_background(alone, rgb)[front & (alone == 0)].any()


def test_a_dimmed_first_look_is_judged_on_its_own_texture():
    """Darker over a plain patch of the table as first seen, a face of the table's hue
    looks like the table in shadow: no texture tells them apart, so it is not taken for a
    shadow -- even where the static memory holds a textured look there (the body itself,
    remembered at rest under another id, its edges textured; round 50)."""
    flat = np.empty((*SIZE, 3), np.uint8)
    flat[:] = (150, 120, 90)
    cur = np.clip(flat * _shadow((100, 120), 40, 0.5, soft=2)[..., None], 0, 255)
    cur = cur.astype(np.uint8)
    textured = _texture(0)
    memory = _remembered(textured)
    gray = _gray(cur)
    memory.observe(cur, gray, np.abs(gray - _gray(textured)))
    first = FirstLook(SIZE, covered=20.0, tolerance=10.0)
    first.update(flat, np.ones(SIZE, bool), np.zeros(SIZE, np.int32))
    labels = _marks_on_shadow_and_body()
    box, shadow = cast_shadows(memory, cur, labels, first)
    core = np.zeros(SIZE, bool)
    core[105:135, 95:125] = True
    assert shadow[core[box]].mean() < 0.05
    # the same first look, textured, dimmed by the same shadow: a shadow
    first.update(textured, np.ones(SIZE, bool), np.zeros(SIZE, np.int32))
    first.look[:], first.known[:] = textured, True
    shaded = np.clip(textured * _shadow((100, 120), 40, 0.5, soft=2)[..., None], 0, 255)
    box, shadow = cast_shadows(memory, shaded.astype(np.uint8), labels, first)
    assert shadow[core[box]].mean() > 0.9
