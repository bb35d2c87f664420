"""The reverse path: VLM text -> noun phrases -> open-vocabulary detector -> label map.

The paper (section 6.1) turns the VLM baselines' answers into masks with YOLOE-L, a
promptable open-vocabulary segmenter: the object names become YOLOE's text classes and
its instance masks on the final frame become the prediction. Pieces:

* `Detections`: (K, H, W) masks, scores and the phrase of each instance.
* `PhraseDetector`: the protocol a detector follows, ``detect(image, phrases) -> Detections``.
* `YOLOEDetector`: ultralytics YOLOE behind that protocol. Weights come from a local file;
  text embeddings come from a local MobileCLIP text encoder file, or are given up front
  with `set_classes(names, embeddings)`.
* `masks_to_label_map`: instance masks -> (H, W) int32 labels (0 = background, 1..K).
* `TextGrounder`: answer text + image -> label map, with any `PhraseDetector`;
  `YOLOEGrounder` is a `TextGrounder` over a `YOLOEDetector`.

torch and ultralytics are imported only when a YOLOE model is built.
"""
from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from motionbits.frames import as_rgb_array, fraction, whole_number
from motionbits.objects import Instance, check_mask, instance_from_mask

from .base import Frame, MissingDependencyError, require
from .phrases import phrases_from_answer

__all__ = [
    "Detections",
    "PhraseDetector",
    "YOLOEDetector",
    "TextGrounder",
    "YOLOEGrounder",
    "masks_to_label_map",
]


@dataclass
class Detections:
    """Instances found in one image.

    Attributes:
        masks: (K, H, W) bool, one mask per instance, at the image's size (numbers are
            read as non-zero = object; NaN is an error).
        scores: (K,) float32 confidences in [0, 1].
        phrases: K strings, the text prompt each instance was found for, or [] for none.
    """

    masks: np.ndarray
    scores: np.ndarray
    phrases: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.masks = check_mask(self.masks, ndim=3, name="masks")  # NaN was read as True
        self.scores = _scores(self.scores).astype(np.float32).reshape(-1)
        if len(self.scores) != len(self.masks):
            raise ValueError(f"{len(self.masks)} masks but {len(self.scores)} scores")
        if self.scores.size and not (np.all(self.scores >= 0) and np.all(self.scores <= 1)):  # NaN: arbitrary order
            raise ValueError(f"scores must be confidences in [0, 1] (finite), got {self.scores[:8]}")
        # a str was one phrase per letter; None (or None in the list) failed in len() or became a name
        self.phrases = phrase_list(self.phrases, "phrases")
        if self.phrases and len(self.phrases) != len(self.masks):
            raise ValueError(f"{len(self.masks)} masks but {len(self.phrases)} phrases")

    def __len__(self) -> int:
        return len(self.masks)

    @classmethod
    def empty(cls, height: int, width: int) -> Detections:
        return cls(np.zeros((0, height, width), bool), np.zeros((0,), np.float32), [])

    def instances(self) -> list[Instance]:
        """The detections as :class:`motionbits.Instance`: ids 1..K in this order, with
        mask, score and phrase (``name``); ``motionbits.to_supervision`` takes them."""
        return [
            instance_from_mask(m, k + 1, score=float(s), name=self.phrases[k] if self.phrases else None)
            for k, (m, s) in enumerate(zip(self.masks, self.scores))
        ]


def phrase_list(value: Any, name: str = "phrases") -> list[str]:
    """``value`` as a list of str; TypeError for a bare str (read one phrase per letter),
    None, or items that are not str (None became the phrase "None")."""
    if isinstance(value, (str, bytes, dict)) or not isinstance(value, Iterable):
        raise TypeError(f"{name} must be a list of str, got {type(value).__name__} {value!r:.60}"
                        + (f" (for one phrase pass [{value!r:.40}])" if isinstance(value, str) else ""))
    out = list(value)
    bad = next((p for p in out if not isinstance(p, str)), out)
    if bad is not out:
        raise TypeError(f"{name} must be a list of str, got an item {type(bad).__name__} {bad!r:.40}")
    return out


