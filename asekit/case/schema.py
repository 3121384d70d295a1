"""The case file: a declarative model of one flat all-movable surface or plate wing (TOML).

A case is a frozen :class:`Case` of small frozen specs. :func:`load_case` reads a TOML file (or
:func:`case_from_dict` a dict) and checks every key: unknown keys are errors, and every error
names the key path and the valid range, e.g. ``panel[1].tip_chord must be > 0 m, got -0.1``.
The format is documented in ``docs/case-format.md``; ``data/cases/`` holds worked examples.

SI units throughout the file, except keys whose name says otherwise (``fibre_angle_deg``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from asekit.aero.hmatrix import SOLVERS
from asekit.aero.methods import METHODS, resolve_method
from asekit.aeroelastic.methods import FLUTTER_METHODS
from asekit.atmosphere import MAX_ALTITUDE, MIN_ALTITUDE
from asekit.case.imported import ImportedModel
from asekit.case.resources import pk_problem, resource_problem
from asekit.geometry import (
    Material,
    OrthotropicMaterial,
    Planform,
    Thickness,
    ThicknessTable,
    chordwise_profile,
)
from asekit.rfa.methods import RFA_FITS
from asekit.structure.mesh import Grading, Stations, check_stations, station_array
from asekit.structure.supports import SUPPORTS
from asekit.util.validate import read_toml


class CaseError(ValueError):
    """A case file or case definition that cannot be analysed; the message names the key."""


class SolverError(RuntimeError):
    """A numerical failure (ARPACK, SuperLU, LinAlgError, out of memory) of a case that passed
    the loader's checks, raised at the door of :mod:`asekit.case.pipeline`: the message names
    the step that failed, the solver's own message and what to change in the case."""


#: Largest leading- or trailing-edge sweep (deg) of a panel: beyond it the plate elements'
#: smallest angle (90 deg - the sweep) is below 5 deg and the plate's rigid-body modes carry
#: strain energy (the planform is all but folded over itself).
MAX_EDGE_SWEEP_DEG = 85.0
#: Largest estimated sparse LU factor (bytes) of the structural eigenproblem (K - sigma M, one
#: per modal model): refused by the loader before SuperLU runs out of memory.
MAX_STRUCTURAL_BYTES = 2 * 2 ** 30
#: Ranges of the engineering materials (Pa for moduli, kg/m^3 for density): foams and soft
#: elastomers (10 kPa, 1 kg/m^3) to ten times diamond's modulus and four times osmium's density.
#: Values many orders of magnitude outside are typing errors (and make ARPACK fail).
MODULUS_RANGE = (1e4, 1e13)
DENSITY_RANGE = (1.0, 1e5)


def structural_factor_bytes(n_dof: int) -> float:
    """Estimated memory (bytes) of the sparse LU factor of K - sigma M for ``n_dof`` plate
    degrees of freedom: nnz(L + U) = 10.4 n_dof^1.294 entries of 12 bytes (value and row
    index), the fit of SuperLU's MMD_AT_PLUS_A fill on square plate meshes from 20 x 20 to
    160 x 160 elements (1260 to 77280 dof, within 3 %; measured for issue 22)."""
    return 12.0 * 10.4 * float(n_dof) ** 1.294


def _max_dof(max_bytes: float) -> int:
    """The largest n_dof whose :func:`structural_factor_bytes` fits in ``max_bytes``."""
    return int((max_bytes / (12.0 * 10.4)) ** (1.0 / 1.294))


# ---------------------------------------------------------------------------------------------
# the specs
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class PanelSpec:
    """One flat trapezoidal panel: its planform (m) and its structural mesh (elements chordwise
    ``n_chord`` and spanwise ``n_span``). Panels are joined spanwise in order.

    ``chord_spacing`` / ``span_spacing``: where the nodes sit along the chord / span, None for
    equal spacing, a :class:`~asekit.structure.mesh.Stations` (explicit fractions, keys
    ``chord_stations`` / ``span_stations``) or a :class:`~asekit.structure.mesh.Grading`
    (clustered toward a fraction, keys ``chord_grading`` / ``span_grading``). The chord spacing
    is the same on every panel (a conforming mesh)."""

    planform: Planform
    n_chord: int
    n_span: int
    chord_spacing: Stations | Grading | None = None
    span_spacing: Stations | Grading | None = None


@dataclass(frozen=True)
class SupportSpec:
    """How the surface is held; ``kind`` is a key of :data:`asekit.structure.supports.SUPPORTS`
    (which reads the kind's keys and builds its structure), the other fields are the kinds' keys.

    Attributes
    ----------
    kind : ``"clamped_root"`` (every DOF of the root-chord nodes fixed), ``"edges"`` (``edges``:
        the condition -- clamped, simply_supported, sliding or free -- of the root, tip, leading
        and trailing edges, e.g. for panel flutter) or ``"shaft"`` (the
        thesis's pitch shaft: ``axis_point`` (x, y) m on the root chord, ``torsional_stiffness``
        N m/rad of the actuator-fin connection, optional ``bending_stiffness`` N m/rad about the
        chordwise axis, ``model`` "FN2" (fictitious mass: rigid pitch mode + elastic modes) or
        "FN1" (spring to ground), ``radius`` None for the single-node shaft or the radius (m) of
        a rigid shaft region, ``fictitious_inertia_factor``), or ``"imported"`` (the
        constraints, rigid links and springs of ``Case.structure``, e.g. a deck's SPC / RBE2 /
        CELAS, applied as they are; not a case-file kind). ``"partial"`` (nodes at listed
        points and on parts of the edges, clamped, pinned or on springs) keeps its keys in
        ``options`` (:mod:`asekit.structure.supports`).
    options : the keys of any other kind, as sorted (key, value) pairs (values hashable).
    """

    kind: str = "clamped_root"
    axis_point: tuple[float, float] | None = None
    torsional_stiffness: float | None = None
    bending_stiffness: float | None = None
    model: str = "FN2"
    radius: float | None = None
    fictitious_inertia_factor: float = 1.0e6
    edges: tuple[tuple[str, str], ...] | None = None
    options: tuple[tuple[str, object], ...] = ()

    def option(self, name: str, default=None):
        """The value of a kind's own key that has no field here (``options``, set by a kind
        registered in :data:`asekit.structure.supports.SUPPORTS` without touching this
        class), or ``default``."""
        return dict(self.options).get(name, default)


@dataclass(frozen=True)
class PointMass:
    """A concentrated mass at ``position`` (x, y) m: ``mass`` kg, ``inertia`` (I_xx, I_yy) kg m^2."""

    position: tuple[float, float]
    mass: float
    inertia: tuple[float, float] = (0.0, 0.0)


@dataclass(frozen=True)
class ControlSurfaceSpec:
    """A hinged control surface (``[[control_surface]]``, issue 25) on panel ``panel``
    (0-based): its hinge line at chord fractions ``hinge_chord_fraction`` = (inboard, outboard)
    of the panel's local chord, between the span fractions ``span_fraction`` = (start, end) of
    the panel; ``kind`` "rigid" (a rigid surface rotating about its hinge, as Nastran's
    AESURF) or "elastic" (the plate region released along its hinge,
    :mod:`asekit.structure.hinge`); ``hinge_stiffness`` N m/rad and ``hinge_damping`` N m s/rad of the hinge;
    ``mass_balance``: ((x, y) m, mass kg) pairs fixed to the surface
    (:mod:`asekit.aeroelastic.control_surface`); ``freeplay_deg`` the half-width (deg) of a
    freeplay gap in the hinge spring (0: none; :mod:`asekit.aeroelastic.hinge_freeplay`)."""

    name: str
    panel: int
    hinge_chord_fraction: tuple[float, float]
    span_fraction: tuple[float, float] = (0.0, 1.0)
    kind: str = "rigid"
    hinge_stiffness: float = 0.0
    hinge_damping: float = 0.0
    mass_balance: tuple[tuple[tuple[float, float], float], ...] = ()
    actuator: SurfaceActuatorSpec | None = None
    freeplay_deg: float = 0.0          # hinge freeplay half-width (deg), 0: none
    linked_to: str = ""                # AELINK: the name of the surface this one is geared to
    gear_ratio: float = 0.0            # delta_this = gear_ratio delta_linked_to (with linked_to)


@dataclass(frozen=True)
class SurfaceActuatorSpec:
    """The servo-actuator on a control surface's hinge (``[control_surface.actuator]``,
    issue 25; :mod:`asekit.ase.flap`): the ASE loop's flight condition, airspeed ``speed``
    (m/s) at ``mach`` (the GAFs' Mach number, within aero.machs) and ``altitude`` (m), and the
    step command ``step_deg`` (deg). The motor, transmission and PD gains are asekit's
    defaults (thesis Tables 12 and 17: the Faulhaber drive and System 3)."""

    speed: float
    mach: float = 0.0
    altitude: float = 0.0
    step_deg: float = 1.0


@dataclass(frozen=True)
class DampingSpec:
    """Damping of the elastic modes (docs/conventions.md): ``modal_damping_ratio`` zeta (viscous,
    C_ii = 2 zeta omega_i M_ii; one value or one per elastic mode) or ``structural_g``
    (structural damping g of K (1 + i g), applied as its viscous equivalent at each mode's
    natural frequency, zeta = g / 2); both None = undamped (the thesis)."""

    modal_damping_ratio: float | tuple[float, ...] | None = None
    structural_g: float | tuple[float, ...] | None = None


@dataclass(frozen=True)
class ModesSpec:
    """Elastic modes kept: the first ``count`` with out-of-plane motion, or all below ``f_max``
    (Hz); ``keep_rigid`` keeps the rigid pitch mode of an FN2 shaft (needed for the ASE loop)."""

    count: int | None = None
    f_max: float = 1000.0
    keep_rigid: bool = True


