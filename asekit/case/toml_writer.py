"""A small TOML writer for case files (the standard library reads TOML, ``tomllib``, but does not
write it): nested tables, arrays of tables, strings, booleans, integers, floats and arrays of
those, enough for every key of a case file (docs/case-format.md).

Floats are written with Python's shortest round-trip repr, so ``tomllib.loads(dumps(d)) == d``
bit for bit. Comments of the source file are not kept.
"""

from __future__ import annotations

import math


def _key(k: str) -> str:
    k = str(k)
    if k and all(c.isalnum() or c in "_-" for c in k):
        return k
    return _string(k)


def _string(s: str) -> str:
    out = s.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\t", "\\t")
    return f'"{out}"'


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + " }"
    if hasattr(v, "item"):                                    # a numpy scalar
        return _value(v.item())
    raise TypeError(f"cannot write a {type(v).__name__} to TOML: {v!r}")


def _is_table_array(v) -> bool:
    return isinstance(v, (list, tuple)) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def _emit(d: dict, prefix: str, lines: list) -> None:
    scalars = [(k, v) for k, v in d.items() if not isinstance(v, dict) and not _is_table_array(v)]
    for k, v in scalars:
        lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in d.items():
        name = f"{prefix}.{_key(k)}" if prefix else _key(k)
        if isinstance(v, dict):
            if lines:
                lines.append("")
            lines.append(f"[{name}]")
            _emit(v, name, lines)
        elif _is_table_array(v):
            for item in v:
                if lines:
                    lines.append("")
                lines.append(f"[[{name}]]")
                _emit(item, name, lines)


def dumps(d: dict) -> str:
    """TOML text of the nested dict ``d`` (module docstring).

    Examples
    --------
    >>> import tomllib
    >>> d = {"case": {"name": "fin"}, "panel": [{"root_chord": 0.156, "n_chord": 6}],
    ...      "flight": {"velocities": {"min": 100.0, "max": 460.0}}}
    >>> print(dumps(d))
    [case]
    name = "fin"
    <BLANKLINE>
    [[panel]]
    root_chord = 0.156
    n_chord = 6
    <BLANKLINE>
    [flight]
    <BLANKLINE>
    [flight.velocities]
    min = 100.0
    max = 460.0
    <BLANKLINE>
    >>> tomllib.loads(dumps(d)) == d
    True
    """
    if not isinstance(d, dict):
        raise TypeError(f"dumps needs a dict of tables, got {type(d).__name__}")
    lines: list[str] = []
    _emit(d, "", lines)
    return "\n".join(lines) + "\n"
