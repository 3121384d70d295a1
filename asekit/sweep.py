"""Flight-envelope and uncertainty sweeps of a case file, serial, in local processes or on a
Dask cluster, with identical results.

A sweep (TOML, ``data/sweeps/``) names a base case file and varies its keys by key path
(``material.youngs_modulus``, ``support.torsional_stiffness``, ``thickness.root``,
``damping.modal_damping_ratio``, ``actuator.controller.k_p``, ``panel[0].tip_chord``...) plus
the analysed flight condition ``flight.mach`` / ``flight.altitude``. Each parameter is a grid
(``values`` or a ``range``) or a distribution (normal, uniform, lognormal, truncated normal) for
Monte Carlo with a seed. The samples are the Cartesian product of the grids times the Monte
Carlo draws (the same draws at every grid point: common random numbers).

Every sample edits the parsed TOML dict of the base case at its key paths and rebuilds the
case with :func:`asekit.case.case_from_dict`, so it is validated with the same key-path errors
as a case file; a sample whose case is invalid (or whose analysis raises) becomes a failed row
with its error message, never a dropped row.

AIC reuse. The sweep honours the base case's ``aero.method`` (:mod:`asekit.aero.methods`;
``auto`` resolved per Mach). Every method of the registry has a structure-independent pressure
operator (it depends on the boxes, Mach and k only): the DLM's normalwash matrices D(M, k)
(:func:`asekit.aero.dlm.normalwash_matrices`), the Mach-box and piston pressure matrices. The
sweep forms it once per (M, k) for the base box mesh (:func:`aic_factors`: the LU of D, or the
matrix) and projects each sample's mode shapes:
Q_ij(M, k) = h_i(lp)^T A Op(M, k) (dh_j/dx + i k h_j / b) (thesis Eqs. 2.10-2.12, the same
operations as :func:`asekit.aero.gaf.gaf_from_box_modes`, so for the DLM and piston theory the
projected GAFs are bit-identical to a rebuilt database). Where forming the operator costs more
than the sweep's samples would (the Mach-box matrices of a sweep with few samples,
:attr:`asekit.aero.methods.AeroMethod.reuse_break_even`), or a method's operator depends on the
structure, each sample's GAFs are computed by the method itself, as the pipeline does. A sample
whose boxes, reduced frequencies, method or kernel settings differ from the base (a planform or
``aero`` key varied) gets its own (column ``aic_reused`` false). The analysed Mach must lie in
the method's range: otherwise the sweep file is refused naming its key path and
``aero.method``. On Dask the operators are scattered to the workers once, on local processes
they are passed once per process (pool initializer).

Determinism: the samples are drawn up front from ``numpy.random.SeedSequence(seed)`` (one
child stream per parameter, inverse-CDF transforms, no rejection), every sample is evaluated by
the same pure function, and the table is sorted by sample index: the same sweep file gives
bit-identical tables serially, with processes and on Dask (except the timing column
``wall_s``) on machines with the same floating-point behaviour.

Results: one row per sample (:data:`BASE_COLUMNS`, every parameter value, every output), journaled
row by row to the output CSV as samples finish, so an interrupted sweep resumes from its partial
output file (rows of another sweep are refused by their ``sweep_id``; its failed rows are run
again unless ``retry_failed=False``). A worker process that dies is replaced and its sample run
again, a bounded number of times (:func:`_run_processes`); workers die with the sweep's process.
"""

from __future__ import annotations

import copy
import csv
import hashlib
import io
import itertools
import json
import logging
import math
import os
import re
import time
import tomllib
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from asekit.aero.gaf import GafDatabase, gaf_from_box_modes
from asekit.aero.methods import AERO_METHODS, TransonicWarning, method_spec, resolve_method
from asekit.aero.spline import fe_spline, modal_forces
from asekit.aeroelastic.flutter import divergence_speeds
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline as P
from asekit.case.envelope import flutter_points, start_kind
from asekit.case.schema import CaseError, _number, _Table, case_from_dict
from asekit.util.blas import one_blas_thread
from asekit.util.conventions import mode_number
from asekit.util.extras import require
from asekit.util.paths import CASES_DIR
from asekit.util.validate import read_toml

_log = logging.getLogger(__name__)


class SweepError(ValueError):
    """A sweep file or sweep definition that cannot be run; the message names the key."""


# ---------------------------------------------------------------------------------------------
# key paths into the parsed TOML dict
# ---------------------------------------------------------------------------------------------
_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")
#: Parameters that are not case-file keys: the analysed flight condition of each sample (Mach
#: and either the altitude, 1976 standard atmosphere, or the density in kg/m^3).
CONDITION_PATHS = ("flight.mach", "flight.altitude", "flight.density")
#: Outputs that need the speed of sound of the analysed condition (not known for a density).
SPEED_OF_SOUND_OUTPUTS = ("flight_speed", "flutter_margin", "flutter_inside")


def parse_key_path(path: str) -> tuple:
    """``"panel[0].tip_chord"`` -> ``("panel", 0, "tip_chord")``; SweepError if malformed."""
    if not isinstance(path, str) or not path:
        raise SweepError(f"a key path must be a non-empty string, got {path!r}")
    out = []
    for part in path.split("."):
        m = _TOKEN.fullmatch(part)
        if m is None:
            raise SweepError(f"key path {path!r} is malformed at {part!r} (expected names "
                             f"joined by dots, with optional [index], e.g. panel[0].tip_chord)")
        out.append(m.group(1))
        out.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
    return tuple(out)


def get_key(d: dict, path: str):
    """The value at ``path`` in the nested dict ``d`` (KeyError / IndexError if absent)."""
    cur = d
    for t in parse_key_path(path):
        cur = cur[t]
    return cur


def set_key(d: dict, path: str, value) -> None:
    """Set ``path`` in the nested dict ``d`` in place, creating missing tables (a table the
    case schema does not know is then refused by :func:`~asekit.case.case_from_dict`)."""
    toks = parse_key_path(path)
    cur = d
    for i, t in enumerate(toks[:-1]):
        nxt = toks[i + 1]
        if isinstance(t, int):
            if not isinstance(cur, list) or t >= len(cur):
                raise SweepError(f"key path {path!r}: index [{t}] does not exist in the base case")
            cur = cur[t]
            continue
        if not isinstance(cur, dict):
            raise SweepError(f"key path {path!r}: {t!r} is not inside a table")
        if t not in cur:
            if isinstance(nxt, int):
                raise SweepError(f"key path {path!r}: {t} is not in the base case")
            cur[t] = {}
        cur = cur[t]
    last = toks[-1]
    if isinstance(last, int):
        if not isinstance(cur, list) or last >= len(cur):
            raise SweepError(f"key path {path!r}: index [{last}] does not exist in the base case")
        cur[last] = value
    else:
        if not isinstance(cur, dict):
            raise SweepError(f"key path {path!r}: the parent of {last!r} is not a table")
        cur[last] = value


# ---------------------------------------------------------------------------------------------
# parameters and samplers
# ---------------------------------------------------------------------------------------------
DISTRIBUTIONS = ("normal", "uniform", "lognormal", "truncated_normal")


@dataclass(frozen=True)
class Parameter:
    """One varied key.

    Attributes
    ----------
    path : the case-file key path (or ``flight.mach`` / ``flight.altitude``).
    kind : ``"grid"`` (``values``) or a distribution: ``"normal"`` (``a`` = mean,
        ``b`` = standard deviation), ``"uniform"`` (``low``, ``high``), ``"lognormal"``
        (``a`` = median, ``b`` = sigma of ln X), ``"truncated_normal"`` (mean ``a``, standard
        deviation ``b`` of the parent normal, truncated to [``low``, ``high``]).
    """

    path: str
    kind: str
    values: tuple = ()
    a: float | None = None
    b: float | None = None
    low: float | None = None
    high: float | None = None

    @property
    def is_grid(self) -> bool:
        return self.kind == "grid"

    def draw(self, u: np.ndarray) -> np.ndarray:
        """Values from uniforms ``u`` in (0, 1) by the inverse CDF (deterministic)."""
        from scipy.special import ndtr, ndtri
        if self.kind == "normal":
            return self.a + self.b * ndtri(u)
        if self.kind == "uniform":
            return self.low + (self.high - self.low) * u
        if self.kind == "lognormal":
            return self.a * np.exp(self.b * ndtri(u))
        if self.kind == "truncated_normal":
            lo, hi = ndtr((self.low - self.a) / self.b), ndtr((self.high - self.a) / self.b)
            x = self.a + self.b * ndtri(lo + u * (hi - lo))
            return np.clip(x, self.low, self.high)
        raise SweepError(f"{self.path}: not a distribution ({self.kind})")