def _scores(scores: Any, name: str = "scores") -> np.ndarray:
    """``scores`` as a float64 array; TypeError for anything but numbers (else numpy's
    "could not convert string to float", or None's "must be finite")."""
    a = np.asarray(scores)
    if a.dtype.kind not in "biuf":
        raise TypeError(f"{name} must be numbers (one per mask), got {type(scores).__name__} {scores!r:.60}")
    return a.astype(np.float64)


def _check_counts(min_area: Any, max_instances: Any) -> None:
    """``min_area`` a whole number >= 0, ``max_instances`` one >= 1 or None (else 2.5 read as 2,
    NaN kept every instance, -1 gave an empty map)."""
    if whole_number("min_area", min_area) < 0:
        raise ValueError(f"min_area must be >= 0 pixels, got {min_area!r}")
    if max_instances is not None and whole_number("max_instances", max_instances) < 1:
        raise ValueError(f"max_instances must be >= 1 or None, got {max_instances!r}")


@runtime_checkable
class PhraseDetector(Protocol):
    """Anything that finds instances of text phrases in an image."""

    def detect(self, image: np.ndarray, phrases: Sequence[str]) -> Detections:
        """Instances of `phrases` in `image` ((H, W, 3) uint8 RGB); masks at (H, W)."""
        ...


def masks_to_label_map(
    masks: np.ndarray,
    scores: np.ndarray | None = None,
    *,
    min_area: int = 1,
    max_instances: int | None = None,
) -> np.ndarray:
    """Instance masks -> one label map.

    Masks are painted from the highest score down; a pixel keeps the first (highest-scoring)
    instance that claims it. An instance left with fewer than `min_area` pixels of its own is
    dropped. Labels are 1..K in descending-score order, with no gaps.

    Args:
        masks: (K, H, W) bool (numbers: non-zero = object; NaN is an error).
        scores: (K,) finite numbers, higher first; None paints in the given order.
        min_area: minimum visible pixels for an instance to keep a label.
        max_instances: keep at most this many labels (the highest-scoring ones).

    Returns:
        (H, W) int32 label map, 0 = background.
    """
    masks = check_mask(masks, ndim=3, name="masks")  # a NaN mask was read as all True
    k, h, w = masks.shape
    if scores is not None:
        scores = _scores(scores)
    if scores is not None and scores.shape != (k,):
        raise ValueError(f"{k} masks but scores of shape {scores.shape}; give one score per mask")
    if scores is not None and not np.all(np.isfinite(scores)):  # NaN: arbitrary order
        raise ValueError(f"scores must be finite, got {scores[:8]}")
    _check_counts(min_area, max_instances)
    labels = np.zeros((h, w), np.int32)
    order = np.arange(k) if scores is None else np.argsort(-scores, kind="stable")
    next_label = 1
    for i in order:
        if max_instances is not None and next_label > max_instances:
            break
        own = masks[i] & (labels == 0)
        if int(own.sum()) < max(min_area, 1):
            continue
        labels[own] = next_label
        next_label += 1
    return labels


# --------------------------------------------------------------------------- YOLOE


def _default_device() -> str:
    torch = require("torch", "yoloe", "YOLOEDetector")
    return "cuda:0" if torch.cuda.is_available() else "cpu"