@dataclass(frozen=True)
class AeroSpec:
    """Unsteady aerodynamics.

    machs : GAF database Mach numbers; reduced_frequencies : k = omega b / U (None: automatic,
    15 values from 0.001 to 2 pi f_max b / u_min); reference_semichord b (m); f_max (Hz) and
    u_min (m/s) for the automatic k and the mesh rules (15 boxes per wavelength, 4 boxes per
    chord, aspect ratio < 3); boxes : per panel (n_chord, n_span), or None for automatic from
    the mesh rules; kernel "quartic" | "parabolic"; symmetry "none" | "wall" (a reflection plane
    at the root); method: a key of :data:`asekit.aero.methods.AERO_METHODS` ("dlm" doublet
    lattice M < 1, "supersonic" Mach boxes M > 1, "piston" M > 1, "auto" by Mach), each Mach of
    ``machs`` inside its range; "tsd" the time-linearised transonic small disturbance,
    0 < M < 1.3 with the gap, which needs ``section`` = (shape, thickness_ratio) (``aero.section``,
    "biconvex" only) and ``symmetry = "wall"``.
    """

    machs: tuple[float, ...]
    reference_semichord: float
    reduced_frequencies: tuple[float, ...] | None = None
    f_max: float = 1000.0
    u_min: float = 100.0
    boxes: tuple[tuple[int, int], ...] | None = None
    kernel: str = "quartic"
    symmetry: str = "none"
    method: str = "dlm"
    #: the DLM solve of the GAFs (:data:`asekit.aero.hmatrix.SOLVERS`): "dense" LU (default),
    #: "hmatrix" (compressed matrix + GMRES, GAFs within 1e-6 relative) or "auto" (by size)
    solver: str = "dense"
    # issue 29 (tsdcase): the aerofoil section of method "tsd", (shape, thickness_ratio)
    section: tuple[str, float] | None = None


@dataclass(frozen=True)
class FlightSpec:
    """Flight conditions: ``altitudes`` (m, 1976 standard atmosphere) or explicit
    ``densities`` (kg/m^3; then ``speeds_of_sound`` m/s may be given for match points);
    the p-k velocity sweep ``velocities`` (m/s, ascending); the envelope ``envelope_mach``
    (min, max) and ``envelope_altitude`` (min, max) m for match points and flutter margins."""

    velocities: tuple[float, ...]
    altitudes: tuple[float, ...] | None = None
    densities: tuple[float, ...] | None = None
    speeds_of_sound: tuple[float, ...] | None = None
    envelope_mach: tuple[float, float] | None = None
    envelope_altitude: tuple[float, float] | None = None


#: The actuator keys of a case file, each None (the default of :class:`asekit.servo.actuator.DCMotor`,
#: :class:`asekit.servo.actuator.Transmission`, the thesis's System 3 and power limits) unless given.
MOTOR_KEYS = ("resistance", "inductance", "torque_constant", "back_emf_constant",
              "rotor_inertia", "viscous_damping")
TRANSMISSION_KEYS = {"ratio": "ratio", "efficiency": "efficiency",
                     "transmission_inertia": "inertia"}


@dataclass(frozen=True)
class ActuatorSpec:
    """The servo-actuator (thesis Ch. 4-5): DC motor, transmission, PD controller
    K_c (K_P + K_D s), power limits, and the flight condition of the ASE analysis. A value left
    None takes asekit's default: the Faulhaber 2642 drive of :class:`asekit.servo.actuator.DCMotor` and
    :class:`asekit.servo.actuator.Transmission` (thesis Table 12), System 3 (Table 17), 24 V / 10 A
    (Table 16)."""

    resistance: float | None = None
    inductance: float | None = None
    torque_constant: float | None = None
    back_emf_constant: float | None = None
    rotor_inertia: float | None = None
    viscous_damping: float | None = None
    ratio: float | None = None
    efficiency: float | None = None
    transmission_inertia: float | None = None
    k_c: float | None = None
    k_p: float | None = None
    k_d: float | None = None
    supply_voltage: float | None = None
    current_limit: float | None = None
    mach: float = 0.5
    altitude: float = 0.0
    step_deg: float = 1.0


@dataclass(frozen=True)
class GustProfile:
    """A user-given gust velocity history (``gust.profile``, a CSV file with the columns
    ``time_s`` and ``velocity_ms``): ``name`` the file's name, ``time`` (s, strictly ascending)
    and ``velocity`` (m/s, true airspeed, upward > 0) at the reference station x0."""

    name: str
    time: tuple[float, ...]
    velocity: tuple[float, ...]


#: Limits of a gust profile file: rows, time (s) and |velocity| (m/s).
PROFILE_MAX_ROWS = 200000
PROFILE_MAX_TIME = 600.0
PROFILE_MAX_VELOCITY = 100.0


def _profile_cell(where: str, col: str, text, low: float, high: float, unit: str) -> float:
    try:
        v = float(text)
    except (TypeError, ValueError):
        v = math.nan
    if not (math.isfinite(v) and low <= v <= high):
        raise CaseError(f"{where} column {col} must be a number within [{low:g}, {high:g}] "
                        f"{unit}, got {text!r}")
    return v


def read_gust_profile(path, key: str = "gust.profile") -> GustProfile:
    """Read and check a gust profile CSV (columns ``time_s``, ``velocity_ms``, a header row).

    Parameters
    ----------
    path : str or Path of the CSV file; key : the case-file key named in errors.

    Returns
    -------
    GustProfile
        Every row checked: time in [0, 600] s, strictly ascending, velocity in [-100, 100] m/s,
        2 to 200000 rows.

    Raises
    ------
    CaseError
        Naming the key, the file, the row (1 = the first data row) and the column.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "g.csv"
    >>> _ = f.write_text("time_s,velocity_ms\\n0,0\\n0.1,2.5\\n0.2,0\\n")
    >>> read_gust_profile(f).velocity
    (0.0, 2.5, 0.0)
    """
    import csv

    path = Path(path)
    name = path.name
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError) as e:
        raise CaseError(f"{key}: cannot read {str(path)!r}: {e}") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    head = [c.strip() for c in rows[0]] if rows else []
    if "time_s" not in head or "velocity_ms" not in head:
        raise CaseError(f"{key} {name}: the first row must name the columns time_s and "
                        f"velocity_ms, got {head}")
    it, iv = head.index("time_s"), head.index("velocity_ms")
    data = rows[1:]
    if not 2 <= len(data) <= PROFILE_MAX_ROWS:
        raise CaseError(f"{key} {name}: must hold 2 to {PROFILE_MAX_ROWS} data rows, "
                        f"got {len(data)}")
    t, w = [], []
    for i, r in enumerate(data, start=1):
        where = f"{key} {name} row {i}"
        if len(r) != len(head):
            raise CaseError(f"{where} must hold {len(head)} values, got {len(r)}")
        t.append(_profile_cell(where, "time_s", r[it].strip(), 0.0, PROFILE_MAX_TIME, "s"))
        w.append(_profile_cell(where, "velocity_ms", r[iv].strip(), -PROFILE_MAX_VELOCITY,
                               PROFILE_MAX_VELOCITY, "m/s"))
        if i > 1 and t[-1] <= t[-2]:
            raise CaseError(f"{where} column time_s must exceed the previous row's "
                            f"{t[-2]:g} s (times strictly ascending), got {t[-1]:g}")
    return GustProfile(name, tuple(t), tuple(w))


@dataclass(frozen=True)
class GustStation:
    """A load monitoring station (``[[gust.station]]``): ``name``; the cut at the spanwise
    fraction ``eta`` of the surface (0 the root, < 1); ``axis`` the chord fraction at the cut
    of the torsion axis (parallel to y; default 0.25, the quarter chord)."""

    name: str
    eta: float
    axis: float = 0.25


#: At most this many ``[[gust.station]]`` tables.
MAX_STATIONS = 50


def _gust_stations(raw) -> tuple[GustStation, ...]:
    """The ``[[gust.station]]`` tables, every key checked."""
    if raw is None:
        return ()
    if not isinstance(raw, list) or not 1 <= len(raw) <= MAX_STATIONS:
        raise CaseError(f"gust.station must be an array of 1 to {MAX_STATIONS} tables "
                        f"([[gust.station]])")
    out = []
    for i, d in enumerate(raw):
        t = _Table(d, f"gust.station[{i}]")
        name = t.text("name", default="")
        if not name.strip():
            raise CaseError(f"gust.station[{i}].name must be a non-empty string, got {name!r}")
        eta = t.number("eta", required=True, low=0.0, high=1.0, low_open=False, high_open=True)
        axis = t.number("axis", default=0.25, low=0.0, high=1.0, low_open=False)
        t.done()
        out.append(GustStation(name, eta, axis))
    names = [s.name for s in out]
    if len(set(names)) != len(names):
        raise CaseError(f"gust.station[].name must be unique, got {names}")
    return tuple(out)


@dataclass(frozen=True)
class GustSpec:
    """Discrete 1-cos gusts (issue 27, :mod:`asekit.case.gust_loads`): gradient distances H (m;
    each gust 2 H long), the design gust velocity U_ds (m/s, true airspeed, upward), the flight
    condition (Mach, altitude in m; default the actuator's, else the first of aero.machs at
    0 m), the gust reference station x0 (m; default the most upstream leading edge) and the
    simulated time after the gust has passed (s); with ``[gust.turbulence]`` also continuous
    turbulence: RMS gust velocity sigma (m/s), scale length L (m, default 762 m = 2500 ft) and
    spectrum ("von_karman" or "dryden"); a user-given gust ``profile``
    (:class:`GustProfile`) and load monitoring ``stations`` (:class:`GustStation`)."""

    gradient_lengths: tuple[float, ...]
    design_velocity: float
    mach: float
    altitude: float = 0.0
    x0: float | None = None
    settle_time: float = 0.5
    turbulence_sigma: float | None = None
    scale_length: float = 762.0
    spectrum: str = "von_karman"
    profile: GustProfile | None = None
    stations: tuple[GustStation, ...] = ()


@dataclass(frozen=True)
class FlutterIndexSpec:
    """Normalisation of the flutter speed as a flutter speed index
    FSI = U_f / (b_s omega_alpha sqrt(mu)) (Yates 1987): ``semichord`` b_s (m), ``f_alpha``
    omega_alpha / 2 pi (Hz), ``mass_ratio`` mu; the frequency ratio is omega_f / omega_alpha."""

    semichord: float
    f_alpha: float
    mass_ratio: float


