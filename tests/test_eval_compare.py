"""Two scored runs compared: paired per-body differences, bootstrap interval over scenes,
and the ``motionbits compare`` command."""

import json

import numpy as np
import pytest

from motionbits.cli import main
from motionbits.eval.compare import ALL_TRACKS, compare_runs, format_scene_changes, scene_changes
from motionbits.eval.metrics import evaluate_frame


def two_bodies(shape=(40, 60)):
    gt = np.zeros(shape, np.int32)
    gt[5:15, 5:15] = 1
    gt[20:35, 30:50] = 2
    return gt


def scene(pred, gt):
    return evaluate_frame(pred, gt).to_dict()


def runs(n_scenes=6, track="t", better=()):
    """Run A finds body 1 of every scene and misses body 2; run B also finds body 2 in
    the scenes ``better``."""
    gt = two_bodies()
    a, b = {}, {}
    for k in range(n_scenes):
        key = f"{track}/scene_{k:04d}"
        a[key] = scene(np.where(gt == 1, 7, 0), gt)
        b[key] = scene(gt * 7 if k in better else np.where(gt == 1, 7, 0), gt)
    return a, b


def test_identical_runs_change_nothing():
    a, _ = runs()
    r = compare_runs(a, a)["t"]
    assert r["delta"] == 0 and r["ci"] == (0.0, 0.0) and r["up"] == r["down"] == 0
    assert r["mIoU_a"] == pytest.approx(0.5) and r["scenes"] == 6 and r["instances"] == 12


def test_a_gain_on_every_scene_is_outside_chance():
    a, b = runs(better=range(6))
    r = compare_runs(a, b)["t"]
    assert r["delta"] == pytest.approx(0.5) and r["mIoU_b"] == pytest.approx(1.0)
    assert r["ci"][0] > 0 and r["up"] == 6 and r["down"] == 0


def test_a_gain_on_one_scene_of_six_is_not():
    a, b = runs(better=[3])
    r = compare_runs(a, b)["t"]
    assert r["delta"] == pytest.approx(0.5 / 6)
    low, high = r["ci"]
    assert low <= 0 < r["delta"] < high and r["up"] == 1  # resamples without scene 3


def test_the_interval_widens_with_the_level():
    a, b = runs(n_scenes=12, better=[0, 1, 2, 5, 8])
    narrow = compare_runs(a, b, level=0.5)["t"]["ci"]
    wide = compare_runs(a, b, level=0.99)["t"]["ci"]
    assert wide[0] < narrow[0] and narrow[1] < wide[1]


def test_several_tracks_get_a_row_of_all_scenes():
    a1, b1 = runs(track="x", better=range(6))
    a2, b2 = runs(track="y")
    r = compare_runs({**a1, **a2}, {**b1, **b2})
    assert set(r) == {"x", "y", ALL_TRACKS}
    assert r[ALL_TRACKS]["scenes"] == 12 and r[ALL_TRACKS]["delta"] == pytest.approx(0.25)
    assert r["y"]["delta"] == 0


def test_runs_on_other_scenes_or_bodies_are_refused():
    a, b = runs()
    b.pop(next(iter(b)))
    with pytest.raises(ValueError, match="same scenes"):
        compare_runs(a, b)
    a, b = runs()
    gt = two_bodies()
    key = next(iter(b))
    b[key] = scene(np.where(gt == 1, 7, 0), np.where(gt == 1, 1, 0))
    with pytest.raises(ValueError, match="different GT bodies"):
        compare_runs(a, b)
    with pytest.raises(ValueError, match="level"):
        compare_runs(a, a, level=1.0)


def test_compare_command_reads_benchmark_and_eval_files(tmp_path, capsys):
    a, b = runs(better=range(6))
    fa, fb, fe = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "e.json"
    fa.write_text(json.dumps({"methods": {"motionbits": {"per_scene": a}},
                              "seconds_per_frame": {"motionbits": 0.1}}))
    fb.write_text(json.dumps({"methods": {"motionbits": {"per_scene": b},
                                          "flow-cc": {"per_scene": a}}}))
    fe.write_text(json.dumps({"per_scene": b}))  # eval --json of one folder
    out = tmp_path / "cmp.json"
    assert main(["compare", str(fa), str(fb), "--method", "motionbits", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "+50.0" in text and "95% CI" in text
    saved = json.loads(out.read_text())
    assert saved["tracks"]["t"]["delta"] == pytest.approx(0.5)
    assert main(["compare", str(fa), str(fe), "--method", "motionbits"]) == 0  # moot for e
    assert "+50.0" in capsys.readouterr().out
    # several methods and none chosen; a file that is not a scored run
    assert main(["compare", str(fa), str(fb)]) == 2
    assert "--method" in capsys.readouterr().err
    (tmp_path / "bad.json").write_text("[1, 2]")
    assert main(["compare", str(fa), str(tmp_path / "bad.json")]) == 2
    assert "not a --json file" in capsys.readouterr().err


def test_scene_changes_put_the_scene_that_moved_first_with_its_body():
    a, b = runs(better=[3])
    rows = scene_changes(a, b)
    others = [f"t/scene_{k:04d}" for k in (0, 1, 2, 4, 5)]  # unchanged: in key order
    assert [r["scene"] for r in rows] == ["t/scene_0003", *others]
    top = rows[0]
    assert top["delta"] == pytest.approx(0.5) and top["mIoU_b"] == pytest.approx(1.0)
    one = pytest.approx(1.0)
    assert top["bodies"] == [(1, one, one), (2, 0.0, one)]
    assert all(r["delta"] == 0 for r in rows[1:])
    text = format_scene_changes(rows[:2]).splitlines()
    assert "t/scene_0003" in text[2] and "2: 0.00 -> 1.00" in text[2] and "1: " not in text[2]
    assert text[3].endswith("  -")  # a scene that did not move names no body


def test_compare_command_lists_the_scenes_that_moved(tmp_path, capsys):
    a, b = runs(better=[2, 4])
    fa, fb, out = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "cmp.json"
    fa.write_text(json.dumps({"per_scene": a}))
    fb.write_text(json.dumps({"per_scene": b}))
    assert main(["compare", str(fa), str(fb), "--scenes", "2", "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert "the 2 scenes that changed most" in text
    assert "t/scene_0002" in text and "t/scene_0004" in text and "t/scene_0000" not in text
    saved = json.loads(out.read_text())["scenes"]
    assert [r["scene"] for r in saved] == ["t/scene_0002", "t/scene_0004"]
    assert main(["compare", str(fa), str(fb), "--scenes", "-1"]) == 2
    assert "--scenes" in capsys.readouterr().err