class YOLOEDetector:
    """ultralytics YOLOE (segmentation) prompted with text classes.

    Args:
        model: an ``ultralytics.YOLOE`` segmentation model (``YOLOE("yoloe-11l-seg.pt")``).
        text_encoder: how to embed phrases not given with `set_classes`: a path to the
            TorchScript MobileCLIP text encoder YOLOE was trained with (``mobileclip_blt.ts``
            for YOLOE-11/v8), or a callable ``list[str] -> (N, D)`` raw text features.
            None: only phrases registered with `set_classes` can be detected.
        conf: minimum confidence of a detection.
        iou: NMS IoU threshold.
        imgsz: inference size (longer side), as in ultralytics.
        max_det: at most this many detections per image.
        device: ``"cpu"``, ``"cuda:0"``, ...; default CUDA when available.
    """

    def __init__(
        self,
        model: Any,
        *,
        text_encoder: str | os.PathLike | Callable[[list[str]], Any] | None = None,
        conf: float = 0.25,
        iou: float = 0.7,
        imgsz: int = 640,
        max_det: int = 100,
        device: str | None = None,
    ) -> None:
        fraction("conf", conf)  # else NaN, 5 or -1 reached ultralytics' predict on the first image
        fraction("iou", iou)
        if whole_number("imgsz", imgsz) < 1:
            raise ValueError(f"imgsz must be >= 1 pixel, got {imgsz!r}")
        if whole_number("max_det", max_det) < 1:
            raise ValueError(f"max_det must be >= 1, got {max_det!r}")
        self.model = model
        self.conf = float(conf)
        self.iou = float(iou)
        self.imgsz = int(imgsz)
        self.max_det = int(max_det)
        self.device = device or _default_device()
        self._text_encoder_spec = text_encoder
        self._encode: Callable[[list[str]], Any] | None = None
        self._embeddings: dict[str, Any] = {}  # phrase -> (D,) prompt embedding (after YOLOE's text head)
        self._active: list[str] | None = None  # classes currently set on the model
        if text_encoder is not None and not callable(text_encoder) and not isinstance(text_encoder, (str, os.PathLike)):
            raise TypeError(f"text_encoder must be a file path, a callable or None, got {type(text_encoder).__name__}")
        if text_encoder is not None and not callable(text_encoder) and not os.path.isfile(text_encoder):
            raise FileNotFoundError(
                f"text encoder file '{text_encoder}' does not exist. YOLOE's text prompts need the "
                f"MobileCLIP TorchScript text encoder (mobileclip_blt.ts for YOLOE-11/v8) as a local file; "
                f"or precompute embeddings and pass them to set_classes(names, embeddings)."
            )

    @classmethod
    def from_pretrained(
        cls,
        weights: str | os.PathLike,
        *,
        text_encoder: str | os.PathLike | Callable[[list[str]], Any] | None = None,
        **kwargs: Any,
    ) -> YOLOEDetector:
        """Build from a local YOLOE checkpoint (``yoloe-11l-seg.pt``) or model YAML (random weights).

        A ``.yaml`` name may be one of ultralytics' packaged model configs
        (``"yoloe-11s-seg.yaml"``): that builds an untrained model, useful for tests only.
        """
        ultralytics = require("ultralytics", "yoloe", "YOLOEDetector")
        require("torch", "yoloe", "YOLOEDetector")
        w = os.fspath(weights)
        if not w.endswith((".yaml", ".yml")) and not os.path.isfile(w):
            raise FileNotFoundError(
                f"YOLOE weights '{w}' not found. Pass a local checkpoint file such as yoloe-11l-seg.pt "
                f"(the paper used YOLOE-L); nothing is downloaded."
            )
        model = ultralytics.YOLOE(w)
        if getattr(model, "task", "segment") != "segment":
            raise ValueError(f"'{w}' is a {model.task} model; the grounder needs a YOLOE *-seg* model for masks")
        return cls(model, text_encoder=text_encoder, **kwargs)

    # ----------------------------------------------------------------- embeddings
    @property
    def known_phrases(self) -> list[str]:
        """Phrases with an embedding ready (from `set_classes` or computed earlier)."""
        return list(self._embeddings)

    def set_classes(self, names: Sequence[str], embeddings: Any = None) -> None:
        """Register phrases with their YOLOE prompt embeddings (no text encoder needed).

        Args:
            names: N phrases.
            embeddings: (N, D) or (1, N, D) tensor / array of *prompt embeddings* as
                ``YOLOE.get_text_pe(names)`` returns them (text features already passed through
                YOLOE's text head); None computes them with the text encoder.
        """
        names = phrase_list(names, "names")  # "cup" was three classes c, u, p; None the class "None"
        import torch

        if embeddings is None:
            emb = self._embed(names)
        else:
            emb = torch.as_tensor(np.asarray(embeddings) if not torch.is_tensor(embeddings) else embeddings)
            emb = emb.detach().float().reshape(-1, emb.shape[-1])
            if emb.shape[0] != len(names):
                raise ValueError(f"{len(names)} names but {emb.shape[0]} embeddings")
        for n, e in zip(names, emb):
            self._embeddings[n] = e.detach().cpu()
        self._active = None

    def _text_features(self, names: list[str]) -> Any:
        if self._encode is None:
            spec = self._text_encoder_spec
            if spec is None:
                raise ValueError(
                    f"no embeddings for {names} and no text encoder: pass text_encoder='mobileclip_blt.ts' "
                    f"(a local file) to YOLOEDetector, or call set_classes(names, embeddings) first"
                )
            if callable(spec):
                self._encode = spec
            else:
                import torch

                try:
                    from ultralytics.nn.text_model import MobileCLIPTS
                except ImportError as exc:  # the `clip` tokenizer package is missing
                    raise MissingDependencyError(
                        "YOLOE text prompts need ultralytics' CLIP tokenizer: "
                        "pip install git+https://github.com/ultralytics/CLIP.git"
                    ) from exc
                enc = MobileCLIPTS(torch.device(self.device), weight=os.fspath(spec))
                self._encode = lambda texts: enc.encode_text(enc.tokenize(texts))
        return self._encode(names)

    def _embed(self, names: list[str]) -> Any:
        """Raw text features -> YOLOE prompt embeddings, through the model's own text head."""
        import torch

        feats = torch.as_tensor(self._text_features(names)).float()
        feats = feats.reshape(1, len(names), feats.shape[-1])
        head = self.model.model.model[-1]
        param = next(self.model.model.parameters())
        with torch.inference_mode():
            pe = head.get_tpe(feats.to(param.device, param.dtype)) if hasattr(head, "get_tpe") else feats
        return pe.detach().float().reshape(len(names), -1)

    # ----------------------------------------------------------------- detection
    def _activate(self, phrases: list[str]) -> None:
        import torch

        if phrases == self._active:
            return
        missing = [p for p in phrases if p not in self._embeddings]
        if missing:
            self.set_classes(missing)
        param = next(self.model.model.parameters())
        emb = torch.stack([self._embeddings[p] for p in phrases])[None].to(param.device, param.dtype)
        self.model.set_classes(list(phrases), emb)
        self._active = list(phrases)

    def detect(self, image: Frame, phrases: Sequence[str]) -> Detections:
        """Instances of `phrases` (a list of str) in `image` ((H, W, 3) uint8 RGB or PIL);
        masks at (H, W). Blank phrases ("", "  ") are dropped, as `TextGrounder` drops
        them, and repeats are asked once; no phrase left gives no detections."""
        rgb = as_rgb_array(image, name="image")
        h, w = rgb.shape[:2]
        # "cup" was read as c, u, p; "" and " " were sent to YOLOE as classes
        phrases = list(dict.fromkeys(p for p in phrase_list(phrases) if p.strip()))
        if not phrases:
            return Detections.empty(h, w)
        self._activate(phrases)
        result = self.model.predict(
            np.ascontiguousarray(rgb[:, :, ::-1]),  # ultralytics takes numpy images as BGR
            conf=self.conf,
            iou=self.iou,
            imgsz=self.imgsz,
            max_det=self.max_det,
            retina_masks=True,  # masks at the original image size
            device=self.device,
            verbose=False,
        )[0]
        if result.masks is None or result.boxes is None or len(result.boxes) == 0:
            return Detections.empty(h, w)
        masks = result.masks.data.detach().cpu().numpy() > 0.5
        if masks.shape[1:] != (h, w):  # defensive: resize to the image if the backend did not
            import cv2

            masks = np.stack([cv2.resize(m.astype(np.uint8), (w, h), interpolation=cv2.INTER_NEAREST) for m in masks]) > 0
        scores = result.boxes.conf.detach().cpu().numpy().astype(np.float32)
        cls = result.boxes.cls.detach().cpu().numpy().astype(int)
        return Detections(masks, scores, [phrases[c] for c in cls])


