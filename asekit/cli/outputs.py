"""Output paths of every command, checked before any work and created when missing, the same
way for ``reproduce`` (``--json``, ``--figures``), ``analyse`` (``--json``, ``--report``) and
``sweep`` (``--out``): each check returns None or the one-line reason the path is unusable, and
makes the missing folders of a usable path."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path


def writable_dir(path: Path) -> str | None:
    """None if ``path`` is (or can be made) a writable directory, else the reason."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        return f"{path} exists and is not a directory"
    probe = path
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        return f"{probe} is not a directory"
    if not os.access(probe, os.W_OK | os.X_OK):
        return f"{probe} is not writable"
    return None


def _make(path: Path, option: str) -> str | None:
    """``mkdir -p path``, or the reason it failed."""
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return f"{option} {path}: cannot create the folder ({exc.strerror or exc})"
    return None


def check_file(option: str, value: str | None, dash: bool = True) -> str | None:
    """A file output (``--json PATH``, ``--out PATH``; ``'-'`` is standard output when ``dash``):
    None when it can be written (its missing folders are created), else the reason."""
    if value is None or (dash and value == "-"):
        return None
    path = Path(value)
    if not value.strip() or path.is_dir():
        return (f"{option} {value!r}: give a file path"
                + (" (or '-' for standard output)" if dash else ""))
    if path.exists() and not os.access(path, os.W_OK):
        return f"{option} {value}: the file is not writable"
    parent = path.parent if str(path.parent) else Path(".")
    reason = writable_dir(parent)
    if reason:
        return f"{option} {value}: {reason}"
    return _make(parent, option)


def check_dir(option: str, value: str | None, what: str = "the output") -> str | None:
    """A folder output (``--figures DIR``, ``--report DIR``): None when it is (or can be made) a
    writable folder (its missing parents are created; the folder itself is made by the command),
    else the reason."""
    if value is None:
        return None
    if not value.strip():
        return f"{option} {value!r}: give a directory for {what}"
    path = Path(value)
    reason = writable_dir(path)
    if reason:
        return f"{option} {value}: {reason}"
    return _make(path.parent if str(path.parent) else Path("."), option)


def print_error(line: str, code: int, log: logging.Logger) -> int:
    """Print ``line``, the one line of a failed command, on standard error, log it to
    ``log`` for ``--log-file`` only (marked ``file_only``: the console handler leaves it out)
    and return the exit ``code``."""
    print(line, file=sys.stderr)
    log.error("%s", line, extra={"file_only": True})
    return code
