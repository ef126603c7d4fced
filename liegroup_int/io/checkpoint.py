"""Checkpoints: the state, the counters and the scene at an output time, written atomically.

``checkpoint.npz`` holds the state arrays (``state/<name>``), the time, the integration
counters and the JSON of everything needed to rebuild the run (scene source, overrides,
record interval). It is written through a temporary file and renamed, so a run killed at
any moment leaves either the previous or the new checkpoint, never half of one.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np


def write_checkpoint(path: Path, t: float, state: dict, stats: dict, meta: dict) -> None:
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp.npz")
    arrays = {f"state/{k}": np.asarray(v) for k, v in state.items()}
    try:
        np.savez(tmp, t=np.float64(t), stats=json.dumps(stats), meta=json.dumps(meta), **arrays)
        os.replace(tmp, path)
    except OSError:  # the previous checkpoint stays
        tmp.unlink(missing_ok=True)
        raise


def read_checkpoint(path: Path) -> dict:
    """``{"t": float, "state": {name: array}, "stats": dict, "meta": dict, "path": str}``."""
    with np.load(path, allow_pickle=False) as z:
        return {
            "path": str(path),
            "t": float(z["t"]),
            "state": {k.split("/", 1)[1]: z[k].copy() for k in z.files if k.startswith("state/")},
            "stats": json.loads(str(z["stats"])),
            "meta": json.loads(str(z["meta"])),
        }