# --------------------------------------------------------------------------- grounders


class TextGrounder:
    """VLM answer + image -> (H, W) int32 label map, with any `PhraseDetector`.

    Args:
        detector: finds instances of phrases in an image (`YOLOEDetector`, or a stub).
        parse: answer text -> phrases; default `phrases_from_answer` (the
            ``- <noun phrase>: <description>`` format, else free-text noun phrases).
        min_area: instances with fewer visible pixels are dropped.
        max_instances: at most this many labels per image.
    """

    def __init__(
        self,
        detector: PhraseDetector,
        *,
        parse: Callable[[str], list[str]] = phrases_from_answer,
        min_area: int = 1,
        max_instances: int | None = None,
    ) -> None:
        if not callable(getattr(detector, "detect", None)):  # else AttributeError on the first answer
            raise TypeError(f"detector must have detect(image, phrases) -> Detections, got {type(detector).__name__}")
        if not callable(parse):
            raise TypeError(f"parse must be callable as parse(text) -> list of phrases, got {type(parse).__name__}")
        _check_counts(min_area, max_instances)
        self.detector = detector
        self.parse = parse
        self.min_area = min_area
        self.max_instances = max_instances

    def phrases(self, text: str) -> list[str]:
        """The detector prompts found in `text`: ``parse``'s phrases, stripped, without
        empty ones and repeats.

        Raises:
            TypeError: ``parse`` returned something else than a list of str (a str was read
                letter by letter, None failed with "'NoneType' object is not iterable", a
                None or 3 in the list reached the detector).
        """
        found = self.parse(text)
        if isinstance(found, (str, bytes, dict)) or not hasattr(found, "__iter__"):
            raise TypeError(f"parse must return a list of str phrases, got {type(found).__name__} {found!r:.60}")
        found = list(found)
        if not all(isinstance(p, str) for p in found):
            raise TypeError(f"parse must return a list of str phrases, got {found!r:.60}")
        return list(dict.fromkeys(p.strip() for p in found if p.strip()))

    def detect(self, text: str, image: Frame) -> Detections:
        """Instances of the objects named in `text`, found in `image`."""
        rgb = as_rgb_array(image, name="image")
        phrases = self.phrases(text)
        if not phrases:
            return Detections.empty(*rgb.shape[:2])
        det = self.detector.detect(rgb, phrases)
        name = type(self.detector).__name__
        if not isinstance(det, Detections):
            raise TypeError(f"{name}.detect must return Detections, got {type(det).__name__}")
        if det.masks.shape[1:] != rgb.shape[:2]:
            raise ValueError(f"{name}.detect returned masks of {det.masks.shape[2]}x{det.masks.shape[1]} for an "
                             f"image of {rgb.shape[1]}x{rgb.shape[0]}; masks must have the image's size")
        return det

    def ground(self, text: str, image: Frame) -> np.ndarray:
        """(H, W) int32 label map of the objects named in `text` (0 = background, 1..K)."""
        det = self.detect(text, image)
        return masks_to_label_map(det.masks, det.scores, min_area=self.min_area, max_instances=self.max_instances)

    __call__ = ground


