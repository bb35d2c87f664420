"""One object in one frame, shared by ``motionbits``, ``somprompt`` and ``vlm_adapters``.

:class:`Instance` is what every package returns for an object: a MotionBit of the
segmenter, a mark of a set-of-mark picture, a detection of the VLM -> YOLOE path. It
converts to and from what the field already uses: label maps (0 = background, k > 0 =
object k), COCO run-length encoding (``pycocotools``, extra ``coco``) and supervision's
``sv.Detections`` (extra ``supervision``).

This module imports only numpy (the extras are imported when their functions are called),
so ``somprompt`` and ``vlm_adapters`` can use it without loading the segmenter.

Example:
    >>> import numpy as np
    >>> labels = np.zeros((4, 6), np.int32); labels[1:3, 2:5] = 7
    >>> [obj] = instances_from_labels(labels)
    >>> obj.id, obj.bbox, obj.area, obj.centroid
    (7, (2, 1, 5, 3), 6, (3.0, 1.5))
    >>> bool((labels_from_instances([obj], labels.shape) == labels).all())
    True
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, field, replace
from typing import Any, Iterable, Sequence

import numpy as np

from motionbits.frames import whole_number

__all__ = [
    "Instance",
    "MissingDependencyError",
    "require",
    "require_attr",
    "check_label_map",
    "instance_from_mask",
    "instances_from_labels",
    "labels_from_instances",
    "encode_rle",
    "decode_rle",
    "to_supervision",
    "from_supervision",
]


class MissingDependencyError(ImportError):
    """An optional dependency is not installed; the message names the extra to install."""


def require(module: str, extra: str, purpose: str = "") -> Any:
    """Import ``module`` or raise :class:`MissingDependencyError` that names the extra.

    Args:
        module: dotted module name, e.g. ``"pycocotools.mask"``.
        extra: the ``motionbits`` extra that provides it, e.g. ``"coco"``.
        purpose: what needs it, for the message (e.g. ``"Qwen2_5_VLAdapter"``).
    """
    try:
        return importlib.import_module(module)
    except (ImportError, RuntimeError, OSError) as exc:  # e.g. torchvision ops built for another torch
        who = f"{purpose} needs" if purpose else "This needs"
        raise MissingDependencyError(
            f"{who} the optional dependency '{module.split('.')[0]}', which is not installed "
            f"or failed to import ({exc}). Install it with: pip install \"motionbits[{extra}]\""
        ) from exc


def require_attr(module: Any, name: str, extra: str, purpose: str = "") -> Any:
    """``getattr(module, name)`` for a lazily importing package (transformers), with clear errors.

    transformers imports a class's module on first access; when that import fails (e.g.
    torchvision's compiled ops do not load against the installed torch) it raises
    ``ModuleNotFoundError: Could not import module '<name>'`` and keeps the real cause in
    ``__cause__``. This turns both that and a class the installed version lacks into
    :class:`MissingDependencyError` naming the underlying cause and the extra to install.
    """
    who = purpose or "This"
    package = module.__name__.split(".")[0]
    try:
        return getattr(module, name)
    except AttributeError:
        version = getattr(module, "__version__", "?")
        raise MissingDependencyError(
            f"{who} needs {package}.{name}, which {package} {version} does not have. "
            f"Upgrade: pip install -U \"motionbits[{extra}]\""
        ) from None
    except (ImportError, RuntimeError, OSError) as exc:
        cause = exc.__cause__ or exc
        raise MissingDependencyError(
            f"{who} could not import {package}.{name}: {type(cause).__name__}: {cause}. "
            f"Repair the install (torch and torchvision must be matching builds): "
            f"pip install \"motionbits[{extra}]\""
        ) from exc


@dataclass(frozen=True)
class Instance:
    """One object in one frame (pixel coordinates of that frame).

    Attributes:
        id: object id (> 0): the label in a label map, stable across frames where the
            producer tracks objects (MotionBits, marks).
        bbox: ``(x0, y0, x1, y1)``, x1/y1 exclusive (width = x1 - x0).
        area: pixels in the mask (the box area for a box-only detection).
        centroid: ``(x, y)`` mean of the mask pixels (the box centre without a mask).
        mask: (H, W) bool mask, or None (see :meth:`get_mask`).
        rle: COCO RLE ``{"size": [H, W], "counts": str}``, or None.
        score: detector confidence, or None.
        name: class or phrase (e.g. the YOLOE text prompt), or None.
        twist: MotionBits only: ``(omega rad/frame, v_x, v_y px/frame)`` spatial twist of
            the motion from the previous frame about the image origin.
        moving: MotionBits only: whether it moved between the previous frame and this one.
        first_moved, last_moved: MotionBits only: frame indices of its first and latest
            motion.

    ``mask`` and ``rle`` are left out of ``==`` and ``repr``.
    """

    id: int
    bbox: tuple[int, int, int, int]
    area: int
    centroid: tuple[float, float]
    mask: np.ndarray | None = field(default=None, compare=False, repr=False)
    rle: dict | None = field(default=None, compare=False, repr=False)
    score: float | None = None
    name: str | None = None
    twist: tuple[float, float, float] | None = None
    moving: bool | None = None
    first_moved: int | None = None
    last_moved: int | None = None

    def get_mask(self) -> np.ndarray:
        """(H, W) bool mask, from ``mask`` or decoded from ``rle``.

        Raises:
            ValueError: the instance holds neither (e.g. a MotionBit straight from
                ``MotionBitsSegmenter.update``: use ``result.instances()``).
        """
        if self.mask is not None:
            return self.mask
        if self.rle is not None:
            return decode_rle(self.rle)
        raise ValueError(
            f"instance {self.id} holds no mask and no RLE; build it with masks "
            "(instances_from_labels(labels) or MotionBitsResult.instances())"
        )

    def with_rle(self) -> "Instance":
        """This instance with its mask encoded as COCO RLE (and ``mask`` dropped)."""
        return replace(self, rle=encode_rle(self.get_mask()), mask=None)


def check_mask(mask: Any, *, ndim: int = 2, name: str = "mask") -> np.ndarray:
    """``mask`` as a bool array of ``ndim`` dimensions ((H, W), or (K, H, W) for 3): bool, or
    numbers where non-zero is the object.

    Raises:
        TypeError: not numbers (None, str, object arrays: "int() argument must be ...").
        ValueError: another number of dimensions, or NaN / infinity (NaN is non-zero and
            was read as "object" everywhere; cast to uint8 it was background).
    """
    try:
        m = np.asarray(mask)
    except ValueError:  # ragged nested lists
        raise ValueError(f"{name} must be a rectangular array, got ragged {type(mask).__name__}") from None
    if m.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be a bool or numeric array (non-zero = object), got "
                        f"{type(mask).__name__}" + (f" of {m.dtype}" if isinstance(mask, np.ndarray) else ""))
    if m.ndim != ndim:
        raise ValueError(f"{name} must be {'(K, H, W)' if ndim == 3 else '(H, W)'} (a {ndim}-D array), "
                         f"got shape {m.shape}")
    if m.dtype.kind == "f" and not np.isfinite(m).all():
        raise ValueError(f"{name} holds NaN or infinite values; a mask is bool, or 0 (background) "
                         "and non-zero (object)")
    return m if m.dtype == np.bool_ else m != 0


def check_label_map(
    labels: np.ndarray,
    shape: tuple[int, int] | None = None,
    *,
    name: str = "labels",
) -> np.ndarray:
    """Validate an (H, W) label map and return it as an int64 array.

    A label map holds 0 for background and k > 0 for object k. Boolean maps are
    accepted as a single object with id 1; an (H, W, 1) map is squeezed.

    Args:
        labels: (H, W) array of non-negative integers (any integer dtype) or bool.
        shape: (H, W) that the map must have (the frame it belongs to), or None.
        name: what to call the argument in error messages.

    Returns:
        (H, W) int64 array (the input itself when it already is one).

    Raises:
        TypeError: not a numpy array, or not an integer/bool dtype.
        ValueError: not 2-D, negative ids, ids beyond int64 (uint64 maps), or a size that
            differs from ``shape``.
    """
    if not isinstance(labels, np.ndarray):
        raise TypeError(
            f"{name} must be an (H, W) numpy integer array (0 = background, k > 0 = object k), "
            f"got {type(labels).__name__}"
        )
    if labels.dtype == np.bool_:
        labels = labels.astype(np.int64)
    elif not np.issubdtype(labels.dtype, np.integer):
        raise TypeError(
            f"{name} must have an integer dtype (0 = background, k > 0 = object k), got "
            f"{labels.dtype}; if it holds whole numbers, use labels.astype(np.int32)"
        )
    if labels.ndim == 3 and labels.shape[2] == 1:
        labels = labels[..., 0]
    if labels.ndim != 2:
        raise ValueError(f"{name} must be an (H, W) label map, got shape {labels.shape}")
    if labels.size and labels.min() < 0:
        raise ValueError(f"{name} holds negative ids (min {labels.min()}); ids must be >= 0")
    if labels.size and labels.dtype == np.uint64 and labels.max() > np.iinfo(np.int64).max:
        # would wrap to negative ids in int64
        raise ValueError(f"{name} holds ids too large for int64 (max {labels.max()}); "
                         f"ids must be <= {np.iinfo(np.int64).max}")
    if shape is not None and tuple(labels.shape) != tuple(shape[:2]):
        raise ValueError(
            f"{name} has size {labels.shape[1]}x{labels.shape[0]} (W x H) but the frame is "
            f"{shape[1]}x{shape[0]}; resize the label map with nearest-neighbour "
            "interpolation (cv2.INTER_NEAREST) to the frame size"
        )
    return labels if labels.dtype == np.int64 else labels.astype(np.int64)


def instance_from_mask(mask: np.ndarray, id: int, *, rle: bool = False, **fields: Any) -> Instance:
    """:class:`Instance` of one (H, W) bool mask: box, area and centroid measured on it.

    Args:
        mask: (H, W) bool, or numbers where non-zero is the object (NaN is an error; an
            empty mask gives box (0, 0, 0, 0), area 0, centroid NaN).
        id: the object's id.
        rle: store the mask as COCO RLE instead of the array (extra ``coco``).
        **fields: other :class:`Instance` fields (``score``, ``name``, ``twist``, ...).
    """
    m = check_mask(mask)  # a NaN mask was read as all True, None as one False pixel
    id = _object_id(id, "id")
    ys, xs = np.nonzero(m)
    if xs.size:
        bbox = (int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1)
        centroid = (float(xs.mean()), float(ys.mean()))
    else:
        bbox, centroid = (0, 0, 0, 0), (float("nan"), float("nan"))
    return Instance(id=id, bbox=bbox, area=int(xs.size), centroid=centroid,
                    mask=None if rle else m, rle=encode_rle(m) if rle else None, **fields)


def instances_from_labels(labels: np.ndarray, *, rle: bool = False) -> list[Instance]:
    """One :class:`Instance` (with its mask, or its COCO RLE when ``rle``) per id > 0 of an
    (H, W) integer label map, ids ascending."""
    lm = check_label_map(labels)
    return [instance_from_mask(lm == i, int(i), rle=rle) for i in np.unique(lm) if i > 0]


def _object_id(value: Any, name: str) -> int:
    """An object id as an int: a whole number >= 1 (0 is the background)."""
    value = whole_number(name, value)  # 2.7 was id 2, True id 1
    if value < 1:
        raise ValueError(f"{name} must be >= 1 (0 is the background), got {value}")
    return value


def labels_from_instances(objects: Iterable[Instance], shape: tuple[int, int]) -> np.ndarray:
    """(H, W) int32 label map of ``objects`` (later objects drawn over earlier ones).

    Raises:
        TypeError / ValueError: ``shape`` is not (H, W) whole numbers >= 0, an object is not
            an :class:`Instance`, or its id is not a whole number in 1 .. 2**31 - 1 (int32).
    """
    if isinstance(shape, (str, bytes)) or not hasattr(shape, "__len__") or len(shape) < 2:
        raise TypeError(f"shape must be (H, W), got {shape!r:.40}")
    h, w = (whole_number(f"shape[{i}]", v) for i, v in enumerate(shape[:2]))
    if h < 0 or w < 0:
        raise ValueError(f"shape must be (H, W) >= 0, got {tuple(shape)!r}")
    if objects is None or isinstance(objects, (str, bytes, Instance)):
        raise TypeError(f"objects must be a list of Instance, got {type(objects).__name__}")
    out = np.zeros((h, w), np.int32)
    for k, obj in enumerate(objects):
        if not isinstance(obj, Instance):
            raise TypeError(f"objects[{k}] is {type(obj).__name__}, not an Instance "
                            "(instance_from_mask(mask, id) makes one of a mask)")
        oid = _object_id(obj.id, f"objects[{k}].id")
        if oid > np.iinfo(np.int32).max:  # else numpy's OverflowError
            raise ValueError(f"objects[{k}].id {oid} does not fit the int32 label map "
                             f"(at most {np.iinfo(np.int32).max})")
        m = obj.get_mask()
        if m.shape != out.shape:
            raise ValueError(f"instance {obj.id} has a {m.shape} mask; the label map is {out.shape}")
        out[m] = oid
    return out


def encode_rle(mask: np.ndarray) -> dict:
    """COCO RLE of an (H, W) bool mask: ``{"size": [H, W], "counts": str}`` (JSON-ready)."""
    mask_util = require("pycocotools.mask", "coco")
    m = np.asarray(mask)
    if m.ndim != 2:
        raise ValueError(f"mask must be (H, W), got shape {m.shape}")
    rle = mask_util.encode(np.asfortranarray(m.astype(np.uint8)))
    return {"size": [int(s) for s in rle["size"]], "counts": rle["counts"].decode("ascii")}


def decode_rle(rle: dict) -> np.ndarray:
    """(H, W) bool mask of a COCO RLE (compressed ``counts`` as str or bytes)."""
    mask_util = require("pycocotools.mask", "coco")
    if not isinstance(rle, dict) or "size" not in rle or "counts" not in rle:
        raise ValueError("rle must be a dict with 'size' [H, W] and 'counts' (COCO run-length encoding)")
    size = rle["size"]
    if (isinstance(size, (str, bytes)) or not hasattr(size, "__len__") or len(size) != 2
            or any(isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0 for v in size)):
        # else pycocotools' OverflowError "can't convert negative value to siz"
        raise ValueError(f"rle['size'] must be [H, W], two whole numbers >= 0, got {size!r:.40}")
    counts = rle["counts"]
    if not isinstance(counts, (str, bytes, list)):
        raise TypeError(f"rle['counts'] must be a str, bytes or a list of run lengths, got "
                        f"{type(counts).__name__}")
    if isinstance(counts, list):  # uncompressed RLE
        coded = mask_util.frPyObjects(rle, *rle["size"])
    else:
        coded = {"size": list(rle["size"]), "counts": counts.encode("ascii") if isinstance(counts, str) else counts}
    return mask_util.decode(coded).astype(bool)


def to_supervision(objects: Sequence[Instance]) -> Any:
    """``sv.Detections`` of ``objects`` (extra ``supervision``).

    ``id`` -> ``tracker_id``; ``bbox`` -> ``xyxy``; masks -> ``mask`` (when every object
    has one); ``score`` -> ``confidence`` and ``name`` -> ``data["class_name"]`` (when
    every object has one); MotionBits' ``twist`` -> ``data["twist"]`` (N, 3). There is
    no ``class_id``: colour supervision's annotators by id with
    ``color_lookup=sv.ColorLookup.TRACK``.
    """
    sv = require("supervision", "supervision")
    objects = list(objects)
    if not objects:
        return sv.Detections.empty()

    def has(attr: str) -> bool:
        return all(getattr(o, attr) is not None for o in objects)

    data: dict[str, np.ndarray] = {}
    if has("name"):
        data["class_name"] = np.array([o.name for o in objects])
    if has("twist"):
        data["twist"] = np.array([o.twist for o in objects], np.float64)
    masks = None
    if all(o.mask is not None or o.rle is not None for o in objects):
        masks = np.stack([o.get_mask() for o in objects])
    return sv.Detections(
        xyxy=np.array([o.bbox for o in objects], np.float32),
        mask=masks,
        confidence=np.array([o.score for o in objects], np.float32) if has("score") else None,
        tracker_id=np.array([o.id for o in objects], int),
        data=data,
    )


def from_supervision(detections: Any) -> list[Instance]:
    """:class:`Instance` list of an ``sv.Detections``: ids from ``tracker_id`` (else
    1..N); box, area and centroid measured on the masks when present, else from ``xyxy``
    (rounded outwards; area = box area); ``confidence``, ``data["class_name"]`` and
    ``data["twist"]`` when present."""
    n = len(detections)
    ids = detections.tracker_id if detections.tracker_id is not None else np.arange(1, n + 1)
    names = (detections.data or {}).get("class_name")
    twists = (detections.data or {}).get("twist")
    out = []
    for i in range(n):
        fields = {
            "score": None if detections.confidence is None else float(detections.confidence[i]),
            "name": None if names is None else str(names[i]),
            "twist": None if twists is None else tuple(float(v) for v in twists[i]),
        }
        if detections.mask is not None:
            out.append(instance_from_mask(detections.mask[i], int(ids[i]), **fields))
            continue
        x0, y0, x1, y1 = (float(v) for v in detections.xyxy[i])
        box = (int(np.floor(x0)), int(np.floor(y0)), int(np.ceil(x1)), int(np.ceil(y1)))
        out.append(Instance(id=int(ids[i]), bbox=box, area=(box[2] - box[0]) * (box[3] - box[1]),
                            centroid=((x0 + x1) / 2, (y0 + y1) / 2), **fields))
    return out
