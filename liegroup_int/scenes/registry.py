"""Built-in scenes shipped with the package (``scenes/builtin/*.toml``)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .schema import SceneError, read_toml


def _builtin_dir() -> Path:
    return Path(str(resources.files("liegroup_int.scenes") / "builtin"))


def builtin_names() -> list[str]:
    """Names of the built-in scenes, sorted."""
    return sorted(p.stem for p in _builtin_dir().glob("*.toml"))


def builtin_path(name: str) -> Path:
    """Path of a built-in scene; :class:`SceneError` naming the valid ones if unknown."""
    p = _builtin_dir() / f"{name}.toml"
    if not p.is_file():
        import difflib

        close = difflib.get_close_matches(str(name), builtin_names(), n=1, cutoff=0.6)
        hint = f"did you mean '{close[0]}'? " if close else ""
        raise SceneError(f"{name}: not a scene file and not a built-in scene ({hint}built-ins: "
                         f"{', '.join(builtin_names())})")
    return p


def builtin_descriptions() -> dict[str, str]:
    """``name -> description`` of every built-in scene."""
    return {n: read_toml(builtin_path(n)).get("description", "") for n in builtin_names()}
