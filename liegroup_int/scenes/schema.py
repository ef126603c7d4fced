"""Scene files: TOML read into checked, dotted keys.

A scene is a TOML file. Its keys are addressed in dotted form (``integrator.dt``), which
is also how ``--set KEY=VALUE`` overrides them. Every problem kind declares its keys as
:class:`Key` entries (type, default, unit, check, doc); loading rejects unknown keys and
bad values with a :class:`SceneError` whose message is one line naming the file, the key
and what was expected.
"""

from __future__ import annotations

import math
import numbers
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

REQUIRED = object()


class SceneError(ValueError):
    """A scene is invalid; the message is one line naming the source and the key."""


@dataclass(frozen=True)
class Key:
    """One scene key.

    Parameters
    ----------
    name : str
        Dotted key, e.g. ``"integrator.dt"``.
    kind : str
        ``"float"``, ``"int"``, ``"str"``, ``"bool"``, ``"vec3"`` (3 floats),
        ``"floats"`` (list of floats), ``"float_or_auto"`` (number, ``"auto"`` or
        ``"none"``), ``"number_or_auto"`` (number or ``"auto"``), ``"table"`` (list of
        ``[t, value]`` pairs), ``"strs"`` (list of strings) or ``"tables"`` (a TOML array
        of tables, ``[[name]]``; each entry is checked by the problem kind).
    default : object
        Default value, or ``REQUIRED``.
    doc : str
        One line for docs/scenes.md.
    unit : str
        Physical unit ("" when dimensionless).
    check : callable, optional
        ``check(value) -> str | None``: an explanation of what was expected, or None.
    choices : tuple of str, optional
        Allowed values of a string key.
    """

    name: str
    kind: str
    default: Any
    doc: str
    unit: str = ""
    check: Callable[[Any], "str | None"] | None = None
    choices: tuple[str, ...] | None = None


def positive(v) -> str | None:
    return None if v > 0 else "a positive number"


def non_negative(v) -> str | None:
    return None if v >= 0 else "a number >= 0"


def flatten(table: Mapping, prefix: str = "") -> dict[str, Any]:
    """Nested TOML tables to ``{"a.b.c": value}``."""
    out: dict[str, Any] = {}
    for k, v in table.items():
        key = f"{prefix}{k}"
        if isinstance(v, Mapping):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def parse_override(text: str) -> tuple[str, Any]:
    """``"KEY=VALUE"`` from the command line; VALUE is read as a TOML value when it
    parses as one (numbers, booleans, arrays, quoted strings), else as a bare string."""
    if "=" not in text:
        raise SceneError(f"--set {text!r}: expected KEY=VALUE")
    key, raw = text.split("=", 1)
    key, raw = key.strip(), raw.strip()
    if not key:
        raise SceneError(f"--set {text!r}: empty key")
    try:
        value = tomllib.loads(f"v = {raw}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw
    return key, value


def _is_number(v) -> bool:
    """A finite real number, NumPy's scalars included (not a bool)."""
    return isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)


def _as_list(value):
    """A list, tuple or one-dimensional array as a list (anything else unchanged)."""
    return list(value) if isinstance(value, (list, tuple)) or getattr(value, "ndim", None) == 1 else value


class _Expected(Exception):
    """What a value of a key's kind should have been (the end of :func:`coerce`'s line)."""


def _unit(key: Key) -> str:
    return f" [{key.unit}]" if key.unit else ""


def _as_float(value, expected: str) -> float:
    if not _is_number(value):
        raise _Expected(expected)
    return float(value)


def _float_or_auto(key: Key, value):
    if isinstance(value, str) and value in ("auto", "none"):
        return None if value == "none" else value
    return _as_float(value, 'a finite number, "auto", or "none" (adaptive stepping with rtol/atol)')


def _of_type(test, expected: str):
    def check(key: Key, value):
        if not test(value):
            raise _Expected(expected)
        return value
    return check


def _str(key: Key, value):
    if not isinstance(value, str):
        raise _Expected("a string")
    if key.choices is not None and value not in key.choices:
        raise _Expected("one of " + ", ".join(repr(c) for c in key.choices))
    return value


def _numbers(value, n: int | None, expected: str) -> tuple:
    value = _as_list(value)
    if not (isinstance(value, list) and value and (n is None or len(value) == n) and all(map(_is_number, value))):
        raise _Expected(expected)
    return tuple(float(x) for x in value)


def _strs(key: Key, value):
    if not (isinstance(value, list) and all(isinstance(x, str) for x in value)):
        raise _Expected("a list of strings")
    if key.choices is not None and any(x not in key.choices for x in value):
        raise _Expected("names among " + ", ".join(key.choices))
    return tuple(value)


def _tables(key: Key, value):
    if not (isinstance(value, list) and all(isinstance(x, Mapping) for x in value)):
        raise _Expected("an array of tables ([[" + key.name + "]] entries)")
    return tuple(dict(x) for x in value)


