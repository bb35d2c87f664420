"""Grasp proposals from masks (Supplement B's controller input), on hand-built masks."""
from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from motionbits.grasp import grasp_from_mask, grasp_proposals


def test_axis_aligned_rectangle():
    mask = np.zeros((60, 80), bool)
    mask[20:30, 10:50] = True  # 40 wide (x), 10 tall (y)
    g = grasp_from_mask(mask)
    assert g.centroid == pytest.approx((29.5, 24.5))
    assert g.area == 400
    assert abs(g.major_axis[0]) == pytest.approx(1.0)
    assert g.minor_axis == pytest.approx((0.0, 1.0), abs=1e-9)  # jaws close along y
    assert g.angle == pytest.approx(math.pi / 2)
    assert g.width == pytest.approx(10.0)
    assert g.length == pytest.approx(40.0)


@pytest.mark.parametrize("deg", [-60.0, -20.0, 35.0, 80.0])
def test_rotated_rectangle_angle_and_width(deg):
    mask = np.zeros((200, 200), np.uint8)
    box = cv2.boxPoints(((100.0, 90.0), (90.0, 24.0), deg))  # major axis at `deg`
    cv2.fillPoly(mask, [np.round(box).astype(np.int32)], 1)
    g = grasp_from_mask(mask)
    assert g.centroid == pytest.approx((100.0, 90.0), abs=0.6)
    want = math.radians(deg + 90.0)  # closing direction is perpendicular to the length
    diff = math.remainder(g.angle - want, math.pi)
    assert abs(diff) < math.radians(2.0)
    assert -math.pi / 2 < g.angle <= math.pi / 2
    assert g.width == pytest.approx(24.0, abs=2.5)
    assert g.length == pytest.approx(90.0, abs=2.5)
    assert np.dot(g.major_axis, g.minor_axis) == pytest.approx(0.0, abs=1e-9)


def test_proposals_largest_first_and_min_area():
    labels = np.zeros((50, 50), np.int32)
    labels[0:5, 0:5] = 7  # 25 px
    labels[10:30, 10:20] = 3  # 200 px
    labels[40:44, 40:50] = 5  # 40 px
    got = grasp_proposals(labels)
    assert [i for i, _ in got] == [3, 5, 7]
    assert [g.area for _, g in got] == [200, 40, 25]
    assert [i for i, _ in grasp_proposals(labels, min_area=30)] == [3, 5]


def test_bad_input():
    with pytest.raises(ValueError, match="empty"):
        grasp_from_mask(np.zeros((4, 4), bool))
    with pytest.raises(ValueError, match="2-D"):
        grasp_from_mask(np.ones((2, 4, 4), bool))
    with pytest.raises(ValueError, match="integer"):
        grasp_proposals(np.ones((4, 4), np.float32))
