"""Locations of the repository's data files (``data/``)."""

from pathlib import Path

DATA_DIR = Path(__file__).resolve().parent.parent / "data"
FIN_FILE = DATA_DIR / "fin.toml"
THESIS_FILE = DATA_DIR / "thesis.toml"