def _check_mach_value(where: str, v) -> float:
    """A finite number for a Mach value of the sweep file (its range is the case's aero
    method's, checked by :func:`_check_condition`)."""
    return _number(where, v, None, None, True, False, "", SweepError)


#: The keys of a [[parameter]] table that each kind reads (besides path).
_DIST_KEYS = {"normal": ("mean", "std"), "uniform": ("low", "high"),
              "lognormal": ("median", "sigma"),
              "truncated_normal": ("mean", "std", "low", "high")}


def _grid_values(t: _Table, where: str) -> tuple:
    """The values of a grid parameter: ``values`` (a non-empty list) or ``range``
    ({min, max, num} or {min, max, step})."""
    if t.has("values") and t.has("range"):
        raise SweepError(f"{where}: give values or range, not both")
    if t.has("values"):
        vals = t.raw("values")
        if not isinstance(vals, list) or not vals:
            raise SweepError(f"{where}.values must be a non-empty list, got {vals!r}")
        return tuple(vals)
    r = t.table("range")
    if r.has("num") == r.has("step"):
        raise SweepError(f"{r.path} must be {{min, max, num}} or {{min, max, step}}, got {r.d!r}")
    lo, hi = r.number("min", required=True), r.number("max", required=True)
    n = r.integer("num", low=1, high=100000)
    st = r.number("step", low=0.0)
    r.done()
    if hi < lo:
        raise SweepError(f"{r.path}: min ({lo:g}) must be <= max ({hi:g})")
    if n is not None:
        return tuple(float(v) for v in np.linspace(lo, hi, n))
    n = int(math.floor((hi - lo) / st + 1e-9)) + 1
    if n > 100000:
        raise SweepError(f"{r.path} gives {n} values (> 100000)")
    return tuple(float(v) for v in lo + st * np.arange(n))


def _parameter(i: int, d, base: dict) -> Parameter:
    """The ``i``-th [[parameter]] table (asekit.case.schema's _Table: typed getters naming the
    key path ``parameter[i] (path).key``, unknown keys refused)."""
    t = _Table(d, f"parameter[{i}]", SweepError)
    path = t.raw("path")
    if not isinstance(path, str):
        raise SweepError(f"parameter[{i}].path is missing (a case-file key path, e.g. "
                         f"material.youngs_modulus)")
    parse_key_path(path)
    t.path = where = f"parameter[{i}] ({path})"
    grid = t.has("values") or t.has("range")
    if grid and t.has("distribution"):
        raise SweepError(f"{where}: give values/range (a grid) or a distribution, not both")
    if grid:
        vals = _grid_values(t, where)
        t.done()
        return Parameter(path, "grid", values=vals)
    if not t.has("distribution"):
        raise SweepError(f"{where}: give values, range or distribution "
                         f"({', '.join(DISTRIBUTIONS)})")
    dist = t.string("distribution", DISTRIBUTIONS)
    allowed = _DIST_KEYS[dist]
    bad = sorted(set(t.d) - set(allowed) - {"path", "distribution"})
    if bad:
        raise SweepError(f"{where}: {bad[0]} is not a parameter of the {dist} distribution "
                         f"(give {', '.join(sorted(allowed))})")

    def centre(key):
        if t.has(key):
            return t.number(key)
        if path in CONDITION_PATHS:
            raise SweepError(f"{where}.{key} is missing")
        try:
            v = get_key(base, path)
        except (KeyError, IndexError, TypeError):
            raise SweepError(f"{where}.{key} is missing and the base case has no value at "
                             f"{path}") from None
        return _number(f"{where}.{key} (the base case's {path})", v, None, None, True, False,
                       "", SweepError)

    def spread(key):
        return t.number(key, required=True, low=0.0)

    def bounds():
        lo, hi = t.number("low", required=True), t.number("high", required=True)
        if not lo < hi:
            raise SweepError(f"{where}: low ({lo:g}) must be < high ({hi:g})")
        return lo, hi

    if dist == "normal":
        out = Parameter(path, dist, a=centre("mean"), b=spread("std"))
    elif dist == "uniform":
        lo, hi = bounds()
        out = Parameter(path, dist, low=lo, high=hi)
    elif dist == "lognormal":
        med = centre("median")
        if med <= 0:
            raise SweepError(f"{where}.median must be > 0, got {med:g}")
        out = Parameter(path, dist, a=med, b=spread("sigma"))
    else:
        mean, std = centre("mean"), spread("std")
        lo, hi = bounds()
        from scipy.special import ndtr
        if ndtr((hi - mean) / std) - ndtr((lo - mean) / std) < 1e-12:
            raise SweepError(f"{where}: [low, high] = [{lo:g}, {hi:g}] holds no probability of "
                             f"the normal(mean {mean:g}, std {std:g})")
        out = Parameter(path, dist, a=mean, b=std, low=lo, high=hi)
    t.done()
    return out


# ---------------------------------------------------------------------------------------------
# outputs
# ---------------------------------------------------------------------------------------------
#: Outputs at the analysed condition (flight.mach, flight.altitude) of each sample.
POINT_OUTPUTS = {
    "flutter_speed": "m/s, first p-k flutter crossing (empty: none in the velocity sweep)",
    "flutter_frequency": "Hz, at the flutter speed",
    "flutter_mode": "the fluttering elastic mode, numbered from 1 (rigid mode not counted)",
    "divergence_speed": "m/s, static divergence (steady GAF eigenproblem; empty: none)",
    "unstable_at_start": "the first speed of the velocity sweep is already unstable",
    "flight_speed": "m/s, M a at the analysed condition",
    "flutter_margin": "U_f / (M a) - 1 at the analysed condition",
    "flutter_inside": "flutter at or below the flight speed M a (unstable at the condition)",
    "f1_hz": "Hz, first elastic natural frequency",
    "f2_hz": "Hz, second elastic natural frequency",
}
#: Outputs over the whole case (every aero.machs x flight altitude; the analyse pipeline).
ENVELOPE_OUTPUTS = {
    "min_flutter_speed": "m/s, lowest flutter speed over aero.machs x flight conditions (empty "
                         "when only bounded: a condition unstable at the sweep's first speed)",
    "min_flutter_speed_upper_bound": "m/s, the lowest flutter speed is at most this (a "
                                     "condition unstable at the first speed of the sweep)",
    "envelope_margin": "smallest flutter margin U_f / U_envelope - 1 over the altitudes "
                       "(needs [flight.envelope]; empty when only bounded)",
    "envelope_margin_upper_bound": "the smallest flutter margin is at most this (the case "
                                   "summary's margin_upper_bound at an altitude)",
    "envelope_margin_lower_bound": "the smallest flutter margin is at least this (no flutter "
                                   "up to the last speed of the sweep at an altitude)",
    "matched_mach": "lowest match-point Mach over the altitudes (empty: no match)",
}
#: Outputs of the ASE loop (needs [actuator]): thesis Ch. 5 / Table 2 metrics.
ASE_OUTPUTS = {f"{t}_{m}": d for t in ("aem1", "aem2") for m, d in (
    ("stable", "closed loop stable"), ("max_real_pole", "1/s, largest closed-loop Re(pole)"),
    ("settling_s", "s, 2 % settling time of the power-limited step"),
    ("steady_error", "fraction of the command at the end of the step"),
    ("corner_overshoot", "largest corner overshoot, fraction of the command"))}
OUTPUTS = {**POINT_OUTPUTS, **ENVELOPE_OUTPUTS, **ASE_OUTPUTS}
#: Columns of every table, before the parameters and outputs.
BASE_COLUMNS = ("sample", "sweep_id", "seed", "status", "error", "aic_reused", "wall_s")
DEFAULT_OUTPUTS = ("flutter_speed", "flutter_frequency", "divergence_speed", "unstable_at_start",
                   "flutter_margin", "flutter_inside")