@dataclass(frozen=True)
class FlutterSpec:
    """How flutter is analysed (``[flutter]``): ``method``, a key of
    :data:`asekit.aeroelastic.methods.FLUTTER_METHODS` ("pk" by default, "root_locus"); ``rfa``,
    a key of :data:`asekit.rfa.methods.RFA_FITS` ("roger" by default, "minimum_state"), the
    rational function approximation of the root-locus method and the ASE loop, with ``lags``
    lag roots (4)."""

    method: str = "pk"
    rfa: str = "roger"
    lags: int = 4


@dataclass(frozen=True)
class ConvergenceSpec:
    """The discretisation-error study (``[convergence]``, :mod:`asekit.case.convergence`):
    ``enabled`` runs it with every ``analyse``; the case's meshes and ``meshes - 1`` coarser
    ones (2 or 3 meshes), each coarser by ``ratio`` per direction (element and box counts
    divided by it); ``order`` the order of convergence assumed when three meshes do not give
    one (two meshes always assume it)."""

    enabled: bool = False
    meshes: int = 3
    ratio: float = 1.5
    order: float = 1.0


@dataclass(frozen=True)
class Case:
    """A complete case: what the surface is, how it is held and analysed.

    ``structure`` : an :class:`~asekit.case.imported.ImportedModel` (e.g. a Nastran deck read by
    :func:`asekit.io.bdf.read_bdf`) whose mesh, K, M, supports and boxes the pipeline uses instead
    of ``panels`` / ``thickness`` / ``material`` / ``support`` and the automatic boxes; such a
    case has ``panels = ()``, ``thickness = material = None`` and ``support.kind =
    "imported"``. None (default): the declarative case of a case file.
    """

    name: str
    panels: tuple[PanelSpec, ...]
    thickness: Thickness | ThicknessTable
    material: Material | OrthotropicMaterial
    support: SupportSpec
    aero: AeroSpec
    flight: FlightSpec
    modes: ModesSpec = ModesSpec()
    damping: DampingSpec = DampingSpec()
    point_masses: tuple[PointMass, ...] = ()
    actuator: ActuatorSpec | None = None
    control_surfaces: tuple[ControlSurfaceSpec, ...] = ()
    flutter_index: FlutterIndexSpec | None = None
    flutter: FlutterSpec = FlutterSpec()
    convergence: ConvergenceSpec = ConvergenceSpec()
    gust: GustSpec | None = None
    reference: str = ""
    source: str = field(default="", compare=False)
    structure: ImportedModel | None = None
    beam: BeamSpec | None = None

    @classmethod
    def from_toml(cls, path) -> "Case":
        """Read and check a case file (see :func:`load_case`)."""
        return load_case(path)

    @property
    def span(self) -> float:
        """Spanwise extent (m) of the panels, or of the imported mesh."""
        if self.structure is not None:
            return float(np.ptp(self.structure.mesh.nodes[:, 1]))
        return self.panels[-1].planform.tip_le[1] - self.panels[0].planform.root_le[1]

    def fingerprint(self) -> str:
        """SHA-256 of everything that defines the case (not its name or file location); an
        imported structure enters through its content digest."""
        d = asdict(replace(self, structure=None))
        for k in ("name", "reference", "source", "convergence"):    # (convergence: how it is
            d.pop(k)                                               # studied, not what it is)
        if self.structure is not None:      # (absent otherwise: the file cases' digests stay)
            d["structure"] = self.structure.digest
        if self.gust is None:               # (absent: the digests of cases without gusts stay)
            d.pop("gust")
        if not self.control_surfaces:       # (likewise: cases without control surfaces)
            d.pop("control_surfaces")
        for cs in d.get("control_surfaces", ()):   # (and surfaces without an actuator)
            if cs.get("actuator") is None:
                cs.pop("actuator", None)
        if self.beam is None:               # (likewise: plate cases)
            d.pop("beam")
        else:                               # (likewise: beams without in_plane / point_masses)
            if d["beam"].get("in_plane") == "free":
                d["beam"].pop("in_plane")
            if not d["beam"].get("point_masses"):
                d["beam"].pop("point_masses")
            if not d["beam"].get("spline_extension"):
                d["beam"].pop("spline_extension")
        if d.get("aero") is not None and d["aero"].get("solver") == "dense":
            d["aero"].pop("solver")         # (likewise: the default dense DLM solve)
        if d.get("aero") is not None and d["aero"].get("section") is None:
            d["aero"].pop("section", None)  # (likewise: methods without a section, all but tsd)
        return hashlib.sha256(json.dumps(d, sort_keys=True, default=str).encode()).hexdigest()


# ---------------------------------------------------------------------------------------------
# reading and checking
# ---------------------------------------------------------------------------------------------
class _Table:
    """A TOML table being read: typed getters that name the key path, then :meth:`done` refuses
    the keys nobody asked for. ``error`` is the exception class raised (:class:`CaseError` for
    case files; the sweep file passes its :class:`asekit.sweep.SweepError`)."""

    def __init__(self, data, path: str, error: type[ValueError] = CaseError):
        if not isinstance(data, dict):
            raise error(f"{path or 'the file'} must be a table, got {type(data).__name__}")
        self.d = data
        self.path = path
        self.used = set()
        self.error = error

    def key(self, k):
        return f"{self.path}.{k}" if self.path else k

    def has(self, k) -> bool:
        return k in self.d

    def raw(self, k, default=None, required=False):
        self.used.add(k)
        if k not in self.d:
            if required:
                raise self.error(f"{self.key(k)} is missing")
            return default
        return self.d[k]

    def number(self, k, default=None, required=False, low=None, high=None, low_open=True,
               high_open=False, unit=""):
        v = self.raw(k, default, required)
        if v is None:
            return None
        return _number(self.key(k), v, low, high, low_open, high_open, unit, self.error)

    def integer(self, k, default=None, required=False, low=1, high=100000):
        v = self.raw(k, default, required)
        if v is None:
            return None
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.error(f"{self.key(k)} must be an integer in [{low}, {high}], got {v!r}")
        if not low <= v <= high:
            raise self.error(f"{self.key(k)} must be an integer in [{low}, {high}], got {v}")
        return v

    def string(self, k, choices, default=None, required=False):
        v = self.raw(k, default, required)
        if v is None:
            return None
        if v not in choices:
            raise self.error(f"{self.key(k)} must be one of {', '.join(map(repr, choices))}, "
                             f"got {v!r}")
        return v

    def text(self, k, default=""):
        v = self.raw(k, default)
        if not isinstance(v, str):
            raise self.error(f"{self.key(k)} must be a string, got {v!r}")
        return v

    def boolean(self, k, default):
        v = self.raw(k, default)
        if not isinstance(v, bool):
            raise self.error(f"{self.key(k)} must be true or false, got {v!r}")
        return v

    def numbers(self, k, default=None, required=False, length=None, min_length=1, low=None,
                high=None, low_open=True, high_open=False, unit="", ascending=False):
        v = self.raw(k, default, required)
        if v is None:
            return None
        if isinstance(v, (int, float)) and not isinstance(v, bool) and length is None:
            v = [v]
        if not isinstance(v, (list, tuple)):
            raise self.error(f"{self.key(k)} must be a list of numbers, got {v!r}")
        if length is not None and len(v) != length:
            raise self.error(f"{self.key(k)} must hold {length} numbers, got {len(v)}")
        if len(v) < min_length:
            raise self.error(f"{self.key(k)} must hold at least {min_length} number(s), "
                             f"got {len(v)}")
        out = tuple(_number(f"{self.key(k)}[{i}]", x, low, high, low_open, high_open, unit,
                            self.error) for i, x in enumerate(v))
        if ascending and any(b <= a for a, b in zip(out, out[1:])):
            raise self.error(f"{self.key(k)} must be strictly ascending, got {list(out)}")
        return out

    def table(self, k, required=False):
        v = self.raw(k, None, required)
        return None if v is None else _Table(v, self.key(k), self.error)

    def done(self):
        extra = sorted(set(self.d) - self.used)
        if extra:
            raise self.error(f"{self.key(extra[0])} is not a known key"
                             + (f" (also {', '.join(extra[1:])})" if len(extra) > 1 else ""))


def _number(path, v, low, high, low_open, high_open, unit, error=CaseError):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise error(f"{path} must be a finite number{_range(low, high, low_open, high_open, unit)}"
                    f", got {v!r}")
    u = f" {unit}" if unit else ""
    if low is not None and (v <= low if low_open else v < low):
        raise error(f"{path} must be {'>' if low_open else '>='} {low:g}{u}, got {v:g}")
    if high is not None and (v >= high if high_open else v > high):
        raise error(f"{path} must be {'<' if high_open else '<='} {high:g}{u}, got {v:g}")
    return float(v)


def _range(low, high, low_open, high_open, unit):
    parts = []
    if low is not None:
        parts.append(f"{'>' if low_open else '>='} {low:g}")
    if high is not None:
        parts.append(f"{'<' if high_open else '<='} {high:g}")
    return (" " + " and ".join(parts) + (f" {unit}" if unit else "")) if parts else ""


def _wrap(path, fn, *args, **kw):
    """Call a physics constructor and re-raise its ValueError under the case key path."""
    try:
        return fn(*args, **kw)
    except CaseError:
        raise
    except ValueError as exc:
        raise CaseError(f"{path}: {exc}") from None


def _grading(t: _Table) -> Grading:
    """A ``{toward, ratio, width, ramp}`` table (:class:`~asekit.structure.mesh.Grading`)."""
    toward = t.numbers("toward", required=True, low=0.0, high=1.0, low_open=False,
                       ascending=True)
    ratio = t.number("ratio", required=True, low=1.0, high=1e6, low_open=False)
    width = t.number("width", 0.0, low=0.0, high=1.0, low_open=False, high_open=True)
    ramp = t.number("ramp", None, low=0.0, high=1.0)
    t.done()
    return Grading(toward, ratio, width, ramp)


