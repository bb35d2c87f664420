"""Mean IoU per kind of body (``meta.json`` labels) in ``motionbits benchmark``."""

import json

import numpy as np

from motionbits.eval import write_label_map
from motionbits.eval.benchmark import run_benchmark
from motionbits.eval.dataset import evaluate_dataset
from motionbits.eval.kinds import (body_kinds, body_kinds_and_roles, body_roles, format_breakdowns,
                                  format_kinds, iou_by_kind)
from test_eval_dataset import make_scene, squares


def test_body_kinds_reads_meta_and_tolerates_free_form(tmp_path):
    (tmp_path / "meta.json").write_text(json.dumps(
        {"labels": {"1": {"kind": "laptop"}, "2": {"pixels": 5}, "3": {"kind": "hand"}}}))
    assert body_kinds(tmp_path) == {1: "laptop", 3: "hand"}
    for text in ("{}", "[1, 2]", "not json", '{"labels": 3}'):
        (tmp_path / "meta.json").write_text(text)
        assert body_kinds(tmp_path) == {}
    assert body_kinds(tmp_path / "missing") == {}


def test_benchmark_scores_each_kind_of_body(tmp_path):
    shape = (40, 48)
    gt_a = squares(shape, (5, 5, 10), (20, 25, 10))  # ids 1000 (block), 2000 (hand)
    gt_b = squares(shape, (8, 8, 12))  # id 1000 (block)
    for track, name, gt, kinds in (("robot", "a", gt_a, {"1000": "block", "2000": "hand"}),
                                   ("robot", "b", gt_b, {"1000": "block"})):
        scene = make_scene(tmp_path / "data" / track, name, gt)
        (scene / "meta.json").write_text(json.dumps(
            {"labels": {k: {"kind": v} for k, v in kinds.items()}}))

    def half_of_the_first(frames):
        """The top half of the first square of each scene (IoU 0.5), nothing else (the
        scenes come in name order: a, then b)."""
        out = np.zeros(frames[0].shape[:2], np.int32)
        gt = (gt_a, gt_b)[len(seen)]
        seen.append(1)
        ys, xs = np.nonzero(gt == 1000)
        out[ys.min():ys.min() + (ys.max() - ys.min() + 1) // 2, xs.min():xs.max() + 1] = 1
        return out

    seen: list[int] = []
    results, _ = run_benchmark(tmp_path / "data", {"half": half_of_the_first}, progress=False)
    by_kind = results["half"]["by_kind"]
    assert by_kind["robot"]["block"]["n"] == 2
    assert abs(by_kind["robot"]["block"]["mIoU"] - 0.5) < 1e-6
    assert by_kind["robot"]["block"]["missed"] == 0.0
    assert by_kind["robot"]["hand"] == {"n": 1, "mIoU": 0.0, "missed": 1.0}
    text = format_kinds(results)
    assert "block" in text and "50.0 (0%)" in text and "0.0 (100%)" in text
    assert results["half"]["by_role"] == {}  # no script, no push: roles unknown
    assert format_kinds(results, "by_role") == ""


def test_no_kinds_no_table():
    assert iou_by_kind({"t/s": {"instances": [{"gt": 1, "IoU": 0.7}]}}, {"t/s": {}}) == {}
    assert format_kinds({"m": {"by_kind": {}}}) == ""


def test_eval_of_saved_predictions_scores_each_kind(tmp_path):
    gt = squares((40, 48), (5, 5, 10), (20, 25, 10))  # ids 1000 (lid), 2000 (hand)
    scene = make_scene(tmp_path / "gt" / "hand", "a", gt)
    (scene / "meta.json").write_text(json.dumps(
        {"labels": {"1000": {"kind": "laptop"}, "2000": {"kind": "hand"}}}))
    write_label_map(tmp_path / "pred" / "hand" / "a.png", np.where(gt == 2000, 5, 0))
    by_kind = evaluate_dataset(tmp_path / "gt", tmp_path / "pred", progress=False)["by_kind"]
    assert by_kind == {"hand": {"hand": {"n": 1, "mIoU": 1.0, "missed": 0.0},
                                "laptop": {"n": 1, "mIoU": 0.0, "missed": 1.0}}}


def test_body_roles_from_the_script(tmp_path):
    meta = {"labels": {"1": {"body": "obj5"}, "2": {"body": "obj7"}, "3": {"body": "obj9"},
                       "4": {"body": "obj11"}, "5": {"kind": "block"},
                       "6": {"body": "pusher", "kind": "gripper"}},
            "push": {"target": "obj7"},
            "script": {"carries": [{"agent": "agent0", "body": "obj7"}],
                       "kicks": [{"body": "obj9", "t": 1.5}, "junk"]}}
    (tmp_path / "meta.json").write_text(json.dumps(meta))
    # the carried push target is carried; label 5 names no body
    assert body_roles(tmp_path) == {1: "other", 2: "carried", 3: "knocked", 4: "other",
                                    6: "agent"}
    meta["script"] = {}
    (tmp_path / "meta.json").write_text(json.dumps(meta))
    assert body_roles(tmp_path) == {1: "other", 2: "pushed", 3: "other", 4: "other",
                                    6: "agent"}
    for text in ('{"labels": {"1": {"body": "a"}}}', "not json", '{"push": 3, "labels": []}'):
        (tmp_path / "meta.json").write_text(text)
        assert body_roles(tmp_path) == {}


def test_benchmark_scores_each_role_and_the_bodies_missed(tmp_path):
    gt = squares((40, 48), (5, 5, 10), (20, 25, 10))  # ids 1000 (carried), 2000 (knocked)
    scene = make_scene(tmp_path / "data" / "pickplace", "a", gt)
    (scene / "meta.json").write_text(json.dumps(
        {"labels": {"1000": {"body": "obj5", "kind": "block"},
                    "2000": {"body": "obj7", "kind": "block"}},
         "script": {"carries": [{"body": "obj5"}], "kicks": [{"body": "obj7"}]}}))
    results, _ = run_benchmark(tmp_path / "data",
                               {"first": lambda frames: np.where(gt == 1000, 3, 0)},
                               progress=False)
    by_role = results["first"]["by_role"]["pickplace"]
    assert by_role == {"carried": {"n": 1, "mIoU": 1.0, "missed": 0.0},
                       "knocked": {"n": 1, "mIoU": 0.0, "missed": 1.0}}
    assert results["first"]["by_kind"]["pickplace"]["block"]["missed"] == 0.5
    text = format_kinds(results, "by_role")
    assert "role" in text and "100.0 (0%)" in text and "0.0 (100%)" in text
    both = format_breakdowns(results)
    assert both == format_kinds(results) + "\n" + text
    assert body_kinds_and_roles(scene) == (body_kinds(scene), body_roles(scene))