# ---------------------------------------------------------------------------------------------
# the sweep
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Sweep:
    """A checked sweep: ``base`` the parsed TOML dict of the base case (after the sweep's
    ``[case]`` overrides), ``parameters``, Monte Carlo ``samples`` and ``seed``, the analysed
    condition defaults ``mach`` and ``altitude`` (m), or ``density`` (kg/m^3, then
    ``altitude`` is unused: a sweep over a case with densities, e.g. a wind-tunnel case), the
    ``outputs`` and the file it came from."""

    name: str
    base: dict = field(compare=False, hash=False)
    parameters: tuple[Parameter, ...]
    outputs: tuple[str, ...]
    mach: float
    altitude: float
    samples: int = 1
    seed: int = 0
    source: str = field(default="", compare=False)
    density: float | None = None

    @property
    def grid(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.parameters if p.is_grid)

    @property
    def random(self) -> tuple[Parameter, ...]:
        return tuple(p for p in self.parameters if not p.is_grid)

    @property
    def n_samples(self) -> int:
        n = self.samples if self.random else 1
        for p in self.grid:
            n *= len(p.values)
        return n

    @property
    def condition_path(self) -> str:
        """``"flight.density"`` when the samples are analysed at a density, else
        ``"flight.altitude"``."""
        return "flight.altitude" if self.density is None else "flight.density"

    def sweep_id(self) -> str:
        """Short SHA-256 of everything that defines the rows (base case, parameters, outputs,
        condition, samples, seed): the rows of a partial output file must carry it."""
        d = {"base": self.base, "parameters": [p.__dict__ for p in self.parameters],
             "outputs": list(self.outputs), "mach": self.mach, "altitude": self.altitude,
             "samples": self.samples if self.random else 1, "seed": self.seed}
        if self.density is not None:
            d["density"] = self.density
        return hashlib.sha256(json.dumps(d, sort_keys=True, default=repr).encode()).hexdigest()[:16]

    def columns(self) -> tuple[str, ...]:
        params = [p.path for p in self.parameters if p.path not in CONDITION_PATHS]
        return BASE_COLUMNS + ("flight.mach", self.condition_path) + tuple(params) + self.outputs

    def design(self) -> list[dict]:
        """The samples in order: one dict {key path: value} per row (grid-major, then the Monte
        Carlo draws, the same draws at every grid point)."""
        rnd = self.random
        if rnd:
            children = np.random.SeedSequence(self.seed).spawn(len(rnd))
            draws = []
            for p, ss in zip(rnd, children):
                g = np.random.Generator(np.random.PCG64(ss))
                u = (g.integers(0, 2 ** 53, self.samples, dtype=np.int64) + 0.5) / 2.0 ** 53
                draws.append(p.draw(u))
            mc = [{p.path: float(x[i]) for p, x in zip(rnd, draws)} for i in range(self.samples)]
        else:
            mc = [{}]
        grid = self.grid
        out = []
        for combo in itertools.product(*(p.values for p in grid)):
            g = {p.path: v for p, v in zip(grid, combo)}
            out.extend({**g, **m} for m in mc)
        return out

    def case_dict(self, values: dict) -> tuple[dict, float, float]:
        """The sample's case dict (base edited at the key paths), its analysed Mach and its
        altitude (m), or its density (kg/m^3) when :attr:`density` is set."""
        d = copy.deepcopy(self.base)
        mach = self.mach
        cond = self.altitude if self.density is None else self.density
        for path, v in values.items():
            if path == "flight.mach":
                mach = float(v)
            elif path in ("flight.altitude", "flight.density"):
                cond = float(v)
            else:
                set_key(d, path, v)
        return d, mach, cond


def _base_condition(case_dict: dict, case) -> tuple[float, float, float | None]:
    """Default analysed condition (mach, altitude m, density kg/m^3 or None): the envelope's
    top Mach at its lowest altitude (the critical corner: highest flight speed at the highest
    density), else the case's highest Mach at its first altitude; a case with densities
    instead of altitudes: its highest Mach at its first density."""
    f = case.flight
    mach = f.envelope_mach[1] if f.envelope_mach is not None else case.aero.machs[-1]
    if f.envelope_altitude is not None:
        alt = f.envelope_altitude[0]
    elif f.altitudes is not None:
        alt = f.altitudes[0]
    else:
        alt = 0.0
    dens = None if f.densities is None else float(f.densities[0])
    return float(mach), float(alt), dens


def _case_file(cpath: str, base_dir) -> Path:
    """The base case file: ``cpath`` relative to the sweep file, else a shipped case."""
    p = Path(cpath)
    if not p.is_absolute():
        p = Path(base_dir) / p
        if not p.exists():
            if (CASES_DIR / cpath).exists():          # a shipped case by name
                p = CASES_DIR / cpath
    return p


def _outputs(raw, base_case, density_condition: bool) -> tuple[str, ...]:
    """``sweep.outputs`` checked against :data:`OUTPUTS` and what the base case provides."""
    if raw is None:
        return tuple(o for o in DEFAULT_OUTPUTS
                     if not (density_condition and o in SPEED_OF_SOUND_OUTPUTS))
    if not isinstance(raw, list) or not raw or not all(isinstance(o, str) for o in raw):
        raise SweepError(f"sweep.outputs must be a non-empty list of names, got {raw!r}")
    for o in raw:
        if o not in OUTPUTS:
            raise SweepError(f"sweep.outputs: {o!r} is not an output (known: "
                             f"{', '.join(OUTPUTS)})")
        if density_condition and o in SPEED_OF_SOUND_OUTPUTS:
            raise SweepError(f"sweep.outputs: {o} needs the speed of sound of the analysed "
                             f"condition, and the sweep analyses flight.density (kg/m^3; the "
                             f"base case's flight.densities or the sweep's density): give "
                             f"sweep.altitude or a flight.altitude parameter instead")
    if len(set(raw)) != len(raw):
        raise SweepError("sweep.outputs lists a name twice")
    if any(o in ASE_OUTPUTS for o in raw) and base_case.actuator is None:
        raise SweepError("sweep.outputs: the aem1_* / aem2_* outputs need an [actuator] in the "
                         "base case")
    for o in ("envelope_margin", "envelope_margin_upper_bound", "envelope_margin_lower_bound"):
        if o in raw and base_case.flight.envelope_mach is None:
            raise SweepError(f"sweep.outputs: {o} needs [flight.envelope] in the base case")
    return tuple(raw)