class YOLOEGrounder(TextGrounder):
    """`TextGrounder` over YOLOE: the paper's VLM-text -> masks translation.

    Example:
        >>> grounder = YOLOEGrounder.from_pretrained("weights/yoloe-11l-seg.pt",  # doctest: +SKIP
        ...                                          text_encoder="weights/mobileclip_blt.ts")
        >>> labels = grounder.ground("- red block: the cube that slid", final_frame)  # doctest: +SKIP
        >>> labels.shape, labels.dtype  # doctest: +SKIP
        ((480, 640), dtype('int32'))
    """

    detector: YOLOEDetector

    def __init__(self, detector: YOLOEDetector | Any, **kwargs: Any) -> None:
        if not isinstance(detector, YOLOEDetector):  # a bare ultralytics YOLOE model
            detector = YOLOEDetector(detector)
        super().__init__(detector, **kwargs)

    @classmethod
    def from_pretrained(
        cls,
        weights: str | os.PathLike,
        *,
        text_encoder: str | os.PathLike | Callable[[list[str]], Any] | None = None,
        conf: float = 0.25,
        iou: float = 0.7,
        imgsz: int = 640,
        max_det: int = 100,
        device: str | None = None,
        **grounder_kwargs: Any,
    ) -> YOLOEGrounder:
        """Load YOLOE weights (a local ``*-seg.pt``) and optionally its text encoder file."""
        det = YOLOEDetector.from_pretrained(
            weights, text_encoder=text_encoder, conf=conf, iou=iou, imgsz=imgsz, max_det=max_det, device=device
        )
        return cls(det, **grounder_kwargs)

    def set_classes(self, names: Sequence[str], embeddings: Any = None) -> None:
        """Register phrases with precomputed prompt embeddings; see `YOLOEDetector.set_classes`."""
        self.detector.set_classes(names, embeddings)
