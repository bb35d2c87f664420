"""Where the mIoU points go: each body's loss by how its mark fails (``motionbits eval`` and
``motionbits benchmark``)."""

import json
import math

import numpy as np
import pytest

from motionbits.eval.benchmark import run_benchmark
from motionbits.eval.losses import FAILURES, failure, format_losses, loss_budget
from test_eval_dataset import make_scene, squares


@pytest.mark.parametrize("iou, precision, recall, expected", [
    (0.0, 0.0, 0.0, "missed"),
    (0.5, 1.0, 0.5, "short"),    # within the body, half of it
    (0.5, 0.5, 1.0, "spill"),    # all of the body, and as much again
    (0.3, 0.5, 0.45, "both"),
    (0.85, 0.9, 0.94, "close"),
    (0.7, 0.82, 0.84, "spill"),  # both sides over the line: the larger decides
])
def test_each_mark_fails_one_way(iou, precision, recall, expected):
    assert failure(iou, precision, recall) == expected


def test_the_losses_sum_to_what_the_miou_misses_per_track():
    per_scene = {
        "t/a": {"instances": [{"IoU": 0.0, "P": 0.0, "R": 0.0},
                              {"IoU": 0.5, "P": 1.0, "R": 0.5},
                              {"IoU": 0.9, "P": 0.95, "R": 0.94}]},
        "t/b": {"instances": [{"IoU": 0.25, "P": 0.25, "R": 1.0},
                              {"IoU": float("nan"), "P": 0.0, "R": 0.0}]},  # left out
        "u/c": {"instances": [{"IoU": 0.2, "P": 0.4, "R": 0.3}]},
        "u/d": {"instances": []},
    }
    budget = loss_budget(per_scene)
    assert set(budget) == {"t", "u"}
    t = budget["t"]
    assert t["n"] == 4
    assert t["missed"] == pytest.approx(100 / 4)
    assert t["short"] == pytest.approx(50 / 4)
    assert t["spill"] == pytest.approx(75 / 4)
    assert t["both"] == 0.0
    assert t["close"] == pytest.approx(10 / 4)
    assert t["mIoU"] == pytest.approx(100 * (0.0 + 0.5 + 0.9 + 0.25) / 4)
    assert sum(t[k] for k in FAILURES) == pytest.approx(100 - t["mIoU"])
    assert budget["u"] == pytest.approx({"n": 1, "mIoU": 20.0, "missed": 0.0, "short": 0.0,
                                         "spill": 0.0, "both": 80.0, "close": 0.0})


def test_the_benchmark_splits_each_tracks_loss_and_matches_its_miou(tmp_path):
    """Real scores of real label maps: a square marked half (short), one marked with as
    much table around it (spill), one not marked (missed)."""
    shape = (48, 64)
    gt = squares(shape, (4, 4, 10), (4, 30, 10), (28, 30, 10))  # ids 1000, 2000, 3000
    make_scene(tmp_path / "data" / "robot", "a", gt)

    def marks(frames):
        out = np.zeros(shape, np.int32)
        out[4:9, 4:14] = 1        # the top half of the first square
        out[2:16, 28:42] = 2      # the second square and a ring of table around it
        return out

    results, _ = run_benchmark(tmp_path / "data", {"m": marks}, progress=False)
    budget = results["m"]["losses"]["robot"]
    assert budget["n"] == 3
    assert budget["mIoU"] == pytest.approx(100 * results["m"]["tracks"]["robot"]["macro"]["mIoU"])
    assert budget["short"] == pytest.approx(50 / 3)
    assert budget["spill"] == pytest.approx(100 * (1 - 100 / 196) / 3)
    assert budget["missed"] == pytest.approx(100 / 3)
    assert budget["both"] == budget["close"] == 0.0
    text = format_losses(results)
    row = next(line for line in text.splitlines() if line.startswith("robot"))
    assert row.split()[:3] == ["robot", "m", "3"]
    assert math.isclose(float(row.split()[3]), budget["mIoU"], abs_tol=0.05)


def test_no_bodies_no_table():
    assert loss_budget({"t/a": {"instances": []}}) == {}
    assert format_losses({"m": {"losses": {}}}) == ""


def test_motionbits_eval_prints_and_writes_where_the_points_go(tmp_path, capsys):
    from motionbits.cli import main
    from motionbits.eval import write_label_map

    shape = (48, 64)
    gt = squares(shape, (4, 4, 10), (4, 30, 10))
    make_scene(tmp_path / "gt" / "robot", "a", gt)
    pred = np.zeros(shape, np.int32)
    pred[4:9, 4:14] = 1  # half of the first square; the second missed
    write_label_map(tmp_path / "pred" / "robot" / "a.png", pred)
    assert main(["eval", "--gt", str(tmp_path / "gt"), "--pred", f"m={tmp_path / 'pred'}",
                 "--json", str(tmp_path / "out.json"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "[where the mIoU points go]" in out
    row = next(line for line in out.splitlines() if line.startswith("robot") and " m " in line)
    assert row.split()[3:6] == ["25.0", "50.0", "25.0"]  # mIoU, missed, short
    saved = json.loads((tmp_path / "out.json").read_text())["losses"]["robot"]
    assert saved["missed"] == pytest.approx(50.0) and saved["short"] == pytest.approx(25.0)


def test_motionbits_compare_shows_where_each_runs_points_go(tmp_path, capsys):
    from motionbits.cli import main
    from motionbits.eval import write_label_map

    shape = (48, 64)
    gt = squares(shape, (4, 4, 10), (4, 30, 10))
    make_scene(tmp_path / "gt" / "robot", "a", gt)
    half = np.zeros(shape, np.int32)
    half[4:9, 4:14] = 1  # run A: half of the first square
    whole = half.copy()
    whole[4:14, 4:14] = 1  # run B: all of it
    for name, pred in (("a", half), ("b", whole)):
        write_label_map(tmp_path / name / "robot" / "a.png", pred)
        assert main(["eval", "--gt", str(tmp_path / "gt"), "--pred", str(tmp_path / name),
                     "--json", str(tmp_path / f"{name}.json"), "--quiet"]) == 0
    capsys.readouterr()
    assert main(["compare", str(tmp_path / "a.json"), str(tmp_path / "b.json"),
                 "--json", str(tmp_path / "ab.json")]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()
            if line.startswith("robot") and line.split()[1] in ("A", "B")]
    assert [r[1] for r in rows] == ["A", "B"]
    assert rows[0][5] == "25.0" and rows[1][5] == "0.0"  # short: half a body, then none
    assert rows[1][4] == "50.0" and rows[1][8] == "0.0"  # B: the second square still missed
    saved = json.loads((tmp_path / "ab.json").read_text())["losses"]
    assert saved["B"]["robot"]["mIoU"] == pytest.approx(50.0)