def sweep_from_dict(d: dict, base_dir=".", source: str = "") -> Sweep:
    """Build and check a :class:`Sweep` from a parsed sweep file (see ``data/sweeps/``); the
    tables are read by :class:`asekit.case.schema._Table` (typed getters naming the key path,
    unknown keys refused), raising :class:`SweepError`."""
    top = _Table(d, "", SweepError)
    if not top.has("sweep"):
        raise SweepError("sweep is missing: a [sweep] table with case = \"path/to/case.toml\"")
    s = top.table("sweep")
    over = top.raw("case", {})
    raw = top.raw("parameter", [])
    top.done()
    name = s.text("name", "sweep")
    if not name:
        raise SweepError("sweep.name must be a non-empty string, got ''")
    cpath = s.text("case", "")
    if not cpath:
        raise SweepError("sweep.case is missing: the base case file (relative to the sweep file)")
    samples = s.integer("samples", 1, low=1, high=10 ** 7)
    seed = s.integer("seed", 0, low=0, high=2 ** 63 - 1)
    outs = s.raw("outputs")
    mach = None if not s.has("mach") else _check_mach_value("sweep.mach", s.raw("mach"))
    alt = s.number("altitude")
    dens = s.number("density", low=0.0, high=100.0, unit="kg/m^3")
    s.done()
    p = _case_file(cpath, base_dir)
    try:
        with open(p, "rb") as fh:
            base = tomllib.load(fh)
    except FileNotFoundError:
        raise SweepError(f"sweep.case: case file {p} not found") from None
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"sweep.case: {p.name} is not valid TOML: {exc}") from None
    if not isinstance(over, dict):
        raise SweepError("case must be a table of overrides {key path = value}")
    for k, v in over.items():
        set_key(base, k, copy.deepcopy(v))
    try:
        base_case = case_from_dict(copy.deepcopy(base), source=str(p))
    except CaseError as exc:
        raise SweepError(f"base case ({p.name} with the sweep's [case] overrides): {exc}") from None
    if not isinstance(raw, list):
        raise SweepError("parameter must be an array of tables ([[parameter]])")
    params = tuple(_parameter(i, t, base) for i, t in enumerate(raw))
    paths = [q.path for q in params]
    if len(set(paths)) != len(paths):
        dup = next(x for x in paths if paths.count(x) > 1)
        raise SweepError(f"parameter path {dup!r} is given twice")
    # the analysed condition: altitude (standard atmosphere) or density
    by_alt = alt is not None or "flight.altitude" in paths
    by_dens = dens is not None or "flight.density" in paths
    if by_alt and by_dens:
        raise SweepError("give the analysed condition as flight.altitude (sweep.altitude or a "
                         "parameter) or as flight.density (sweep.density or a parameter), "
                         "not both")
    mach0, alt0, dens0 = _base_condition(base, base_case)
    density_condition = by_dens or (not by_alt and dens0 is not None)
    mach = mach0 if mach is None else mach
    alt = alt0 if alt is None else alt
    dens = (dens if dens is not None else dens0) if density_condition else None
    if density_condition and dens is None:
        raise SweepError("sweep.density is missing (the flight.density parameter has no "
                         "default: the base case gives altitudes)")
    method = base_case.aero.method
    _check_condition("sweep.mach", "flight.mach", mach, method)
    _check_condition("sweep.altitude", "flight.altitude", alt)
    if dens is not None:
        _check_condition("sweep.density", "flight.density", dens)
    outputs = _outputs(outs, base_case, density_condition)
    for i, q in enumerate(params):
        if q.path in CONDITION_PATHS and q.is_grid:
            for j, v in enumerate(q.values):
                where = f"parameter[{i}] ({q.path}).values[{j}]"
                _check_condition(where, q.path, _check_mach_value(where, v), method)
    if "samples" in s.d and not any(not q.is_grid for q in params):
        raise SweepError("sweep.samples needs at least one parameter with a distribution")
    sweep = Sweep(name, base, params, outputs, mach, alt, samples, seed, source, dens)
    # every parameter, alone at its first value, must give a case the schema accepts: an
    # unknown key path is an error of the sweep file, not of each sample
    first = sweep.design()[0] if sweep.n_samples else {}
    for i, q in enumerate(params):
        if q.path in CONDITION_PATHS:
            continue
        dd, _, _ = sweep.case_dict({q.path: first[q.path]})
        try:
            _sample_case(dd)
        except CaseError as exc:
            msg = str(exc)
            if "is not a known key" in msg:
                raise SweepError(f"parameter[{i}].path {q.path!r} is not a case-file key: "
                                 f"{msg}") from None
    return sweep


def _sample_case(d: dict):
    """:func:`~asekit.case.case_from_dict` of a sample's dict without repeating the base
    case's :class:`~asekit.aero.methods.TransonicWarning` (given once, when the sweep file is
    read) for every sample."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        return case_from_dict(d)


def _check_condition(where: str, path: str, v: float, method: str = "dlm") -> None:
    """The analysed Mach must lie in the Mach range of the base case's ``aero.method``
    (:func:`asekit.aero.methods.resolve_method`), the altitude in the 1976 standard atmosphere
    (:data:`asekit.atmosphere.MIN_ALTITUDE` to :data:`~asekit.atmosphere.MAX_ALTITUDE`, -5000
    to 47000 m), the density in (0, 100] kg/m^3; SweepError naming the sweep-file key path
    ``where`` and, for the Mach, the case key path ``aero.method``."""
    if path == "flight.mach":
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", TransonicWarning)
                resolve_method(method, v)
        except ValueError as exc:
            raise SweepError(f"{where} = {v:g} cannot be analysed with the base case's "
                             f"aero.method = {method!r} ({method_spec(method).summary}): "
                             f"{exc}") from None
    from asekit.atmosphere import MAX_ALTITUDE, MIN_ALTITUDE
    if path == "flight.altitude" and not MIN_ALTITUDE <= v <= MAX_ALTITUDE:
        raise SweepError(f"{where} must be an altitude in [{MIN_ALTITUDE:g}, {MAX_ALTITUDE:g}] m "
                         f"(the 1976 standard atmosphere's layers implemented), got {v:g}")
    if path == "flight.density" and not 0.0 < v <= 100.0:
        raise SweepError(f"{where} must be a density in (0, 100] kg/m^3, got {v:g}")


def load_sweep(path) -> Sweep:
    """Read and check a sweep file (TOML); SweepError naming the key, or FileNotFoundError."""
    path = Path(path)
    return sweep_from_dict(read_toml(path, SweepError), base_dir=path.parent, source=str(path))


# ---------------------------------------------------------------------------------------------
# AIC reuse
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class AicFactors:
    """The structure-independent aerodynamic operators of one box mesh, per Mach.

    key : what the operators depend on (box corners, k, b_ref, method, kernel, symmetry);
    k : (n_k,) reduced frequencies; b_ref : m; operators : {mach: one operator per k}, each
    with ``pressures(w) -> DeltaCp`` (the DLM: :class:`asekit.aero.dlm.AicFactor`, the LU of
    D(M, k); the Mach-box and piston methods: :class:`asekit.aero.methods.PressureMatrix`), as
    built by the method's :data:`asekit.aero.methods.AERO_METHODS` entry. A Mach missing from
    ``operators`` is computed per sample (:func:`projected_gaf`).
    """

    key: str
    k: np.ndarray
    b_ref: float
    operators: dict

    @property
    def nbytes(self) -> int:
        return sum(sum(a.nbytes for a in vars(op).values() if isinstance(a, np.ndarray))
                   for ops in self.operators.values() for op in ops)


def aero_key(case) -> str:
    """SHA-256 of what the aerodynamic operators of ``case`` depend on besides Mach: its boxes
    (corners), reduced frequencies, reference semichord, method, kernel and symmetry."""
    a = case.aero
    boxes = P.box_mesh(case)
    h = hashlib.sha256(np.ascontiguousarray(boxes.corners).tobytes())
    h.update(np.ascontiguousarray(P.reduced_frequencies(case)).tobytes())
    h.update(json.dumps([a.reference_semichord, a.kernel, a.symmetry, a.method]).encode())
    return h.hexdigest()


def _dlm_kernel(case) -> str:
    """The DLM kernel the pipeline's database uses: ``aero.kernel`` for ``aero.method = "dlm"``,
    the quartic kernel for ``"auto"`` (:func:`asekit.aero.gaf.gaf_from_box_modes`)."""
    return case.aero.kernel if case.aero.method == "dlm" else "quartic"


def _resolved(case, mach: float) -> str:
    """The method the case uses at ``mach`` (its ``aero.method``, resolved per Mach for
    ``auto``); ValueError naming ``flight.mach`` and ``aero.method`` if it cannot."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TransonicWarning)
            return resolve_method(case.aero.method, mach)
    except ValueError as exc:
        raise ValueError(f"flight.mach = {mach:g} cannot be analysed with aero.method = "
                         f"{case.aero.method!r}: {exc}") from None


def aic_factors(case, machs, n_columns: float = math.inf) -> AicFactors:
    """The operators of the case's boxes at every Mach of ``machs`` and the case's reduced
    frequencies (BLAS on one thread), for the methods whose operator is structure-independent
    and worth forming for ``n_columns`` normalwash columns (samples x modes;
    :attr:`asekit.aero.methods.AeroMethod.reuse_break_even`); the other Machs are left out
    (computed per sample)."""
    boxes = P.box_mesh(case)
    ks = P.reduced_frequencies(case)
    a = case.aero
    ops = {}
    with one_blas_thread(), warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)       # the case file was warned
        for m in sorted({float(x) for x in machs}):
            spec = AERO_METHODS[_resolved(case, m)]
            if not spec.structure_independent or n_columns < spec.reuse_break_even * boxes.n:
                continue
            ops[m] = spec.operators(boxes, m, ks, a.reference_semichord, a.symmetry == "wall",
                                    _dlm_kernel(case))
    return AicFactors(aero_key(case), ks, float(a.reference_semichord), ops)