def _spacing(t: _Table, direction: str, count: str):
    """``<direction>_stations`` (a list of fractions) or ``<direction>_grading`` (a table), not
    both; None when neither is given."""
    sk, gk = f"{direction}_stations", f"{direction}_grading"
    if t.has(sk) and t.has(gk):
        raise CaseError(f"{t.key(sk)} and {t.key(gk)} both given: give one of them")
    if t.has(sk):
        st = t.numbers(sk, min_length=2, low=0.0, high=1.0, low_open=False)
        try:
            return Stations(tuple(check_stations(t.key(sk), st)))
        except ValueError as exc:
            raise CaseError(str(exc)) from None
    g = t.table(gk)
    if g is None:
        return None
    if t.d.get(count) is None:
        raise CaseError(f"{t.key(count)} is missing: {t.key(gk)} needs the element count")
    return _grading(g)


def _panel_mesh(t: _Table):
    """(n_chord, n_span, chord_spacing, span_spacing) of one panel: the counts default to the
    element counts of explicit station lists; each spacing is checked against its count."""
    chord, span = _spacing(t, "chord", "n_chord"), _spacing(t, "span", "n_span")
    counts = []
    for k, sp in (("n_chord", chord), ("n_span", span)):
        given = isinstance(sp, Stations) and not t.has(k)
        counts.append(t.integer(k, sp.n_elements if given else None, required=not given,
                                high=2000))
    for k, sp, n in (("chord", chord, counts[0]), ("span", span, counts[1])):
        if sp is not None:
            key = t.key(f"{k}_stations" if isinstance(sp, Stations) else f"{k}_grading")
            try:
                station_array(sp, n, key)
            except ValueError as exc:
                raise CaseError(f"{exc} ({t.key(f'n_{k}')} = {n})") from None
    return counts[0], counts[1], chord, span


def _panels(raw, structural: bool = True) -> tuple[PanelSpec, ...]:
    if raw is None:
        raise CaseError("panel is missing: give at least one [[panel]] table")
    if not isinstance(raw, list) or not raw:
        raise CaseError("panel must be an array of tables ([[panel]]) with at least one panel")
    panels = []
    for i, d in enumerate(raw):
        t = _Table(d, f"panel[{i}]")
        rle = t.numbers("root_leading_edge", required=True, length=2, unit="m")
        tle = t.numbers("tip_leading_edge", required=True, length=2, unit="m")
        rc = t.number("root_chord", required=True, low=0.0, high=1e4, unit="m")
        tc = t.number("tip_chord", required=True, low=0.0, high=1e4, unit="m")
        # a beam case's panels are the aerodynamic planform only: no structural mesh keys
        nc, ns, chord, span = _panel_mesh(t) if structural else (1, 1, None, None)
        t.done()
        if tle[1] <= rle[1]:
            raise CaseError(f"panel[{i}].tip_leading_edge y ({tle[1]:g} m) must exceed "
                            f"root_leading_edge y ({rle[1]:g} m): the planform is crossed or "
                            f"has zero span")
        if i:
            _check_joint(i, panels, rle, rc, nc)
            chord = _joint_chord_spacing(i, panels[0].chord_spacing, chord)
        _check_sweep(i, rle, rc, tle, tc)
        panels.append(PanelSpec(_wrap(f"panel[{i}]", Planform, rle, rc, tle, tc), nc, ns,
                                chord, span))
    return tuple(panels)


def _check_joint(i, panels, rle, rc, nc):
    """Panel ``i``'s root must be panel ``i - 1``'s tip, with panel 0's chordwise count."""
    prev = panels[-1].planform
    if not (np.allclose(prev.tip_le, rle, atol=1e-9) and math.isclose(prev.tip_chord, rc,
                                                                      rel_tol=1e-9)):
        raise CaseError(f"panel[{i}] root (leading edge {list(rle)}, chord {rc:g} m) must "
                        f"coincide with panel[{i - 1}] tip (leading edge "
                        f"{list(prev.tip_le)}, chord {prev.tip_chord:g} m)")
    if nc != panels[0].n_chord:
        raise CaseError(f"panel[{i}].n_chord must equal panel[0].n_chord = "
                        f"{panels[0].n_chord} (a conforming structural mesh), got {nc}")


def _joint_chord_spacing(i, first, mine):
    """Panel ``i``'s chord spacing: panel 0's (the chordwise nodes are shared); a panel may
    omit it or repeat it, not give another."""
    if mine is not None and mine != first:
        raise CaseError(f"panel[{i}] chord spacing {mine} must equal panel[0]'s "
                        f"({first or 'equal spacing'}): the panels share their chordwise nodes "
                        f"(a conforming structural mesh); give it on panel[0] only")
    return first


def _check_sweep(i, rle, rc, tle, tc) -> None:
    """Refuse a panel whose leading or trailing edge is swept beyond :data:`MAX_EDGE_SWEEP_DEG`
    (its elements' smallest angle 90 deg - sweep: a planform folded onto itself)."""
    span = tle[1] - rle[1]
    for edge, dx, keys in (("leading", tle[0] - rle[0], "tip_leading_edge x"),
                           ("trailing", tle[0] + tc - rle[0] - rc,
                            "tip_leading_edge x + tip_chord")):
        sweep = math.degrees(math.atan2(abs(dx), span))
        if sweep > MAX_EDGE_SWEEP_DEG:
            raise CaseError(f"panel[{i}]: the {edge} edge is swept {sweep:.2f} deg ({keys} moves "
                            f"{dx:g} m over a span of {span:g} m), the planform folds onto "
                            f"itself; the edge sweeps must be within +-{MAX_EDGE_SWEEP_DEG:g} "
                            f"deg (|dx| <= {span * math.tan(math.radians(MAX_EDGE_SWEEP_DEG)):.4g}"
                            f" m)")


def _thickness_table(t: _Table) -> ThicknessTable:
    """``[thickness] kind = "table"``: ``x_over_c`` and ``eta`` grids and ``values_m`` (one row
    per eta of one value per x_over_c, m), bilinear over the panel (:class:`ThicknessTable`)."""
    xc = t.numbers("x_over_c", required=True, min_length=2, low=0.0, high=1.0, low_open=False,
                   ascending=True)
    eta = t.numbers("eta", required=True, min_length=2, low=0.0, high=1.0, low_open=False,
                    ascending=True)
    for k, g in (("x_over_c", xc), ("eta", eta)):
        if g[0] != 0.0 or g[-1] != 1.0:
            raise CaseError(f"{t.key(k)} must start at 0 and end at 1 (the whole panel), "
                            f"got {list(g)}")
    rows = t.raw("values_m", required=True)
    if not isinstance(rows, list) or len(rows) != len(eta):
        raise CaseError(f"{t.key('values_m')} must be a list of {len(eta)} rows (one per eta), "
                        f"got {rows!r}")
    values = []
    for i, row in enumerate(rows):
        if not isinstance(row, list) or len(row) != len(xc):
            raise CaseError(f"{t.key('values_m')}[{i}] must hold {len(xc)} numbers (one per "
                            f"x_over_c), got {row!r}")
        values.append(tuple(_number(f"{t.key('values_m')}[{i}][{j}]", v, 0.0, 100.0, False,
                                    False, "m") for j, v in enumerate(row)))
    t.done()
    try:                                   # a cell of zeros (no plate there) names values_m
        return ThicknessTable(xc, eta, tuple(values))
    except ValueError as exc:
        raise CaseError(f"{t.path}.{exc}") from None


def _thickness(t: _Table) -> Thickness | ThicknessTable:
    if t.string("kind", ("linear", "table"), default="linear") == "table":
        return _thickness_table(t)
    root = t.number("root", required=True, low=0.0, high=100.0, unit="m")
    tip = t.number("tip", required=True, low=0.0, high=100.0, unit="m")
    prof = t.raw("profile", "flat")
    t.done()
    return Thickness(root, tip, _wrap("thickness.profile", chordwise_profile, prof))


def _material(t: _Table):
    kind = t.string("kind", ("isotropic", "orthotropic"), default="isotropic")
    name = t.text("name", "")
    big = 1e15
    if kind == "isotropic":
        e = t.number("youngs_modulus", required=True, low=0.0, high=big, unit="Pa")
        nu = t.number("poisson_ratio", required=True, low=-1.0, high=0.5, high_open=True)
        rho = t.number("density", required=True, low=0.0, high=1e6, unit="kg/m^3")
        t.done()
        _engineering("material", {"youngs_modulus": e}, rho)
        return _wrap("material", Material, e, nu, rho, name)
    vals = {k: t.number(k, required=True, low=0.0, high=big, unit="Pa") for k in ("e1", "e2", "g12")}
    nu12 = t.number("nu12", required=True, low=-10.0, high=10.0)
    rho = t.number("density", required=True, low=0.0, high=1e6, unit="kg/m^3")
    g13 = t.number("g13", low=0.0, high=big, unit="Pa")
    g23 = t.number("g23", low=0.0, high=big, unit="Pa")
    angle = t.number("fibre_angle_deg", default=0.0, low=-360.0, high=360.0, low_open=False,
                     unit="deg")
    t.done()
    _engineering("material", dict(vals, g13=g13, g23=g23), rho)
    return _wrap("material", OrthotropicMaterial, vals["e1"], vals["e2"], vals["g12"], nu12, rho,
                 g13, g23, math.radians(angle), name)


def _engineering(path: str, moduli: dict, density: float) -> None:
    """Refuse moduli (Pa) and a density (kg/m^3) outside :data:`MODULUS_RANGE` /
    :data:`DENSITY_RANGE` (engineering materials), naming the key."""
    for k, v in list(moduli.items()) + [("density", density)]:
        lo, hi, unit = (DENSITY_RANGE + ("kg/m^3",) if k == "density"
                        else MODULUS_RANGE + ("Pa",))
        if v is not None and not lo <= v <= hi:
            raise CaseError(f"{path}.{k} = {v:g} {unit} is outside the range of engineering "
                            f"materials [{lo:g}, {hi:g}] {unit} (SI units: Pa and kg/m^3)")


