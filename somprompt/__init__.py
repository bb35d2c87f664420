"""Set-of-Mark prompting from label maps.

Numbered marks on frames and videos from any (H, W) integer label map (0 = background,
k > 0 = object k), prompts from the repository's ``prompts/`` folder, and VLM answers
mapped back to masks ("[3]" -> the mask of mark 3). Imports no segmenter and no VLM
adapter: the segmenter is any ``frames -> label maps`` callable and the VLM any object
with ``generate(frames, prompt, system=None, **gen) -> str``.

Example:
    >>> import numpy as np
    >>> import somprompt
    >>> frame = np.zeros((64, 64, 3), np.uint8)
    >>> labels = np.zeros((64, 64), np.int32); labels[8:40, 8:40] = 1
    >>> marked = somprompt.draw_marks(frame, labels, mode="mask+contour+number")
    >>> somprompt.parse_answer("The block [1] moved.", labels=labels).ids
    [1]
"""

from .anchors import LabelPlacement, distance_to_edge, mask_anchor, place_labels
from .annotators import BoxAnnotator, ContourAnnotator, MaskAnnotator, NumberAnnotator, auto_text_scale
from .answers import (
    Citation,
    NamedObject,
    ParsedAnswer,
    find_citations,
    masks_for_ids,
    parse_answer,
    parse_named_objects,
    repair_text,
)
from .colors import Color, ColorPalette, contrast_ratio, contrasting_color, relative_luminance, to_hex
from .inputs import as_rgb_array, check_label_map
from .metadata import MarkInfo, describe_marks, marks_to_json, save_marks_json
from .pipeline import VLM, GroundedVQA, GroundedVQAResult, Segmenter
from .prompts import (
    PromptError,
    default_prompts_dir,
    format_mark_list,
    list_prompts,
    load_prompt,
    mark_prompt_variables,
    prompt_variables,
)
from .regions import LabelRegions, Region
from .registry import MarkRegistry, MarkStyle, mark_text, parse_mark_text
from .render import MARK_PARTS, MAX_MARKS, RenderedMarks, SetOfMarkRenderer, draw_marks, parse_mode
from .video import (
    MarkedVideo,
    frames_for_vlm,
    mark_video,
    resize_max_side,
    sample_for_vlm,
    sample_frame_indices,
    write_gif,
    write_mp4,
)

__all__ = [
    # rendering
    "SetOfMarkRenderer", "draw_marks", "RenderedMarks", "parse_mode", "MARK_PARTS", "MAX_MARKS",
    "MaskAnnotator", "ContourAnnotator", "BoxAnnotator", "NumberAnnotator", "auto_text_scale",
    "Color", "ColorPalette", "to_hex", "relative_luminance", "contrast_ratio", "contrasting_color",
    # geometry
    "LabelRegions", "Region", "mask_anchor", "distance_to_edge", "place_labels", "LabelPlacement",
    # marks and metadata
    "MarkRegistry", "MarkStyle", "mark_text", "parse_mark_text",
    "MarkInfo", "describe_marks", "marks_to_json", "save_marks_json",
    # video
    "mark_video", "MarkedVideo", "write_mp4", "write_gif", "frames_for_vlm", "sample_for_vlm",
    "sample_frame_indices", "resize_max_side",
    # prompts
    "load_prompt", "list_prompts", "prompt_variables", "default_prompts_dir", "PromptError",
    "format_mark_list", "mark_prompt_variables",
    # answers
    "parse_answer", "find_citations", "ParsedAnswer", "Citation", "masks_for_ids",
    "parse_named_objects", "NamedObject", "repair_text",
    # pipeline
    "GroundedVQA", "GroundedVQAResult", "Segmenter", "VLM",
    # input checks
    "as_rgb_array", "check_label_map",
]