def projected_gaf(model, case, factors: AicFactors, mach: float) -> np.ndarray:
    """Q(M, k) (n_k, n_modes, n_modes) of ``model``: from the factored operators when
    ``factors`` holds ``mach``, Q = H_lp^T diag(A) Op(M, k) (dH/dx + i k H / b) per k
    (Eqs. 2.10-2.12, the operations of :func:`asekit.aero.gaf.gaf_from_box_modes`: for the
    DLM bit-identical to a rebuilt database, for the Mach-box method equal to rounding), else
    rebuilt for this sample by :func:`~asekit.aero.gaf.gaf_from_box_modes` with the case's
    method."""
    boxes = P.box_mesh(case)
    bm = fe_spline(model, boxes)
    ops = factors.operators.get(float(mach))
    if ops is None:
        a = case.aero
        method = a.kernel if a.method == "dlm" else a.method
        _resolved(case, mach)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", TransonicWarning)
            return gaf_from_box_modes(bm, boxes, mach, factors.k, factors.b_ref,
                                      a.symmetry == "wall", method)
    n = bm.h_cp.shape[1]
    out = np.empty((factors.k.size, n, n), complex)
    for ik, kk in enumerate(factors.k):
        cp = ops[ik].pressures(bm.normalwash(kk, factors.b_ref))
        out[ik] = modal_forces(bm, cp, boxes.area)
    return out


def needed_machs(sweep: Sweep) -> set:
    """The Mach numbers the samples need operators at: their analysed Machs, and every
    ``aero.machs`` when envelope or ASE outputs are asked for."""
    machs = {sweep.mach}
    for p in sweep.parameters:
        if p.path == "flight.mach":
            machs = set(float(v) for v in p.values) if p.is_grid else set()
    if any(o in ENVELOPE_OUTPUTS or o in ASE_OUTPUTS for o in sweep.outputs):
        machs |= {float(m) for m in sweep.base["aero"]["machs"]}
    return machs


def base_factors(sweep: Sweep) -> AicFactors:
    """The operators of the base case at :func:`needed_machs` (computed once per sweep), for
    the samples x modes of the base case's modal model."""
    case = _sample_case(copy.deepcopy(sweep.base))
    n_modes = len(P.modal_model(case).frequencies_hz)
    return aic_factors(case, needed_machs(sweep), sweep.n_samples * n_modes)


# ---------------------------------------------------------------------------------------------
# one sample
# ---------------------------------------------------------------------------------------------
def _database(model, case, factors: AicFactors, machs):
    ms = np.array(sorted({float(m) for m in machs}))
    Q = np.stack([projected_gaf(model, case, factors, m) for m in ms])
    return GafDatabase(ms, factors.k, Q, factors.b_ref, model.n_rigid, {})


def evaluate(sweep: Sweep, factors: AicFactors, index: int, values: dict) -> dict:
    """The row of sample ``index`` with parameter ``values`` (key path -> value): the case is
    rebuilt from the edited dict (:func:`~asekit.case.case_from_dict`), its modes projected on
    the factored operators (or its GAFs rebuilt, :func:`projected_gaf`), p-k at the analysed
    condition (and over the case for envelope outputs, the ASE loop for aem outputs). Any
    exception gives ``status = "failed"`` and its message."""
    t0 = time.perf_counter()
    row = {c: None for c in sweep.columns()}
    row.update({"sample": int(index), "sweep_id": sweep.sweep_id(), "seed": sweep.seed})
    for k, v in values.items():
        row[k] = v
    try:
        with one_blas_thread():
            out, reused, mach, cond = _analyse(sweep, factors, values)
        row.update(out)
        row["aic_reused"] = reused
        row["status"] = "ok"
    except Exception as exc:                 # recorded in the row, never dropped
        row["status"] = "failed"
        row["error"] = f"{type(exc).__name__}: {exc}".replace("\n", " ")
        mach, cond = sweep.case_dict(values)[1:] if _safe(sweep, values) else (None, None)
    row["flight.mach"], row[sweep.condition_path] = mach, cond
    row["wall_s"] = time.perf_counter() - t0
    return row


def _safe(sweep, values):
    try:
        sweep.case_dict(values)
        return True
    except Exception:
        return False


def _condition(sweep: Sweep, value: float) -> P.FlightCondition:
    """The analysed flight condition: the standard atmosphere at the altitude, or the density
    (no speed of sound)."""
    if sweep.density is not None:
        _check_condition("flight.density", "flight.density", value)
        return P.FlightCondition(None, float(value), None)
    _check_condition("flight.altitude", "flight.altitude", value)
    atm = standard_atmosphere(value)
    return P.FlightCondition(float(value), float(atm.density), float(atm.speed_of_sound))


def bounded_minimum(items) -> tuple[float | None, float | None, float | None]:
    """The minimum of quantities each known as ("value", x), ("upper", x) (at most x),
    ("lower", x) (at least x) or (None, None) (unknown): (value, upper bound, lower bound),
    the value when it is determined (then no bounds), else the bounds that hold (None where
    none). min <= every value and upper bound; min >= the least value or lower bound unless a
    quantity is only bounded above or unknown."""
    vals = [x for k, x in items if k == "value"]
    ups = [x for k, x in items if k == "upper"]
    lows = [x for k, x in items if k == "lower"]
    above = vals + ups
    upper = float(min(above)) if above else None
    open_below = bool(ups) or any(k is None for k, _ in items)
    lower = None if open_below or not vals + lows else float(min(vals + lows))
    if upper is not None and upper == lower:
        return upper, None, None
    return None, upper, lower


_MARGIN_KEYS = (("value", "margin"), ("upper", "margin_upper_bound"),
                ("lower", "margin_lower_bound"))


def _envelope_outputs(case, fa) -> dict:
    """min_flutter_speed, envelope_margin (each the value or its bounds, from the flutter
    points and margins of the case summary, :func:`asekit.case.pipeline.flutter`) and
    matched_mach of one sample."""
    speeds = [(k, u) for _, u, k in flutter_points(list(fa.results), case.flight.velocities)]
    if any(r.unstable_at_start and "flutter" not in start_kind(r) for r in fa.results):
        speeds.append((None, None))              # divergence at the first speed: U_f unknown
    u, u_up, _ = bounded_minimum(speeds)
    margins = [next(((k, m[key]) for k, key in _MARGIN_KEYS if m[key] is not None),
                    (None, None)) for m in fa.margins]
    e, e_up, e_low = bounded_minimum(margins)
    mm = [m["matched_mach"] for m in fa.match_points if m["matched_mach"] is not None]
    return {"min_flutter_speed": u, "min_flutter_speed_upper_bound": u_up,
            "envelope_margin": e, "envelope_margin_upper_bound": e_up,
            "envelope_margin_lower_bound": e_low,
            "matched_mach": float(min(mm)) if mm else None}


def _inside(case, r, u_f: float | None, u_fl: float) -> tuple[float | None, bool]:
    """(flutter_margin, flutter_inside) at the flight speed ``u_fl`` = M a (m/s) from the p-k
    result ``r`` and its flutter speed ``u_f``; ValueError when the velocity sweep cannot
    decide: it starts unstable above M a (the instability may lie above or below M a), or it
    ends below M a without flutter."""
    u0, u_max = case.flight.velocities[0], case.flight.velocities[-1]
    if r.unstable_at_start:
        if u0 > u_fl:
            raise ValueError(f"flutter_inside: unstable at {u0:g} m/s, the first speed of "
                             f"flight.velocities, above the flight speed M a = {u_fl:g} m/s: "
                             f"start the velocity sweep lower")
        return None, True
    if u_f is not None:
        return u_f / u_fl - 1.0, bool(u_f <= u_fl)
    if u_max >= u_fl:
        return None, False
    raise ValueError(f"flutter_inside: no flutter up to {u_max:g} m/s, the end of "
                     f"flight.velocities, below the flight speed M a = {u_fl:g} "
                     f"m/s: extend the velocity sweep")


