"""Locations of asekit's data files: the repository's ``data/`` folder in a source checkout
(an editable install), the package ``asekit.data`` inside an installed wheel."""

from pathlib import Path

_SOURCE_DATA = Path(__file__).resolve().parents[2] / "data"
#: data/ of the checkout, else asekit/data/ of the installed wheel (pyproject maps one to the other)
DATA_DIR = (_SOURCE_DATA if (_SOURCE_DATA / "thesis.toml").exists()
            else Path(__file__).resolve().parents[1] / "data")
#: The reference fin, one case among the shipped cases.
CASES_DIR = DATA_DIR / "cases"
FIN_FILE = CASES_DIR / "nalci2013_fin.toml"
THESIS_FILE = DATA_DIR / "thesis.toml"


def user_cache_dir() -> Path:
    """Where asekit writes rebuilt caches (GAF databases): ``$ASEKIT_CACHE_DIR`` if set, else
    ``$XDG_CACHE_HOME/asekit``, else ``~/.cache/asekit``. Never inside the repository or the
    installed package, so running anything leaves tracked files as they are."""
    import os
    env = os.environ.get("ASEKIT_CACHE_DIR")
    if env:
        return Path(env).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg).expanduser() if xdg else Path.home() / ".cache") / "asekit"


def shipped_cases() -> dict[str, Path]:
    """The case files shipped with asekit (``data/cases/*.toml``), by name (the file stem).

    Examples
    --------
    >>> "agard445_6" in shipped_cases()
    True
    """
    return {p.stem: p for p in sorted(CASES_DIR.glob("*.toml"))}


def shipped_case(name: str) -> Path | None:
    """The shipped case file called ``name`` (with or without ``.toml``), or None.

    Examples
    --------
    >>> shipped_case("agard445_6.toml").name
    'agard445_6.toml'
    >>> shipped_case("no_such_case") is None
    True
    """
    stem = name[:-5] if name.endswith(".toml") else name
    if "/" in stem or "\\" in stem:
        return None
    return shipped_cases().get(stem)