def _table(key: Key, value):
    if not (isinstance(value, list) and len(value) >= 2 and all(
            isinstance(r, list) and len(r) == 2 and all(_is_number(x) for x in r) for r in value)):
        raise _Expected("a list of at least two [t, value] pairs")
    pairs = tuple((float(a), float(b)) for a, b in value)
    if any(b[0] <= a[0] for a, b in zip(pairs, pairs[1:])):
        raise _Expected("[t, value] pairs with strictly increasing t")
    return pairs


#: The converter of each key kind: ``(key, value) -> clean value``, or raises :class:`_Expected`.
_KINDS: dict[str, Callable] = {
    "float": lambda key, v: _as_float(v, "a finite number" + _unit(key)),
    "float_or_auto": _float_or_auto,
    "number_or_auto": lambda key, v: v if isinstance(v, str) and v == "auto" else _as_float(
        v, "a finite number" + _unit(key) + ' or "auto"'),
    "int": lambda key, v: int(_of_type(lambda x: isinstance(x, numbers.Integral) and not isinstance(x, bool),
                                       "an integer")(key, v)),
    "bool": _of_type(lambda v: isinstance(v, bool), "true or false"),
    "str": _str,
    "vec3": lambda key, v: _numbers(v, 3, "a list of 3 numbers"),
    "floats": lambda key, v: _numbers(v, None, "a non-empty list of numbers"),
    "strs": _strs,
    "tables": _tables,
    "table": _table,
}


def coerce(key: Key, value, where: str):
    """Check ``value`` against ``key.kind`` (and ``key.check``); return the clean value."""
    try:
        clean = _KINDS[key.kind](key, value)
        msg = key.check(clean) if key.check is not None and clean not in ("auto", None) else ""
        if msg:
            raise _Expected(msg)
    except _Expected as exc:
        shown = " ".join(repr(value).split())  # one line, whatever the value (a 2-D array)
        raise SceneError(f"{where}: key '{key.name}' = {shown}: expected {exc}") from None
    return clean


#: Byte-order marks of encodings other than UTF-8, which a scene file cannot use.
_OTHER_BOMS = {b"\xff\xfe\x00\x00": "UTF-32", b"\x00\x00\xfe\xff": "UTF-32", b"\xff\xfe": "UTF-16",
               b"\xfe\xff": "UTF-16"}


def decode_scene_text(data: bytes, path) -> str:
    """A scene file's bytes as text: UTF-8, with or without a byte-order mark.

    Raises
    ------
    SceneError
        One line: a binary file (NUL bytes), another encoding's byte-order mark, or bytes
        that are not UTF-8 (with the line and column of the first).
    """
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    for bom, name in _OTHER_BOMS.items():
        if data.startswith(bom):
            raise SceneError(f"{path}: a {name} file; save the scene as UTF-8 text")
    nul = data.find(b"\x00")
    if nul >= 0:
        raise SceneError(f"{path}: a binary file (NUL byte at offset {nul}), not a TOML scene")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        col = exc.start - (data.rfind(b"\n", 0, exc.start) + 1) + 1
        raise SceneError(f"{path}: not UTF-8 text (byte 0x{data[exc.start]:02x} at line {line}, column {col}); "
                         f"save the scene as UTF-8") from None


def read_toml(path: Path) -> dict:
    """Parse a TOML file (UTF-8, a byte-order mark accepted), turning unreadable, binary,
    wrongly encoded and invalid files into a one-line :class:`SceneError`."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file") from None
    except IsADirectoryError:
        raise SceneError(f"{path}: a directory, not a scene file") from None
    except OSError as exc:
        raise SceneError(f"{path}: cannot read: {exc.strerror}") from None
    try:
        return tomllib.loads(decode_scene_text(data, path))
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: invalid TOML: {exc}") from None


def resolve_keys(keys: Mapping[str, Key], given: Mapping[str, Any], where: str) -> dict[str, Any]:
    """Apply defaults, reject unknown and missing keys, coerce every value."""
    unknown = sorted(set(given) - set(keys))
    if unknown:
        import difflib

        close = difflib.get_close_matches(unknown[0], list(keys), n=1, cutoff=0.75)
        near = [k for k in keys if k.split(".")[0] == unknown[0].split(".")[0]]
        hint = (f" (did you mean '{close[0]}'?)" if close
                else f" (keys of this section: {', '.join(sorted(near))})" if near else "")
        raise SceneError(f"{where}: unknown key '{unknown[0]}'{hint}")
    out = {}
    for name, key in keys.items():
        if name in given:
            out[name] = coerce(key, given[name], where)
        elif key.default is REQUIRED:
            raise SceneError(f"{where}: missing required key '{name}' ({key.doc})")
        else:
            out[name] = key.default
    return out