def _analyse(sweep: Sweep, factors: AicFactors, values: dict):
    d, mach, cval = sweep.case_dict(values)
    case = _sample_case(d)
    _resolved(case, mach)
    cond = _condition(sweep, cval)
    model = P.modal_model(case)
    n_modes = len(model.frequencies_hz)                 # one sample's normalwash columns
    if aero_key(case) == factors.key:
        fac, reused = factors, True
    else:
        fac, reused = aic_factors(case, needed_machs(sweep) | {mach}, n_modes), False
    if float(mach) not in fac.operators:
        fac = AicFactors(fac.key, fac.k, fac.b_ref,
                         {**fac.operators, **aic_factors(case, [mach], n_modes).operators})
    reused = reused and float(mach) in factors.operators
    out = {}
    want = set(sweep.outputs)
    f_el = model.frequencies_hz[model.n_rigid:]
    if "f1_hz" in want:
        out["f1_hz"] = float(f_el[0])
    if "f2_hz" in want:
        out["f2_hz"] = float(f_el[1]) if f_el.size > 1 else None
    if want & set(POINT_OUTPUTS) - {"f1_hz", "f2_hz"}:
        db = _database(model, case, fac, [mach])
        r = P.analyse_condition(case, db, mach, cond, model)
        f = r.flutter
        u_f = None if (f is None or r.unstable_at_start) else float(f.speed)
        u_fl = None if cond.speed_of_sound is None else float(mach) * cond.speed_of_sound
        div = divergence_speeds(model, db.Q[0, 0].real, cond.density)
        out.update({"flutter_speed": u_f,
                    "flutter_frequency": None if u_f is None else float(f.frequency_hz),
                    "flutter_mode": None if u_f is None else mode_number(f.mode, f.n_rigid),
                    "divergence_speed": float(div[0]) if div.size else None,
                    "unstable_at_start": bool(r.unstable_at_start), "flight_speed": u_fl})
        if "flutter_margin" in want or "flutter_inside" in want:
            out["flutter_margin"], out["flutter_inside"] = _inside(case, r, u_f, u_fl)
    if want & set(ENVELOPE_OUTPUTS) or want & set(ASE_OUTPUTS):
        db = _database(model, case, fac, case.aero.machs)
        if want & set(ENVELOPE_OUTPUTS):
            out.update(_envelope_outputs(case, P.flutter(case, db=db)))
        if want & set(ASE_OUTPUTS):
            a = P.ase(case, db=db)
            for t in ("AEM1", "AEM2"):
                p = t.lower()
                out[f"{p}_stable"] = bool(a.stable[t])
                out[f"{p}_max_real_pole"] = a.max_real_pole[t]
                out[f"{p}_settling_s"] = a.settling_s[t]
                out[f"{p}_steady_error"] = a.steady_error[t]
                out[f"{p}_corner_overshoot"] = max(a.corner_overshoot[t].values())
    return {k: v for k, v in out.items() if k in want}, reused, float(mach), float(cval)


# ---------------------------------------------------------------------------------------------
# the output file (journal)
# ---------------------------------------------------------------------------------------------
def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, (bool, np.bool_)):
        return "True" if v else "False"
    if isinstance(v, (float, np.floating)):
        if not math.isfinite(v):
            return "inf" if v > 0 else ("-inf" if v < 0 else "nan")
        return repr(float(v))                      # shortest round-trip repr: bit-exact
    return str(v)


def format_row(row: dict, columns) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerow([_cell(row.get(c)) for c in columns])
    return buf.getvalue()


def read_journal(path: Path, sweep: Sweep) -> dict[int, str]:
    """The finished rows of a partial output file, {sample: CSV line}. A last line cut off by
    an interruption is dropped (that sample runs again); SweepError if the file belongs to
    another sweep or has other columns."""
    cols = list(sweep.columns())
    text = path.read_text()
    if not text.strip():
        return {}
    lines = text.splitlines(keepends=True)
    header = next(csv.reader([lines[0]]))
    if header != cols:
        raise SweepError(f"{path}: its columns are not this sweep's; give another --out or "
                         f"delete the file")
    done = {}
    sid = sweep.sweep_id()
    i_s, i_id = cols.index("sample"), cols.index("sweep_id")
    for ln in lines[1:]:
        if not ln.endswith("\n"):
            continue                                  # cut off mid-write
        cells = next(csv.reader([ln]))
        if len(cells) != len(cols):
            continue
        if cells[i_id] != sid:
            raise SweepError(f"{path}: holds rows of another sweep (sweep_id {cells[i_id]}, "
                             f"this one {sid}); give another --out or delete the file")
        done[int(cells[i_s])] = ln
    return done


def read_table(path):
    """The output CSV as a pandas DataFrame (floats read back bit-exactly)."""
    pd = require("pandas", "asekit sweep (the results table)")
    df = pd.read_csv(path)
    return df


# ---------------------------------------------------------------------------------------------
# executors
# ---------------------------------------------------------------------------------------------
EXECUTORS = ("serial", "processes", "dask")
#: A sample whose worker process dies this many times while computing it (killed by a signal,
#: out of memory, a crash in compiled code) is a failed row (:class:`WorkerLost` naming it).
MAX_WORKER_DEATHS = 3
#: Worker processes replaced in one run of the "processes" executor at most; the samples not
#: computed after that are failed rows (:class:`WorkerLost`) that a resume runs again.
MAX_WORKER_RESTARTS = 12
#: s between two checks of a worker's watchdog that its parent (the sweep) is alive.
WATCHDOG_INTERVAL = 0.5


class WorkerLost(RuntimeError):
    """The process computing a sample died (killed by a signal, out of memory, a crash in
    compiled code): the error of its failed row, naming the sample."""


def _die_with_parent(parent_pid: int) -> None:
    """Make this worker process end when the sweep's process ``parent_pid`` is gone (killed
    with SIGKILL, it cannot clean up): on Linux the kernel kills it on the parent's death
    (prctl PR_SET_PDEATHSIG = SIGKILL), and on every POSIX system a daemon thread exits the
    process once it has been re-parented (os.getppid() != parent_pid, polled every
    :data:`WATCHDOG_INTERVAL` s)."""
    import signal
    import sys
    import threading
    if sys.platform.startswith("linux"):
        try:
            import ctypes
            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)           # 1 = PR_SET_PDEATHSIG
        except (OSError, AttributeError):                        # no libc prctl: the watchdog
            pass
    if os.name != "posix":
        return
    if os.getppid() != parent_pid:                    # the parent died before prctl took hold
        os._exit(1)

    def watch():
        while os.getppid() == parent_pid:
            time.sleep(WATCHDOG_INTERVAL)
        os._exit(1)

    threading.Thread(target=watch, name="asekit-sweep-watchdog", daemon=True).start()