def _support(t: _Table, panels) -> SupportSpec:
    """The ``[support]`` table: its ``kind`` picks a :class:`asekit.structure.supports.SupportKind`
    of :data:`asekit.structure.supports.SUPPORTS`, which reads the kind's own keys."""
    kind = t.string("kind", tuple(SUPPORTS), required=True)
    try:
        fields = SUPPORTS[kind].parse(t, panels[0].planform)
    except CaseError:
        raise
    except ValueError as exc:             # the kind's own checks name their key path
        raise CaseError(str(exc)) from None
    _check_support_points(fields.get("points") or (), panels)
    known = {f.name for f in dataclasses.fields(SupportSpec)} - {"kind", "options"}
    extra = tuple(sorted((k, v) for k, v in fields.items() if k not in known))
    return SupportSpec(kind=kind, options=extra,
                       **{k: v for k, v in fields.items() if k in known})


def _check_support_points(points, panels) -> None:
    """Refuse a support point (``support.points``, (x, y) m) that is off the plate, naming it
    and the plate's x range at its y (or the plate's y range)."""
    y0, y1 = panels[0].planform.root_le[1], panels[-1].planform.tip_le[1]
    for i, (x, y) in enumerate(points):
        if _on_planform(panels, x, y):
            continue
        if not y0 <= y <= y1:
            where = f"y must lie in [{y0:g}, {y1:g}] m"
        else:
            pf = next(p.planform for p in panels if p.planform.root_le[1] <= y
                      <= p.planform.tip_le[1])
            e = (y - pf.root_le[1]) / pf.span
            x_le = pf.root_le[0] + e * (pf.tip_le[0] - pf.root_le[0])
            c = pf.root_chord + e * (pf.tip_chord - pf.root_chord)
            where = f"at y = {y:g} m, x must lie in [{x_le:g}, {x_le + c:g}] m"
        raise CaseError(f"support.points[{i}] = [{x:g}, {y:g}] m is off the plate: {where}")


def _on_planform(panels, x: float, y: float) -> bool:
    """Whether (x, y) lies on one of the panels (edges included, to 1e-9 of the size)."""
    for p in panels:
        pf = p.planform
        tol = 1e-9 * max(pf.span, pf.root_chord, pf.tip_chord)
        eta = (y - pf.root_le[1]) / pf.span
        if not -tol / pf.span <= eta <= 1 + tol / pf.span:
            continue
        e = min(max(eta, 0.0), 1.0)
        x_le = pf.root_le[0] + e * (pf.tip_le[0] - pf.root_le[0])
        c = pf.root_chord + e * (pf.tip_chord - pf.root_chord)
        if x_le - tol <= x <= x_le + c + tol:
            return True
    return False


def _point_masses(raw, panels=()) -> tuple[PointMass, ...]:
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise CaseError("point_mass must be an array of tables ([[point_mass]])")
    out = []
    for i, d in enumerate(raw):
        t = _Table(d, f"point_mass[{i}]")
        pos = t.numbers("position", required=True, length=2, unit="m")
        m = t.number("mass", required=True, low=0.0, high=1e9, low_open=False, unit="kg")
        inertia = t.numbers("inertia", default=[0.0, 0.0], length=2, low=0.0, low_open=False,
                            high=1e9, unit="kg m^2")
        t.done()
        if panels and not _on_planform(panels, *pos):
            c = panels[0].planform.corners.tolist() + panels[-1].planform.corners.tolist()
            lo, hi = np.min(c, axis=0), np.max(c, axis=0)
            raise CaseError(f"point_mass[{i}].position {list(pos)} m is off the planform (the "
                            f"panels span x {lo[0]:g} to {hi[0]:g} m, y {lo[1]:g} to {hi[1]:g} "
                            f"m): a point mass must lie on a panel")
        out.append(PointMass(pos, m, inertia))
    return tuple(out)


#: the kinds of control surface (``control_surface[i].kind``): "rigid" (a rigid rotation about
#: the hinge added to the locked wing's modes) or "elastic" (the plate region released along
#: the hinge, :mod:`asekit.structure.hinge`)
CONTROL_SURFACE_KINDS = ("rigid", "elastic")


def _mass_balance(t: _Table, path: str, panels) -> tuple:
    raw = t.raw("mass_balance", [])
    if not isinstance(raw, list):
        raise CaseError(f"{path}.mass_balance must be an array of tables "
                        f"([[control_surface.mass_balance]])")
    out = []
    for j, d in enumerate(raw):
        b = _Table(d, f"{path}.mass_balance[{j}]")
        pos = b.numbers("position", required=True, length=2, unit="m")
        m = b.number("mass", required=True, low=0.0, high=1e9, unit="kg")
        b.done()
        if not _on_planform(panels, *pos):
            raise CaseError(f"{b.path}.position {list(pos)} m is off the planform: a balance "
                            f"mass must lie on a panel")
        out.append((pos, m))
    return tuple(out)


def _one_control_surface(t: _Table, i: int, panels) -> ControlSurfaceSpec:
    path = f"control_surface[{i}]"
    name = t.text("name", "")
    if not name:
        raise CaseError(f"{path}.name is missing or empty")
    panel = t.integer("panel", 0, low=0, high=max(len(panels) - 1, 0))
    hinge = t.numbers("hinge_chord_fraction", required=True, length=2, low=0.0, high=1.0,
                      high_open=True)
    span = t.numbers("span_fraction", default=[0.0, 1.0], length=2, low=0.0, low_open=False,
                     high=1.0)
    if span[1] <= span[0]:
        raise CaseError(f"{path}.span_fraction must be [start, end] with 0 <= start < end "
                        f"<= 1, got {list(span)}")
    kind = t.string("kind", CONTROL_SURFACE_KINDS, default="rigid")
    linked = t.text("linked_to", "")
    gear = t.number("gear_ratio", None if linked else 0.0, required=bool(linked), low=-10.0,
                    low_open=False, high=10.0)
    if gear and not linked:
        raise CaseError(f"{path}.gear_ratio needs {path}.linked_to (the surface it is geared "
                        f"to)")
    k_h = t.number("hinge_stiffness", 0.0, required=not linked, low=0.0, low_open=False,
                   high=1e12, unit="N m/rad")
    c_h = t.number("hinge_damping", 0.0, low=0.0, low_open=False, high=1e12,
                   unit="N m s/rad")
    balance = _mass_balance(t, path, panels)
    actuator = _surface_actuator(t.table("actuator"))
    freeplay = t.number("freeplay_deg", 0.0, low=0.0, low_open=False, high=10.0, unit="deg")
    if freeplay > 0 and k_h <= 0:
        raise CaseError(f"{path}.freeplay_deg = {freeplay:g} needs {path}.hinge_stiffness > 0 "
                        "(the freeplay is in the hinge spring)")
    t.done()
    return ControlSurfaceSpec(name, panel, hinge, span, kind, k_h, c_h, balance, actuator,
                              freeplay, linked, gear)


def _surface_actuator(t: _Table | None) -> SurfaceActuatorSpec | None:
    """``[control_surface.actuator]`` (its Mach is checked against aero.machs by
    case_from_dict)."""
    if t is None:
        return None
    spec = SurfaceActuatorSpec(
        speed=t.number("speed", required=True, low=0.0, high=1e4, unit="m/s"),
        mach=t.number("mach", default=0.0, low=0.0, low_open=False),
        altitude=t.number("altitude", default=0.0, low=MIN_ALTITUDE, low_open=False,
                          high=MAX_ALTITUDE, unit="m"),
        step_deg=t.number("step_deg", default=1.0, low=0.0, high=15.0, unit="deg"))
    t.done()
    return spec


def _control_surfaces(raw, panels) -> tuple[ControlSurfaceSpec, ...]:
    """The ``[[control_surface]]`` tables (docs/case-format.md), every key checked."""
    if raw is None:
        return ()
    if not isinstance(raw, list):
        raise CaseError("control_surface must be an array of tables ([[control_surface]])")
    out = tuple(_one_control_surface(_Table(d, f"control_surface[{i}]"), i, panels)
                for i, d in enumerate(raw))
    names = [c.name for c in out]
    if len(set(names)) != len(names):
        raise CaseError(f"control_surface[].name must be unique, got {names}")
    _check_nesting(out)          # rigid and elastic surfaces may be mixed (issue 25)
    _check_links(out)
    return out


def _check_links(out) -> None:
    """``linked_to`` / ``gear_ratio`` (AELINK, issue 25): a linked surface names another,
    unlinked surface; a case with links has no actuator or freeplay (not modelled)."""
    names = [c.name for c in out]
    for i, c in enumerate(out):
        if not c.linked_to:
            continue
        path = f"control_surface[{i}]"
        if c.linked_to not in names or c.linked_to == c.name:
            raise CaseError(f"{path}.linked_to = {c.linked_to!r} must name another control "
                            f"surface of the case, one of {[n for n in names if n != c.name]}")
        if out[names.index(c.linked_to)].linked_to:
            raise CaseError(f"{path}.linked_to = {c.linked_to!r} is itself linked: link to a "
                            f"free surface (no chains)")
        for j, d in enumerate(out):
            key = "actuator" if d.actuator is not None else "freeplay_deg"
            if d.actuator is not None or d.freeplay_deg > 0:
                raise CaseError(f"control_surface[{j}].{key} cannot be combined with linked "
                                f"surfaces ({path}.linked_to): not modelled")


def _check_nesting(out) -> None:
    """Surfaces on one panel whose spans overlap must be a tab on a flap
    (:func:`asekit.aero.control_surface.nesting`), both of kind "rigid"."""
    from asekit.aero.control_surface import ControlSurface, NestingError, nesting

    surf = [ControlSurface(c.name, *c.hinge_chord_fraction, *c.span_fraction) for c in out]
    for panel in sorted({c.panel for c in out}):
        idx = [i for i, c in enumerate(out) if c.panel == panel]
        try:
            parents = nesting([surf[i] for i in idx])
        except NestingError as exc:
            named = [idx[k] for k in exc.surfaces]
            if len(named) == 2:                  # the first pair that cannot be nested
                j, i = named
                raise CaseError(f"control_surface[{i}].span_fraction "
                                f"{list(out[i].span_fraction)} overlaps control_surface[{j}] "
                                f"({out[j].name!r}) on panel {panel}: {exc}") from None
            raise CaseError(f"control_surface[{named[0]}] on panel {panel}: {exc}") from None
        for k, p in enumerate(parents):
            i = idx[k]
            if p >= 0 and "elastic" in (out[i].kind, out[idx[p]].kind):
                raise CaseError(f"control_surface[{i}] ({out[i].name!r}) is a tab on "
                                f"control_surface[{idx[p]}] ({out[idx[p]].name!r}): a tab and "
                                f"its flap must both be kind = \"rigid\"")


