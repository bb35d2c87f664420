#!/usr/bin/env bash
# Install the optional VLM/YOLOE test dependencies into the active virtual
# environment on a CPU-only machine. Run after `pip install -e ".[test]"`.
#
#   . .venv/bin/activate && bash ci/install-vlm.sh
#
# Why it is not just `pip install -e ".[vlm,yoloe]"`:
#   * torch must stay at the CPU wheel 2.13.0 (constraints.txt); a newer torch means
#     several GB of CUDA packages.
#   * `pip install ultralytics` would resolve torch/torchvision itself and replace CPU
#     torch, so it goes in with --no-deps; its needed runtime deps are listed in
#     requirements-vlm.txt. (opencv-python is skipped: opencv-python-headless provides
#     cv2; nvidia-ml-py / ultralytics-platform are not needed on CPU.)
#   * torchvision exists only as CUDA builds on the registry. It is installed with
#     --no-deps; its compiled ops do not load against CPU torch, so tests/conftest.py
#     registers pure-torch fallbacks for the few ops used (nms, ...). That workaround is
#     test-only: on a normal machine, install a torchvision that matches your torch.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
PIP="python -m pip"
$PIP install -c "$here/constraints.txt" -r "$here/requirements-vlm.txt"
$PIP install -c "$here/constraints.txt" --no-deps "torchvision==0.28.0" "ultralytics>=8.3.160,<8.5"
python - <<'PY'
import importlib.metadata as md
import torch, transformers
print("torch", torch.__version__, "| transformers", transformers.__version__,
      "| ultralytics", md.version("ultralytics"), "| torchvision", md.version("torchvision"))
assert torch.__version__.startswith("2.13.0"), f"torch pin lost: {torch.__version__}"
PY