def _worker_main(conn, sweep, factors, parent_pid: int) -> None:
    """One worker process of the "processes" executor: receives (index, values) on ``conn``,
    sends back the row (:func:`evaluate`), until None or the pipe closes. Ctrl-C is left to
    the parent, which ends its workers."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _die_with_parent(parent_pid)
    while True:
        try:
            job = conn.recv()
        except (EOFError, OSError):
            return
        if job is None:
            return
        conn.send(evaluate(sweep, factors, *job))


def connect(scheduler: str | None, workers: int | None, timeout: float = 5.0):
    """A dask.distributed Client: to ``scheduler`` (SweepError if it is not reachable within
    ``timeout`` s), else to a new LocalCluster of ``workers`` single-threaded worker processes.
    Returns (client, cluster or None)."""
    distributed = require("dask.distributed", "--executor dask")
    Client, LocalCluster = distributed.Client, distributed.LocalCluster
    if scheduler:
        try:
            return Client(scheduler, timeout=f"{timeout}s"), None
        except Exception as exc:      # refused, timed out, or not a Dask scheduler at all
            raise SweepError(f"cannot reach the Dask scheduler at {scheduler} within "
                             f"{timeout:g} s ({type(exc).__name__}: {str(exc)[:120]})") from None
    cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster), cluster


def run_sweep(sweep: Sweep, out=None, executor: str = "serial", workers: int | None = None,
              scheduler: str | None = None, client=None, progress: bool = False,
              factors: AicFactors | None = None, retry_failed: bool = True):
    """Run every sample not yet in ``out`` and return the whole table (pandas DataFrame,
    sorted by sample).

    Parameters
    ----------
    sweep : the :class:`Sweep`.
    out : output CSV path: finished rows are appended as they arrive (an interrupted sweep
        resumes from it); at the end it is rewritten sorted by sample. None: in memory.
    executor : "serial", "processes" (``workers`` local processes, default 2) or "dask"
        (``client`` if given, else ``scheduler`` address, else a LocalCluster of ``workers``).
    progress : tqdm bar.
    factors : precomputed :func:`base_factors` (else computed here, once).
    retry_failed : on resume, run the failed rows of ``out`` again (a lost worker, a sample
        stopped by :data:`MAX_WORKER_RESTARTS`; the default) or, False, keep them.

    The "processes" executor starts its workers with the ``spawn`` method: a script that calls
    it must guard its entry point with ``if __name__ == "__main__":`` (Python's multiprocessing
    rule); notebooks and ``python -m asekit sweep`` need nothing. A worker that dies is
    replaced and its sample run again (:func:`_run_processes`); the workers end with the
    process (and, on Linux, the thread) that called ``run_sweep``.
    """
    if executor not in EXECUTORS:
        raise SweepError(f"executor must be one of {', '.join(EXECUTORS)}, got {executor!r}")
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise SweepError(f"workers must be an integer >= 1, got {workers!r}")
    pd = require("pandas", "asekit sweep (the results table)")     # before any work
    cols = sweep.columns()
    design = sweep.design()
    path = None if out is None else Path(out)
    done: dict[int, str] = {}
    if path is not None and path.exists():
        done = read_journal(path, sweep)
        if retry_failed:
            i_st = cols.index("status")
            done = {i: ln for i, ln in done.items()
                    if next(csv.reader([ln]))[i_st] == "ok"}
        _rewrite(path, cols, done)                    # drops a cut-off last line
    todo = [(i, v) for i, v in enumerate(design) if i not in done]
    _log.info("sweep %s: %d samples, %d kept from %s, %d to run (%s executor)", sweep.name,
              len(design), len(done), path, len(todo), executor)
    rows_mem = dict(done)
    fh = None
    cl = cluster = None
    if todo and executor == "dask":
        cl, cluster = (client, None) if client is not None else connect(scheduler, workers)
    bar = None
    try:
        if todo:
            factors = base_factors(sweep) if factors is None else factors
        if progress:
            from tqdm.auto import tqdm
            bar = tqdm(total=len(design), initial=len(done), desc=f"sweep {sweep.name}",
                       unit="sample")
        if path is not None:
            if not path.exists():
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(",".join(cols) + "\n")
            fh = open(path, "a")

        def record(row):
            _log.debug("sweep %s: sample %s %s", sweep.name, row.get("sample"),
                       row.get("status"))
            line = format_row(row, cols)
            rows_mem[row["sample"]] = line
            if fh is not None:
                fh.write(line)
                fh.flush()
            if bar is not None:
                bar.update(1)

        if todo:
            if executor == "serial":
                for i, v in todo:
                    record(evaluate(sweep, factors, i, v))
            elif executor == "processes":
                _run_processes(sweep, factors, todo, workers or 2, record)
            else:
                _run_dask(cl, sweep, factors, todo, record)
    finally:
        if fh is not None:
            fh.close()
        if bar is not None:
            bar.close()
        if cl is not None and client is None:
            cl.close()
            if cluster is not None:
                cluster.close()
    text = ",".join(cols) + "\n" + "".join(rows_mem[i] for i in sorted(rows_mem))
    if path is not None:
        _atomic_write(path, text)
    return pd.read_csv(io.StringIO(text))


def _rewrite(path: Path, cols, done: dict):
    _atomic_write(path, ",".join(cols) + "\n" + "".join(done[i] for i in sorted(done)))


def _atomic_write(path: Path, text: str):
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def _failed_row(sweep: Sweep, index: int, values: dict, exc: BaseException) -> dict:
    row = {c: None for c in sweep.columns()}
    row.update(values)
    row.update({"sample": index, "sweep_id": sweep.sweep_id(), "seed": sweep.seed,
                "status": "failed", "error": f"{type(exc).__name__}: {exc}".replace("\n", " ")})
    return row


class _Workers:
    """The worker processes of one "processes" run: each has its own pipe, so the sample a
    dead process was computing is known exactly and only that process is replaced (the others
    keep computing; no row is lost, recomputed or duplicated)."""

    def __init__(self, sweep, factors):
        import multiprocessing as mp
        self.ctx = mp.get_context("spawn")
        self.args = (sweep, factors, os.getpid())
        self.procs: dict = {}                 # pipe -> process
        self.busy: dict = {}                  # pipe -> sample index, or None (idle)

    def start(self) -> None:
        here, there = self.ctx.Pipe()
        p = self.ctx.Process(target=_worker_main, args=(there,) + self.args, daemon=True,
                             name="asekit-sweep-worker")
        p.start()
        there.close()
        self.procs[here], self.busy[here] = p, None

    def remove(self, conn) -> int | None:
        """Forget a dead worker; the sample it was computing (None if idle)."""
        p = self.procs.pop(conn)
        p.join(1.0)
        conn.close()
        return self.busy.pop(conn)

    def close(self) -> None:
        """End every worker: idle ones are told to stop, busy ones (an interrupted sweep) are
        terminated."""
        for conn, p in self.procs.items():
            try:
                if self.busy[conn] is None:
                    conn.send(None)
                else:
                    p.terminate()
            except OSError:
                pass
        for conn, p in self.procs.items():
            p.join(5.0)
            if p.is_alive():
                p.kill()
                p.join(1.0)
            conn.close()
        self.procs.clear()
        self.busy.clear()


def _receive(workers: _Workers, conn, record) -> bool:
    """Record the row waiting on ``conn``; False if the worker is gone (EOF, a cut message)."""
    try:
        row = conn.recv()
    except Exception:                     # EOFError, OSError, a message cut by the death
        return False
    workers.busy[conn] = None
    record(row)
    return True


def _lost(sweep, i: int, values: dict, deaths: int) -> dict:
    return _failed_row(sweep, i, values, WorkerLost(
        f"sample {i}: its worker process died {deaths} times while computing it (killed by a "
        f"signal, out of memory or a crash in compiled code); the other samples are not "
        f"affected"))


def _run_processes(sweep, factors, todo, workers, record):
    """The "processes" executor: ``workers`` spawned processes, one sample each at a time. A
    process that dies is replaced and its sample run again (at most :data:`MAX_WORKER_DEATHS`
    deaths per sample, then a failed :class:`WorkerLost` row; at most
    :data:`MAX_WORKER_RESTARTS` replacements per run, then the samples left are failed rows
    that a resume runs again). Workers die with the sweep's process (:func:`_die_with_parent`).
    """
    from multiprocessing.connection import wait
    values = dict(todo)
    queue = [i for i, _ in todo]
    deaths: dict[int, int] = {}
    restarts = 0
    pool = _Workers(sweep, factors)
    try:
        for _ in range(min(workers, len(queue))):
            pool.start()
        while queue or any(i is not None for i in pool.busy.values()):
            for conn in [c for c, i in pool.busy.items() if i is None][:len(queue)]:
                i = pool.busy[conn] = queue.pop(0)
                try:
                    conn.send((i, values[i]))
                except OSError:               # died idle: its sentinel below
                    pass
            sentinels = {p.sentinel: c for c, p in pool.procs.items()}
            ready = wait(list(pool.procs) + list(sentinels))
            for conn in [c for c in ready if c in pool.procs]:
                _receive(pool, conn, record)
            for conn in [sentinels[s] for s in ready if s in sentinels]:
                while pool.busy.get(conn) is not None and conn.poll() and _receive(pool, conn,
                                                                                   record):
                    pass                      # a row sent just before the death is kept
                i = pool.remove(conn)
                if i is not None:
                    deaths[i] = deaths.get(i, 0) + 1
                    if deaths[i] >= MAX_WORKER_DEATHS:
                        record(_lost(sweep, i, values[i], deaths[i]))
                    else:
                        queue.insert(0, i)
                restarts += 1
                if restarts > MAX_WORKER_RESTARTS:
                    _give_up(sweep, queue, values, record)
                elif queue and len(pool.procs) < workers:
                    pool.start()
    finally:
        pool.close()


def _give_up(sweep, queue: list, values: dict, record) -> None:
    """After :data:`MAX_WORKER_RESTARTS`: the samples not started are failed rows (the busy
    workers finish theirs)."""
    for i in queue:
        record(_failed_row(sweep, i, values[i], WorkerLost(
            f"sample {i}: not computed: {MAX_WORKER_RESTARTS + 1} worker processes died in "
            f"this run; run the sweep again to retry")))
    queue.clear()


def _run_dask(client, sweep, factors, todo, record):
    from dask.distributed import as_completed
    # the factors and the sweep go to every worker once; tasks carry their index and values
    fac_f = client.scatter(factors, broadcast=True, hash=False)
    sw_f = client.scatter(sweep, broadcast=True, hash=False)
    futs = [client.submit(evaluate, sw_f, fac_f, i, v, key=f"sample-{sweep.sweep_id()}-{i}",
                          pure=False) for i, v in todo]
    meta = {f.key: (i, v) for f, (i, v) in zip(futs, todo)}
    for f in as_completed(futs):
        i, v = meta[f.key]
        try:
            record(f.result())
        except Exception as exc:              # KilledWorker etc.: a failed row, not a hole
            record(_failed_row(sweep, i, v, exc))
        f.release()


# ---------------------------------------------------------------------------------------------
# statistics
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Proportion:
    """An estimated probability ``p`` = k / n with its two-sided confidence interval
    [``low``, ``high``] at ``confidence``."""

    k: int
    n: int
    p: float
    low: float
    high: float
    confidence: float


def clopper_pearson(k: int, n: int, confidence: float = 0.95) -> Proportion:
    """Exact (Clopper-Pearson) binomial confidence interval of k successes in n trials:
    low = B^-1(alpha/2; k, n - k + 1), high = B^-1(1 - alpha/2; k + 1, n - k), with B^-1 the
    beta quantile (Clopper & Pearson, Biometrika 26(4), 1934, 404-413; low = 0 for k = 0,
    high = 1 for k = n). Coverage is at least ``confidence`` for every p."""
    from scipy.stats import beta
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    if isinstance(k, bool) or int(k) != k or not 0 <= k <= n:
        raise ValueError(f"k must be an integer in [0, n = {n}], got {k!r}")
    if not 0 < confidence < 1:
        raise ValueError(f"confidence must be in (0, 1), got {confidence!r}")
    k, n = int(k), int(n)
    a = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(a / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - a / 2, k + 1, n - k))
    return Proportion(k, n, k / n, lo, hi, confidence)


def _ok(table):
    if "status" not in table:
        raise ValueError("table must be a sweep table (column 'status')")
    return table[table["status"] == "ok"]


def flutter_probability(table, column: str = "flutter_inside",
                        confidence: float = 0.95) -> Proportion:
    """P(flutter inside the envelope) from the successful rows of a sweep table (``column``
    true = flutter at or below the flight speed), with its Clopper-Pearson interval. Failed
    rows are not counted (their number is ``len(table) - n``)."""
    ok = _ok(table)
    if column not in ok:
        raise ValueError(f"the table has no column {column!r} (add it to sweep.outputs)")
    vals = ok[column]
    if vals.isna().any():
        raise ValueError(f"{column} is empty in {int(vals.isna().sum())} successful rows")
    v = vals.astype(str).str.lower().map({"true": True, "false": False, "1": True, "0": False,
                                          "1.0": True, "0.0": False})
    return clopper_pearson(int(v.sum()), int(v.size), confidence)


@dataclass(frozen=True)
class Sensitivity:
    """Standardised regression coefficients of ``output`` on the inputs, ranked by |SRC|
    (``ranking``: (input, SRC) pairs), the regression's ``r2`` and the ``n`` rows used."""

    output: str
    ranking: tuple[tuple[str, float], ...]
    r2: float
    n: int