def _damping(t: _Table | None) -> DampingSpec:
    if t is None:
        return DampingSpec()
    z = t.numbers("modal_damping_ratio", low=0.0, low_open=False, high=1.0, high_open=True)
    g = t.numbers("structural_g", low=0.0, low_open=False, high=2.0, high_open=True)
    t.done()
    if z is not None and g is not None:
        raise CaseError("damping: give modal_damping_ratio or structural_g, not both")
    one = (lambda v: None if v is None else (v[0] if len(v) == 1 else v))
    return DampingSpec(one(z), one(g))


def _modes(t: _Table | None, support: SupportSpec) -> ModesSpec:
    if t is None:
        return ModesSpec()
    count = t.integer("count", high=500)
    f_max = t.number("f_max", default=1000.0, low=0.0, high=1e7, unit="Hz")
    keep = t.boolean("keep_rigid", True)
    t.done()
    if keep and not SUPPORTS[support.kind].has_rigid_mode(support):
        keep = False         # only a kind with a rigid mode (the FN2 shaft) keeps one
    return ModesSpec(count, f_max, keep)


def _aero(t: _Table, panels) -> AeroSpec:
    method = t.string("method", METHODS, default="dlm")     # the registry (aero.methods)
    machs = t.numbers("machs", required=True, low=0.0, low_open=False, ascending=True)
    for i, m in enumerate(machs):       # the method's Mach range, from the registry
        try:
            resolve_method(method, m)
        except ValueError as exc:
            raise CaseError(f"aero.machs[{i}] = {m:g} with aero.method = {method!r}: "
                            f"{exc}") from None
    b = t.number("reference_semichord", required=True, low=0.0, high=1e3, unit="m")
    ks = t.raw("reduced_frequencies", "auto")
    if ks == "auto":
        ks = None
    else:
        t.used.discard("reduced_frequencies")
        ks = t.numbers("reduced_frequencies", low=0.0, low_open=False, high=100.0,
                       ascending=True, min_length=2)
    f_max = t.number("f_max", default=1000.0, low=0.0, high=1e7, unit="Hz")
    u_min = t.number("u_min", default=100.0, low=0.0, high=1e5, unit="m/s")
    kernel = t.string("kernel", ("quartic", "parabolic"), default="quartic")
    symmetry = t.string("symmetry", ("none", "wall"), default="none")
    boxes = t.raw("boxes", "auto")
    solver = t.string("solver", SOLVERS, default="dense")   # (asekit.aero.hmatrix)
    section = _tsd_section(t, method, symmetry)
    t.done()
    if boxes == "auto":
        boxes = None
    else:
        if not isinstance(boxes, list) or len(boxes) != len(panels):
            raise CaseError(f"aero.boxes must be \"auto\" or one table {{n_chord, n_span}} per "
                            f"panel ({len(panels)}), got {boxes!r}")
        out = []
        for i, d in enumerate(boxes):
            bt = _Table(d, f"aero.boxes[{i}]")
            out.append((bt.integer("n_chord", required=True, high=1000),
                        bt.integer("n_span", required=True, high=1000)))
            bt.done()
        boxes = tuple(out)
    if symmetry == "wall" and abs(panels[0].planform.root_le[1]) > 1e-12:
        raise CaseError(f"aero.symmetry = \"wall\" puts the reflection plane at y = 0, but the "
                        f"root is at y = {panels[0].planform.root_le[1]:g} m")
    return AeroSpec(machs, b, ks, f_max, u_min, boxes, kernel, symmetry, method, solver,
                    section)


# --- issue 29 (tsdcase): the TSD's aerofoil section -------------------------------------------
def _tsd_section(t: _Table, method: str, symmetry: str) -> tuple[str, float] | None:
    """``aero.section = { shape = "biconvex", thickness_ratio = tau }``, 0 <= tau < 0.3
    (:func:`asekit.aero.tsd3d.biconvex_thickness`): required by ``aero.method = "tsd"`` (with
    ``aero.symmetry = "wall"``: the TSD half wing is mirrored at its root), refused otherwise
    (no other method reads it)."""
    from asekit.aero.methods import TSD_SECTIONS

    st = t.table("section")
    if method != "tsd":
        if st is not None:
            raise CaseError(f"aero.section is read by aero.method = \"tsd\" only, got "
                            f"aero.method = {method!r}; remove aero.section")
        return None
    if st is None:
        raise CaseError("aero.section is missing: aero.method = \"tsd\" needs the aerofoil "
                        "section, e.g. { shape = \"biconvex\", thickness_ratio = 0.04 }")
    if symmetry != "wall":
        raise CaseError(f"aero.symmetry must be \"wall\" with aero.method = \"tsd\" (its half "
                        f"wing is mirrored at the root y = 0), got {symmetry!r}")
    shape = st.string("shape", TSD_SECTIONS, required=True)
    tau = st.number("thickness_ratio", required=True, low=0.0, high=0.3, low_open=False,
                    high_open=True)
    st.done()
    return shape, float(tau)


