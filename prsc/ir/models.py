"""Which asset an object's class names: its `model`, the compat `model_name`, or its class name.

The sampler's scene JSON writes this name for the backends, and the constraint stage reads
it for a container asset's own interior (prsc.geometry.container.ASSET_INTERIORS), so both
agree on what an object is.
"""

from __future__ import annotations

from typing import Any, Mapping

from prsc.user_assets.asset_files import names_asset_file
from prsc.user_assets.asset_fitting import library_arm_names
from prsc.errors import PrscError

KNOWN_MODELS = frozenset({"tray", "table", "cube", "cylinder", "bowl", "cup", "camera"}) | library_arm_names()
"""Asset names the backends know that a class of the same name uses without saying so (docs/scene-json.md):
the part assets above and the model library's arms."""


def model_of(props: Mapping[str, Any], class_name: str) -> str | None:
    """The asset name: `model`, else the compat `model_name` in lower case, else a known class name."""
    model = props.get("model")
    if model is None:
        model = props.get("model_name")
    if model is None:
        guess = class_name.lower()
        return guess if guess in KNOWN_MODELS else None
    if not isinstance(model, str):
        raise PrscError(f"model of {class_name} must be a string, got {model!r}")
    if names_asset_file(model):
        return model.strip()  # a file name keeps its case (docs/assets.md)
    return model.strip().lower() or None