def standardised_regression_coefficients(table, inputs, output: str) -> Sensitivity:
    """SRC_j = b_j s_j / s_y of the least-squares fit y = b_0 + sum_j b_j x_j over the
    successful rows with a value of ``output`` (Saltelli et al., *Global Sensitivity Analysis:
    The Primer*, Wiley 2008, Sec. 1.2.5, Eqs. 1.6-1.8). For a linear model sum_j SRC_j^2 = R^2;
    the ranking is meaningful when R^2 is close to 1 (it is returned)."""
    ok = _ok(table)
    inputs = list(inputs)
    for c in inputs + [output]:
        if c not in ok:
            raise ValueError(f"the table has no column {c!r}")
    sub = ok[inputs + [output]].dropna()
    n = len(sub)
    if n < len(inputs) + 2:
        raise ValueError(f"need at least {len(inputs) + 2} rows with {output}, got {n}")
    X = sub[inputs].to_numpy(float)
    y = sub[output].to_numpy(float)
    sx, sy = X.std(axis=0, ddof=1), y.std(ddof=1)
    if np.any(sx == 0) or sy == 0:
        raise ValueError("an input or the output does not vary")
    Z = (X - X.mean(0)) / sx
    zy = (y - y.mean()) / sy
    src, *_ = np.linalg.lstsq(np.column_stack([np.ones(n), Z]), zy, rcond=None)
    src = src[1:]
    resid = zy - Z @ src
    r2 = float(1.0 - resid @ resid / (zy @ zy))
    order = np.argsort(-np.abs(src), kind="stable")
    return Sensitivity(output, tuple((inputs[j], float(src[j])) for j in order), r2, n)


def describe(table, column: str = "flutter_speed") -> dict:
    """Mean, standard deviation, 5 / 50 / 95 % quantiles, min, max and count of ``column``
    over the successful rows that have a value, and how many rows had none."""
    ok = _ok(table)
    v = ok[column].dropna().to_numpy(float)
    if v.size == 0:
        raise ValueError(f"no successful row has a {column}")
    q = np.quantile(v, [0.05, 0.5, 0.95])
    return {"n": int(v.size), "missing": int(len(ok) - v.size), "mean": float(v.mean()),
            "std": float(v.std(ddof=1)) if v.size > 1 else 0.0, "p05": float(q[0]),
            "median": float(q[1]), "p95": float(q[2]), "min": float(v.min()),
            "max": float(v.max())}


def match_points(table) -> list[dict]:
    """Match points of an envelope table (columns flight.mach, flight.altitude, flutter_speed,
    flight_speed): per altitude, the Mach at which the flutter Mach U_f(M) / a equals M, by
    linear interpolation of d(M) = U_f / a - M between the grid Machs (the rule of
    :func:`asekit.case.pipeline.flutter`). ``matched_mach`` None where d keeps one sign (no
    match inside the grid: flutter-free if d > 0 throughout)."""
    ok = _ok(table)
    for c in ("flight.mach", "flight.altitude", "flutter_speed", "flight_speed"):
        if c not in ok:
            raise ValueError(f"the table has no column {c!r}")
    out = []
    for h, g in ok.groupby("flight.altitude", sort=True):
        g = g.dropna(subset=["flutter_speed"]).sort_values("flight.mach")
        if "unstable_at_start" in g:
            g = g[~g["unstable_at_start"].astype(bool)]
        m = g["flight.mach"].to_numpy(float)
        a = g["flight_speed"].to_numpy(float) / m
        d = g["flutter_speed"].to_numpy(float) / a - m
        mm = None
        for i in range(len(m) - 1):
            if d[i] == 0 or d[i] * d[i + 1] < 0:
                mm = float(m[i] + (m[i + 1] - m[i]) * d[i] / (d[i] - d[i + 1]))
                break
        speed = None if mm is None else float(mm * np.interp(mm, m, a))
        out.append({"altitude_m": float(h), "matched_mach": mm, "matched_speed_ms": speed,
                    "all_above": bool(mm is None and len(d) and np.all(d > 0))})
    return out