def check_resources(panels, aero: AeroSpec) -> None:
    """Refuse (:class:`CaseError`), before any computation, a case whose structural LU factor
    (:func:`structural_factor_bytes`) exceeds :data:`MAX_STRUCTURAL_BYTES`, whose dense DLM
    matrix (16 n_boxes^2 bytes, one at a time: :func:`asekit.aero.dlm.iter_normalwash_matrices`)
    exceeds :data:`asekit.aero.boxes.MAX_MATRIX_BYTES`, or whose Mach-box grid at a supersonic
    Mach exceeds :data:`asekit.aero.supersonic.MAX_CELLS` cells
    (:func:`asekit.case.resources.resource_problem`); the one-line error names the keys that
    set the size and the values that fit. Called by the loader and at the pipeline's door."""
    nc = panels[0].n_chord
    ns = sum(p.n_span for p in panels)
    dof = 3 * (nc + 1) * (ns + 1)
    need = structural_factor_bytes(dof)
    if need > MAX_STRUCTURAL_BYTES:
        side = int(math.isqrt(_max_dof(MAX_STRUCTURAL_BYTES) // 3)) - 1
        raise CaseError(f"panel[*].n_chord x n_span: {nc} x {ns} elements ({dof} dof) need about "
                        f"{need / 2 ** 30:.3g} GiB for the structural eigenproblem's sparse LU "
                        f"factor (limit {MAX_STRUCTURAL_BYTES / 2 ** 30:.3g} GiB, asekit.case."
                        f"schema.MAX_STRUCTURAL_BYTES): at most {_max_dof(MAX_STRUCTURAL_BYTES)}"
                        f" dof fit (e.g. {side} x {side} elements); lower n_chord or n_span")
    problem = resource_problem(panels, aero)
    if problem is not None:
        raise CaseError(problem)


def _flight(t: _Table) -> FlightSpec:
    alts = t.numbers("altitudes", low=MIN_ALTITUDE, high=MAX_ALTITUDE, low_open=False,
                     unit="m (the 1976 standard atmosphere's layers)")
    dens = t.numbers("densities", low=0.0, high=100.0, unit="kg/m^3")
    sos = t.numbers("speeds_of_sound", low=0.0, high=1e4, unit="m/s")
    vt = t.table("velocities", required=True)
    v0 = vt.number("min", required=True, low=0.0, high=1e5, unit="m/s")
    v1 = vt.number("max", required=True, low=0.0, high=1e5, unit="m/s")
    dv = vt.number("step", required=True, low=0.0, high=1e5, unit="m/s")
    vt.done()
    env = t.table("envelope")
    em = ea = None
    if env is not None:
        em = env.numbers("mach", length=2, low=0.0, low_open=False, high=10.0)
        ea = env.numbers("altitude", length=2, low=MIN_ALTITUDE, low_open=False,
                         high=MAX_ALTITUDE, unit="m")
        env.done()
        for nm, r in (("mach", em), ("altitude", ea)):
            if r is not None and r[1] < r[0]:
                raise CaseError(f"flight.envelope.{nm} must be [min, max] with min <= max, "
                                f"got {list(r)}")
    t.done()
    if (alts is None) == (dens is None):
        raise CaseError("flight: give exactly one of altitudes (m, standard atmosphere) or "
                        "densities (kg/m^3)")
    if sos is not None and (dens is None or len(sos) != len(dens)):
        raise CaseError("flight.speeds_of_sound needs densities and one value per density")
    if v1 <= v0:
        raise CaseError(f"flight.velocities.max must be > min ({v0:g} m/s), got {v1:g}")
    n = int(math.floor((v1 - v0) / dv + 1e-9)) + 1
    if n < 2 or n > 20000:
        raise CaseError(f"flight.velocities must give 2 to 20000 points, got {n} "
                        f"(min {v0:g}, max {v1:g}, step {dv:g} m/s)")
    return FlightSpec(tuple(float(v) for v in v0 + dv * np.arange(n)), alts, dens, sos, em, ea)


def _actuator(t: _Table | None) -> ActuatorSpec | None:
    if t is None:
        return None
    vals = {}
    for name in MOTOR_KEYS + tuple(TRANSMISSION_KEYS) + ("supply_voltage", "current_limit"):
        zero_ok = name in ("viscous_damping", "transmission_inertia")
        vals[name] = t.number(name, low=0.0, low_open=not zero_ok,
                              high=1.0 if name == "efficiency" else 1e6)
    vals["step_deg"] = t.number("step_deg", default=1.0, low=0.0, high=15.0,
                                unit="deg (the fin's travel)")
    ctl = t.table("controller")
    if ctl is not None:
        for name in ("k_c", "k_p", "k_d"):
            vals[name] = ctl.number(name, low=-1e9, high=1e9)
        ctl.done()
    cond = t.table("condition")
    if cond is not None:
        # its range: within aero.machs (checked by case_from_dict), so within aero.method's
        vals["mach"] = cond.number("mach", default=0.5, low=0.0, low_open=False)
        vals["altitude"] = cond.number("altitude", default=0.0, low=MIN_ALTITUDE,
                                       low_open=False, high=MAX_ALTITUDE, unit="m")
        cond.done()
    t.done()
    return ActuatorSpec(**vals)


def _check_surface_actuators(surfaces, aero, rigid_mode: bool) -> None:
    """At most one actuated control surface, its Mach within aero.machs, on a wing without a
    rigid mode (the hinge is the loop's one prescribed coordinate; issue 25)."""
    act = [i for i, c in enumerate(surfaces) if c.actuator is not None]
    if act and rigid_mode:
        raise CaseError(f"control_surface[{act[0]}].actuator needs a wing without a rigid mode "
                        "(a clamped support, or modes.keep_rigid = false): the surface's hinge "
                        "is the loop's one actuated coordinate")
    if len(act) > 1:
        raise CaseError(f"control_surface[{act[1]}].actuator: only one control surface may "
                        f"carry the actuator (control_surface[{act[0]}] has one)")
    for i in act:
        m = surfaces[i].actuator.mach
        if not aero.machs[0] <= m <= aero.machs[-1]:
            raise CaseError(f"control_surface[{i}].actuator.mach must lie within aero.machs "
                            f"[{aero.machs[0]:g}, {aero.machs[-1]:g}], got {m:g}")


def _flutter(t: _Table | None) -> FlutterSpec:
    if t is None:
        return FlutterSpec()
    method = t.string("method", tuple(FLUTTER_METHODS), default="pk")
    rfa = t.string("rfa", tuple(RFA_FITS), default="roger")
    lags = t.integer("lags", default=4, low=1, high=12)
    t.done()
    return FlutterSpec(method, rfa, lags)


def _convergence(t: _Table | None) -> ConvergenceSpec:
    if t is None:
        return ConvergenceSpec()
    spec = ConvergenceSpec(enabled=t.boolean("enabled", False),
                           meshes=t.integer("meshes", default=3, low=2, high=3),
                           ratio=t.number("ratio", default=1.5, low=1.2, high=4.0,
                                          low_open=False),
                           order=t.number("order", default=1.0, low=0.5, high=4.0,
                                          low_open=False))
    t.done()
    return spec


def _gust_profile(t: _Table, source: str) -> GustProfile | None:
    """``gust.profile``: a CSV path relative to the case file (:func:`read_gust_profile`)."""
    if t.raw("profile") is None:
        return None
    rel = t.text("profile")
    base = Path(source).parent if source else Path.cwd()
    return read_gust_profile(base / rel, "gust.profile")


def _gust(t: _Table | None, aero: AeroSpec, actuator: ActuatorSpec | None,
          source: str = "") -> GustSpec | None:
    if t is None:
        return None
    profile = _gust_profile(t, source)
    stations = _gust_stations(t.raw("station"))
    lengths = t.numbers("gradient_lengths", required=profile is None, default=(), min_length=0,
                        low=0.0, high=1000.0, unit="m", ascending=True)
    if len(lengths) > 50:
        raise CaseError(f"gust.gradient_lengths must hold at most 50 values, got {len(lengths)}")
    wds = t.number("design_velocity", required=bool(lengths), default=0.0, low=0.0,
                   high=100.0, low_open=bool(lengths), unit="m/s")
    mach = t.number("mach", default=actuator.mach if actuator is not None else aero.machs[0],
                    low=0.0, low_open=False)
    alt = t.number("altitude", default=actuator.altitude if actuator is not None else 0.0,
                   low=MIN_ALTITUDE, low_open=False, high=MAX_ALTITUDE, unit="m")
    x0 = t.number("x0", low=-1e3, high=1e3, unit="m")
    settle = t.number("settle_time", default=0.5, low=0.0, high=60.0, unit="s")
    turb = t.table("turbulence")
    sigma, scale, spectrum = None, 762.0, "von_karman"
    if turb is not None:
        sigma = turb.number("sigma", required=True, low=0.0, high=100.0, unit="m/s")
        scale = turb.number("scale_length", default=762.0, low=0.0, high=1e5, unit="m")
        spectrum = turb.string("spectrum", ("von_karman", "dryden"), default="von_karman")
        turb.done()
    t.done()
    if not aero.machs[0] <= mach <= aero.machs[-1]:
        raise CaseError(f"gust.mach must lie within aero.machs [{aero.machs[0]:g}, "
                        f"{aero.machs[-1]:g}], got {mach:g}")
    return GustSpec(tuple(lengths), wds, mach, alt, x0, settle, sigma, scale, spectrum, profile,
                    stations)


# ---------------------------------------------------------------------------------------------
# [[beam]]: a stick model in place of the plate structure (issue 24)
# ---------------------------------------------------------------------------------------------
#: the section properties of a [[beam]] table: (key, low bound (open), unit); each a number
#: (uniform) or a list with one value per segment between stations
BEAM_PROPERTIES = (("ea", 0.0, "N"), ("gj", 0.0, "N m^2"), ("ei_flap", 0.0, "N m^2"),
                   ("ei_chord", 0.0, "N m^2"), ("mass_per_length", 0.0, "kg/m"),
                   ("polar_inertia", 0.0, "kg m"))
#: the [[beam]] properties that may be 0 (ea, ei_chord: with in_plane = "fixed" only)
_BEAM_ZERO_OK = ("ea", "ei_chord", "polar_inertia")
#: the values of [[beam]] in_plane
BEAM_IN_PLANE = ("free", "fixed")
#: the largest number of beam elements (a dense 6 (n + 1) eigenproblem)
MAX_BEAM_ELEMENTS = 2000


@dataclass(frozen=True)
class BeamSpec:
    """A straight beam along a reference (elastic) axis in the (x, y) plane, clamped at its
    root: the structure of a stick-model case (``[[beam]]``, docs/case-format.md).

    Attributes
    ----------
    root : (x, y) of the axis's root point (m).
    direction : (dx, dy) unit vector along the axis.
    length : axis length (m), > 0.
    stations : fractions of the length at the segment ends, 0 first, 1 last, ascending.
    n_elements : equal elements per segment (>= 1).
    sections : one (ea, gj, ei_flap, ei_chord, mass, polar_inertia, mass_offset) tuple per
        segment (SI: N, N m^2, N m^2, N m^2, kg/m, kg m, m; the mass axis ``mass_offset`` aft
        of the elastic axis), the arguments of :class:`asekit.structure.beam.BeamSection`.
    in_plane : "free" (default) or "fixed": the in-plane motion (ux, uy, rz) of every node
        fixed, the out-of-plane modes solved alone (Nastran PS 126 on a stick model).
    point_masses : (s, mass, offset, inertia) per rigid mass on a node: s (m) along the axis
        (a node's station), mass (kg), offset (3,) m along (axis, aft, up) and inertia (3,)
        kg m^2 about its centre along the same axes.
    spline_extension : bool, boxes beyond the root or tip move with the end section extended
        straight (Nastran's SPLINE2); False: every panel corner must lie along the beam.
    """

    root: tuple[float, float]
    direction: tuple[float, float]
    length: float
    stations: tuple[float, ...]
    n_elements: int
    sections: tuple[tuple[float, ...], ...]
    in_plane: str = "free"
    point_masses: tuple = ()
    spline_extension: bool = False


def _beam_axis(t: _Table):
    """(direction, length) of a [[beam]] table: ``tip`` or ``sweep_deg`` with ``length``."""
    root = t.numbers("root", required=True, length=2, unit="m")
    tip = t.numbers("tip", length=2, unit="m")
    sweep = t.number("sweep_deg", low=-MAX_EDGE_SWEEP_DEG, high=MAX_EDGE_SWEEP_DEG,
                     low_open=False, unit="deg")
    length = t.number("length", low=0.0, high=1e4, unit="m")
    if tip is not None and (sweep is not None or length is not None):
        raise CaseError(f"{t.path}: give tip, or sweep_deg and length, not both")
    if tip is None:
        if length is None:
            raise CaseError(f"{t.path}: give the axis as tip = [x, y] (m) or as length (m) "
                            f"with sweep_deg (default 0)")
        a = math.radians(sweep or 0.0)
        return root, (math.sin(a), math.cos(a)), length
    dx, dy = tip[0] - root[0], tip[1] - root[1]
    length = math.hypot(dx, dy)
    if dy <= 0 or math.degrees(math.atan2(abs(dx), dy)) > MAX_EDGE_SWEEP_DEG:
        raise CaseError(f"{t.key('tip')} {list(tip)} must lie outboard of root {list(root)} "
                        f"(greater y) with the axis swept by at most {MAX_EDGE_SWEEP_DEG:g} "
                        f"deg")
    return root, (dx / length, dy / length), length


def _beam_sections(t: _Table, n_seg: int):
    """One section tuple per segment; every property a number or a list of n_seg numbers."""
    def column(k, default, low, high, low_open, unit):
        if isinstance(t.raw(k, default, required=default is None), list):
            return t.numbers(k, length=n_seg, low=low, high=high, low_open=low_open, unit=unit)
        return (t.number(k, default, required=default is None, low=low, high=high,
                         low_open=low_open, unit=unit),) * n_seg
    cols = [column(k, None, low, 1e15, k not in _BEAM_ZERO_OK, unit)
            for k, low, unit in BEAM_PROPERTIES]
    cols.append(column("mass_offset", 0.0, -1e4, 1e4, False, "m"))
    for i in range(n_seg):
        m, ip, d = cols[4][i], cols[5][i], cols[6][i]
        if ip < m * d * d * (1 - 1e-12):
            raise CaseError(f"{t.key('polar_inertia')} (segment {i}) must be >= "
                            f"mass_per_length * mass_offset^2 = {m * d * d:g} kg m (the inertia "
                            f"about the mass axis cannot be negative), got {ip:g}")
    return tuple(tuple(c[i] for c in cols) for i in range(n_seg))


def _beam(raw, panels) -> BeamSpec | None:
    """The case's [[beam]] (one table), its stations and sections checked, the panels' corners
    on the axis's span (the beam-to-box spline needs every box between root and tip)."""
    if raw is None:
        return None
    if not isinstance(raw, list) or len(raw) != 1:
        raise CaseError("beam must be one [[beam]] table (one straight beam; several beams "
                        "are not supported yet)")
    t = _Table(raw[0], "beam[0]")
    root, e1, length = _beam_axis(t)
    st = t.numbers("stations", default=[0.0, 1.0], min_length=2, low=0.0, high=1.0,
                   low_open=False, ascending=True)
    if st[0] != 0.0 or st[-1] != 1.0:
        raise CaseError(f"{t.key('stations')} must run from 0 to 1 (fractions of the axis "
                        f"length), got {list(st)}")
    n_el = t.integer("n_elements", 8, high=MAX_BEAM_ELEMENTS)
    if n_el * (len(st) - 1) > MAX_BEAM_ELEMENTS:
        raise CaseError(f"{t.key('n_elements')} x segments = {n_el * (len(st) - 1)} must be "
                        f"<= {MAX_BEAM_ELEMENTS} elements")
    sections = _beam_sections(t, len(st) - 1)
    in_plane = t.text("in_plane", "free")
    if in_plane not in BEAM_IN_PLANE:
        raise CaseError(f"{t.key('in_plane')} must be one of {list(BEAM_IN_PLANE)}, got "
                        f"{in_plane!r}")
    if in_plane == "free":
        for k, j in (("ea", 0), ("ei_chord", 3)):
            if any(sec[j] == 0 for sec in sections):
                raise CaseError(f"{t.key(k)} must be > 0 unless in_plane = \"fixed\" (the "
                                f"in-plane motion would have no stiffness)")
    masses = _beam_point_masses(t, length, st, n_el)
    extension = t.boolean("spline_extension", False)
    t.done()
    tol = 1e-9 * length
    for i, p in enumerate(() if extension else panels):
        for c in p.planform.corners:
            s = (c[0] - root[0]) * e1[0] + (c[1] - root[1]) * e1[1]
            if s < -tol or s > length + tol:
                raise CaseError(f"panel[{i}] corner {[float(c[0]), float(c[1])]} m lies at "
                                f"{s:.6g} m along beam[0]'s axis, outside the beam [0, "
                                f"{length:.6g}] m: the beam-to-box spline needs every box "
                                f"between the beam's root and tip (or set {t.key('spline_extension')}"
                                f" = true)")
    return BeamSpec(tuple(root), tuple(e1), length, tuple(st), n_el, sections, in_plane,
                    masses, extension)


def beam_node_stations(length: float, stations, n_elements: int) -> np.ndarray:
    """The node distances (m) from the root of a [[beam]]: each segment between ``stations``
    (fractions of ``length``) cut into ``n_elements`` equal elements.

    Examples
    --------
    >>> beam_node_stations(2.0, [0.0, 0.5, 1.0], 2).tolist()
    [0.0, 0.5, 1.0, 1.5, 2.0]
    """
    out = [0.0]
    for a, b in zip(stations[:-1], stations[1:]):
        out.extend(np.linspace(a * length, b * length, n_elements + 1)[1:].tolist())
    return np.asarray(out)


def _beam_point_masses(t: _Table, length: float, st, n_el: int) -> tuple:
    """[[beam]] point_masses: inline tables {s, mass, offset, inertia}, each on a node."""
    raw = t.raw("point_masses", [])
    if not isinstance(raw, list):
        raise CaseError(f"{t.key('point_masses')} must be an array of inline tables "
                        f"{{ s, mass, offset, inertia }}")
    nodes = beam_node_stations(length, st, n_el)
    out = []
    for i, d in enumerate(raw):
        pm = _Table(d, f"{t.path}.point_masses[{i}]")
        s = pm.number("s", required=True, low=0.0, high=length * (1 + 1e-12), low_open=False,
                      unit="m")
        if np.min(np.abs(nodes - s)) > 1e-9 * length:
            raise CaseError(f"{pm.key('s')} = {s:g} m is not a node of the beam (nodes every "
                            f"segment / n_elements; nearest {nodes[np.argmin(np.abs(nodes - s))]:g}"
                            f" m)")
        m = pm.number("mass", 0.0, low=0.0, high=1e9, low_open=False, unit="kg")
        off = pm.numbers("offset", default=[0.0, 0.0, 0.0], length=3, low=-1e4, high=1e4,
                         unit="m")
        inertia = pm.numbers("inertia", default=[0.0, 0.0, 0.0], length=3, low=0.0,
                             low_open=False, high=1e9, unit="kg m^2")
        pm.done()
        out.append((float(nodes[np.argmin(np.abs(nodes - s))]), m, tuple(off), tuple(inertia)))
    return tuple(out)


def _structure_kind(top: _Table) -> bool:
    """True for a beam case: a case has [thickness], [material] and [support] (the panels'
    plate structure) or one [[beam]], never both, never neither."""
    plate = [k for k in ("thickness", "material", "support") if top.has(k)]
    if top.has("beam"):
        if plate:
            raise CaseError(f"beam and {', '.join(plate)}: a case has either the panels' "
                            f"plate structure ([thickness], [material], [support]) or a "
                            f"[[beam]], not both")
        for k in ("point_mass", "control_surface", "gust", "actuator"):
            if top.has(k):
                raise CaseError(f"{k} is not supported with [[beam]] yet (stick models: "
                                f"modes, GAFs and flutter only)")
        return True
    if not plate:
        raise CaseError("the case has no structure: give [thickness], [material] and "
                        "[support] (the panels' plate structure) or one [[beam]]")
    return False


def _common_tables(top: _Table, panels, support) -> dict:
    """The tables a plate case and a stick-model case share, parsed and cross-checked:
    [damping], [modes], [aero] (with the resources it needs), [flight] (with the p-k grid's
    size), [flutter] and [convergence], as the Case fields of the same names."""
    damping = _damping(top.table("damping"))
    modes = _modes(top.table("modes"), support)
    aero = _aero(top.table("aero", required=True), panels)
    check_resources(panels, aero)
    flight = _flight(top.table("flight", required=True))
    n_cond = len(flight.altitudes if flight.altitudes is not None else flight.densities)
    problem = pk_problem(len(aero.machs), n_cond, flight.velocities)
    if problem is not None:
        raise CaseError(problem)
    return {"damping": damping, "modes": modes, "aero": aero, "flight": flight,
            "flutter": _flutter(top.table("flutter")),
            "convergence": _convergence(top.table("convergence"))}


def _beam_case(top: _Table, name: str, reference: str, source: str) -> Case:
    """The rest of case_from_dict for a stick-model case (after [case])."""
    panels = _panels(top.raw("panel", None, required=False), structural=False)
    beam = _beam(top.raw("beam"), panels)
    support = SupportSpec("clamped_root")
    common = _common_tables(top, panels, support)
    if top.has("flutter_speed_index"):
        raise CaseError("flutter_speed_index is not supported with [[beam]] yet")
    top.done()
    return Case(name=name, panels=panels, thickness=None, material=None, support=support,
                reference=reference, source=source, beam=beam, **common)


def case_from_dict(d: dict, source: str = "") -> Case:
    """Build and check a :class:`Case` from the parsed TOML dictionary ``d``."""
    top = _Table(d, "")
    info = top.table("case", required=True)
    name = info.text("name", "")
    if not name:
        raise CaseError("case.name is missing or empty")
    reference = info.text("reference", "")
    info.done()
    if _structure_kind(top):
        return _beam_case(top, name, reference, source)
    panels = _panels(top.raw("panel", None, required=False))
    thickness = _thickness(top.table("thickness", required=True))
    material = _material(top.table("material", required=True))
    support = _support(top.table("support", required=True), panels)
    masses = _point_masses(top.raw("point_mass"), panels)
    surfaces = _control_surfaces(top.raw("control_surface"), panels)
    common = _common_tables(top, panels, support)
    aero, modes = common["aero"], common["modes"]
    actuator = _actuator(top.table("actuator"))
    gust = _gust(top.table("gust"), aero, actuator, source)
    fsi = top.table("flutter_speed_index")
    if fsi is not None:
        fsi_spec = FlutterIndexSpec(fsi.number("semichord", required=True, low=0.0, unit="m"),
                                    fsi.number("f_alpha", required=True, low=0.0, unit="Hz"),
                                    fsi.number("mass_ratio", required=True, low=0.0))
        fsi.done()
    else:
        fsi_spec = None
    top.done()
    _check_surface_actuators(surfaces, aero,
                             SUPPORTS[support.kind].has_rigid_mode(support) and modes.keep_rigid)
    if actuator is not None and not (SUPPORTS[support.kind].has_rigid_mode(support)
                                     and modes.keep_rigid):
        raise CaseError("actuator needs support.kind = \"shaft\" with model \"FN2\" and "
                        "modes.keep_rigid = true (the actuator drives the rigid pitch mode)")
    if actuator is not None and not aero.machs[0] <= actuator.mach <= aero.machs[-1]:
        raise CaseError(f"actuator.condition.mach must lie within aero.machs "
                        f"[{aero.machs[0]:g}, {aero.machs[-1]:g}], got {actuator.mach:g}")
    return Case(name=name, panels=panels, thickness=thickness, material=material,
                support=support, point_masses=masses, actuator=actuator,
                control_surfaces=surfaces, flutter_index=fsi_spec, gust=gust,
                reference=reference, source=source, **common)


def load_case(path) -> Case:
    """Read and check a case file (TOML, ``docs/case-format.md``).

    Parameters
    ----------
    path : str or Path of the case file.

    Returns
    -------
    Case
        The frozen, checked case (SI units).

    Raises
    ------
    CaseError
        (a ValueError) naming the offending key path and its valid range.
    FileNotFoundError

    Examples
    --------
    >>> from asekit.util.paths import CASES_DIR
    >>> case = load_case(CASES_DIR / "agard445_6.toml")
    >>> case.support.kind, case.aero.machs, case.flutter.method
    ('clamped_root', (0.499,), 'pk')
    """
    return case_from_dict(read_toml(path, CaseError), source=str(path))
