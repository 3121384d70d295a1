"""Fuzz targets over asekit's public entry points (issue 11), shared by the hypothesis property
tests (tests/test_properties.py) and the on-demand counter (tests/benchmarks/fuzz_count.py).

Each :class:`Target` draws keyword arguments from a hypothesis strategy and calls one entry
point. :func:`classify` sorts the outcome:

* ``ok`` -- returned, every number in the result finite and the target's plausibility check
  passed;
* ``refused`` -- raised ValueError/TypeError whose message names one of the target's
  arguments;
* ``unnamed`` -- ValueError/TypeError that does not name an argument (e.g. numpy's own);
* ``nan`` -- returned a non-finite number (a silent NaN/inf);
* ``implausible`` -- returned finite numbers that break a physical check (e.g. an instability
  in the sweep that is not reported);
* ``crash`` -- any other exception (IndexError, ZeroDivisionError, LinAlgError, ...);
* ``timeout`` -- ran past the counter's time limit (only the counter enforces one).

Only names that exist in asekit before issue 11 are used, so the counter can run against an
older checkout for the before/after counts.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from hypothesis import strategies as st

# ---- strategies ---------------------------------------------------------------------------------
_weird = st.sampled_from([0.0, -0.0, -1.0, 1e-300, 1e300, math.nan, math.inf, -math.inf])


def reals(lo: float, hi: float, weird: bool = True):
    """Floats mostly in [lo, hi], sometimes at the edges of the float range."""
    core = st.floats(lo, hi, allow_nan=False, allow_infinity=False)
    if not weird:
        return core
    # about one draw in ten is an edge value (hypothesis favours the ends of a range, so the
    # switch sits in the middle of 0..20)
    return st.tuples(st.integers(0, 20), core, _weird).map(
        lambda t: t[2] if 9 <= t[0] <= 10 else t[1])


def ints(lo: int, hi: int):
    return st.tuples(st.integers(0, 20), st.integers(lo, hi), st.sampled_from([0, -1])).map(
        lambda t: t[2] if 9 <= t[0] <= 10 else t[1])


# ---- outcome -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Outcome:
    kind: str
    detail: str = ""


def _numbers(obj, depth: int = 0):
    """Every numeric array/scalar reachable in a result (dataclasses, tuples, dicts)."""
    if depth > 4 or obj is None or isinstance(obj, (str, bytes, bool, Path)):
        return
    if isinstance(obj, (int, float, complex, np.number)):
        yield np.asarray(obj)
    elif isinstance(obj, np.ndarray):
        if np.issubdtype(obj.dtype, np.number):
            yield obj
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        for f in dataclasses.fields(obj):
            yield from _numbers(getattr(obj, f.name), depth + 1)
    elif isinstance(obj, dict):
        for v in obj.values():
            yield from _numbers(v, depth + 1)
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from _numbers(v, depth + 1)


def classify(target: "Target", kwargs: dict) -> Outcome:
    try:
        out = target.call(**kwargs)
    except (ValueError, TypeError) as exc:
        msg = str(exc)
        if any(name in msg for name in target.names):
            return Outcome("refused", msg[:160])
        return Outcome("unnamed", f"{type(exc).__name__}: {msg[:160]}")
    except Exception as exc:                 # noqa: BLE001 - that is what is counted
        return Outcome("crash", f"{type(exc).__name__}: {str(exc)[:160]}")
    for a in _numbers(out):
        if not np.all(np.isfinite(a)):
            return Outcome("nan", f"non-finite value in the result of {target.name}")
    if target.check is not None:
        problem = target.check(kwargs, out)
        if problem:
            return Outcome("implausible", problem)
    return Outcome("ok")


@dataclass(frozen=True)
class Target:
    name: str
    strategy: st.SearchStrategy            # of dict kwargs
    call: Callable
    names: tuple[str, ...]                 # argument names a refusal must mention (any one)
    check: Callable | None = None          # (kwargs, result) -> problem text or ""


# ---- atmosphere --------------------------------------------------------------------------------
def _atmosphere(altitude):
    from asekit.atmosphere import standard_atmosphere
    return standard_atmosphere(altitude)


def _atm_check(kw, s):
    if np.any(s.density <= 0) or np.any(s.temperature <= 0) or np.any(s.pressure <= 0):
        return "non-positive density, temperature or pressure"
    return ""


ATMOSPHERE = Target(
    "atmosphere",
    st.fixed_dictionaries({"altitude": st.one_of(reals(-6000.0, 50000.0),
                                                 st.lists(reals(-6000.0, 50000.0), max_size=4))}),
    _atmosphere, ("altitude",), _atm_check)


def _airspeeds(mach, altitude):
    from asekit.atmosphere import dynamic_pressure, true_airspeed
    u = true_airspeed(mach, altitude)
    return u, dynamic_pressure(u, altitude)


AIRSPEEDS = Target(
    "airspeeds",
    st.fixed_dictionaries({"mach": reals(-1.0, 5.0), "altitude": reals(-6000.0, 50000.0)}),
    _airspeeds, ("mach", "altitude", "true_airspeed"))


# ---- surfaces, meshes, VLM, DLM ----------------------------------------------------------------
def _points(y_lo: float, y_hi: float):
    plain = st.tuples(reals(-1.0, 1.0, False), reals(y_lo, y_hi, False), reals(-0.5, 0.5, False))
    weird = st.tuples(reals(-2.0, 2.0), reals(-2.0, 2.0), reals(-1.0, 1.0))
    return st.one_of(plain, plain, plain, weird)

SURFACE_NAMES = ("root_le", "tip_le", "root_chord", "tip_chord", "n_chord", "n_span", "mach",
                 "reference_area", "symmetric", "corners", "mesh", "boxes", "surface", "span")


def _surface_cla(root_le, root_chord, tip_le, tip_chord, n_chord, n_span, mach,
                 reference_area, symmetric):
    from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    from asekit.aero.vlm import lift_curve_slope
    s = TrapezoidSurface(root_le, root_chord, tip_le, tip_chord, n_chord, n_span)
    return lift_curve_slope(mesh_surfaces([s]), mach, reference_area=reference_area,
                            symmetric=symmetric)


def _cla_check(kw, cla):
    """Thin-airfoil bound: a flat lifting surface's CL_alpha (on its own area) is below the 2-D
    value 2 pi / beta (Prandtl-Glauert) and above -1e-9 (it cannot lift against alpha)."""
    if kw["reference_area"] is not None:
        return ""
    beta = math.sqrt(1.0 - kw["mach"] ** 2)
    if not -1e-9 <= cla <= 2 * math.pi / beta * 1.05:
        return f"CL_alpha {cla:.4g} outside [0, 2 pi / beta = {2 * math.pi / beta:.4g}]"
    return ""


SURFACE_VLM = Target(
    "surface_vlm",
    st.fixed_dictionaries({
        "root_le": _points(-0.5, 1.0), "root_chord": reals(0.01, 2.0),
        "tip_le": _points(0.5, 3.0),
        "tip_chord": reals(0.01, 2.0), "n_chord": ints(1, 6), "n_span": ints(1, 6),
        "mach": reals(0.0, 0.95), "reference_area": st.one_of(st.none(), reals(0.01, 5.0)),
        "symmetric": st.booleans()}),
    _surface_cla, SURFACE_NAMES, _cla_check)


def _plate(n_chord=3, n_span=3):
    from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    return mesh_surfaces([TrapezoidSurface((0.0, 0.1, 0.0), 1.0, (0.3, 1.5, 0.0), 0.6,
                                           n_chord, n_span)])


def _mesh_with_extra_box(box, offset, scale, mach):
    """A plate plus one copy of one of its boxes, shifted and scaled: a duplicate, an overlap
    or (far enough) a valid extra box."""
    from asekit.aero.boxes import BoxMesh
    from asekit.aero.vlm import lift_curve_slope
    m = _plate()
    extra = m.corners[box % m.n] * np.array([1.0, 1.0, 1.0]) * scale + np.asarray(offset)
    mesh = BoxMesh(np.concatenate([m.corners, extra[None]]), np.r_[m.strip, 0],
                   np.r_[m.surface, 0])
    return lift_curve_slope(mesh, mach)


MESH_OVERLAP = Target(
    "mesh_overlap",
    st.fixed_dictionaries({
        "box": st.integers(0, 8),
        "offset": st.tuples(st.sampled_from([0.0, 0.05, 0.2, 3.0]),
                            st.sampled_from([0.0, 0.05, 0.3, 5.0]), st.just(0.0)),
        "scale": st.sampled_from([1.0, 0.9, 1.5]), "mach": reals(0.0, 0.9, weird=False)}),
    _mesh_with_extra_box, SURFACE_NAMES)


def _dlm(n_chord, n_span, mach, k, b_ref, symmetric):
    from asekit.aero.dlm import normalwash_matrix
    return normalwash_matrix(_plate(n_chord, n_span), mach, k, b_ref, symmetric=symmetric)


DLM = Target(
    "dlm",
    st.fixed_dictionaries({"n_chord": st.integers(1, 4), "n_span": st.integers(1, 3),
                           "mach": reals(0.0, 0.95), "k": reals(0.0, 5.0),
                           "b_ref": reals(0.01, 2.0), "symmetric": st.booleans()}),
    _dlm, ("mach", "k", "b_ref", "mesh", "symmetric"))


# ---- RFA ---------------------------------------------------------------------------------------
def _rfa(k, n, n_lags, b_ref, scale, seed):
    from asekit.rfa import roger_fit
    rng = np.random.default_rng(seed)
    k = np.asarray(k, float)
    Q = scale * (rng.normal(size=(k.size, n, n)) + 1j * rng.normal(size=(k.size, n, n)))
    return roger_fit(k, Q, b_ref, n_lags=n_lags)


def _rfa_check(kw, fit):
    if not 0.0 <= fit.fit_error <= 10.0:
        return f"fit_error {fit.fit_error}"
    return ""


RFA = Target(
    "rfa",
    st.fixed_dictionaries({
        "k": st.one_of(st.lists(reals(0.0, 3.0), min_size=0, max_size=9),
                       st.builds(lambda xs: sorted(set(xs)),
                                 st.lists(reals(0.0, 3.0, False), min_size=0, max_size=12))),
        "n": st.integers(1, 3),
        "n_lags": ints(0, 6), "b_ref": reals(0.01, 2.0),
        "scale": st.sampled_from([1.0, 1e-3, 0.0, 1e200]), "seed": st.integers(0, 3)}),
    _rfa, ("k", "Q", "b_ref", "lag_roots", "n_lags", "equations", "coefficients"), _rfa_check)


def _gaf_at_mach(mach, interpolate):
    from asekit.aero.gaf import GafDatabase
    db = GafDatabase(np.array([0.4, 0.6, 0.75]), np.array([0.0, 0.5]),
                     np.ones((3, 2, 1, 1), complex), 1.0, 0, {})
    return db.at(mach, interpolate=interpolate)


GAF_AT_MACH = Target(
    "GafDatabase.at",
    st.fixed_dictionaries({"mach": reals(0.0, 1.0), "interpolate": st.booleans()}),
    _gaf_at_mach, ("mach",))


# ---- flutter -----------------------------------------------------------------------------------
def two_dof_coalescence(c):
    """The hand-derivable 2-dof quasi-steady coalescence model of tests/aeroelastic/test_flutter.py:
    (modal, gaf, fit) with stiffnesses 100^2, 150^2, coupling Q = [[0, 1], [-2, 0]] and modal
    damping c (also used by tests/aeroelastic/test_flutter_onset.py)."""
    from asekit.aeroelastic.flutter import TabulatedGaf
    from asekit.aeroelastic.statespace import modal_arrays
    from asekit.rfa import RogerFit
    k1, k2, a, d = TWO_DOF
    Q = np.array([[0.0, a], [d, 0.0]], complex)
    modal = modal_arrays(M=np.eye(2), K=np.diag([k1, k2]), C=c * np.eye(2))
    gaf = TabulatedGaf(np.array([0.0, 10.0]), np.array([Q, Q]), 1.0)
    A = np.zeros((3, 2, 2))
    A[0] = Q.real
    fit = RogerFit(A=A, lag_roots=np.array([]), b_ref=1.0, k=gaf.k, Q=gaf.Q,
                   element_error=np.zeros((2, 2)), fit_error=0.0)
    return modal, gaf, fit


#: (k1, k2, a, d) of :func:`two_dof_coalescence`
TWO_DOF = (100.0 ** 2, 150.0 ** 2, 1.0, -2.0)


_velocities = st.one_of(st.lists(reals(0.1, 300.0), min_size=0, max_size=8),
                        st.builds(lambda a, b, n: list(np.linspace(min(a, b), max(a, b), n)),
                                  reals(0.1, 300.0, weird=False), reals(0.1, 300.0, weird=False),
                                  st.integers(1, 12)),
                        st.builds(lambda a, b, n: list(np.linspace(min(a, b), max(a, b), n)),
                                  reals(0.1, 300.0, weird=False), reals(0.1, 300.0, weird=False),
                                  st.integers(1, 12)))
FLUTTER_NAMES = ("velocities", "density", "max_iter", "tol", "modes", "window", "t_end",
                 "substeps", "coordinate", "record", "max_step")


def _unreported(result_sigma, velocities, instabilities):
    """A root with Re p clearly > 0 somewhere in the sweep must give an instability."""
    sig = np.asarray(result_sigma)
    scale = 1e-6 * max(1.0, float(np.max(np.abs(sig))) if sig.size else 1.0)
    if sig.size and np.max(sig) > scale and not instabilities:
        j = np.unravel_index(np.argmax(sig), sig.shape)[0]
        return (f"Re p = {np.max(sig):.3g} > 0 at U = {velocities[j]:.4g} but no instability "
                "reported")
    return ""


def _pk(c, density, velocities, max_iter, tol):
    import warnings

    from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
    modal, gaf, _ = two_dof_coalescence(c)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = pk_flutter(modal, gaf, density, velocities, max_iter=max_iter, tol=tol)
    return res, pk_instabilities(res, modal, gaf)


def _pk_check(kw, out):
    res, inst = out
    for s in inst:
        if not res.velocities[0] - 1e-9 <= s.speed <= res.velocities[-1] + 1e-9:
            return f"instability at {s.speed} outside the sweep"
    return _unreported(res.p.real, res.velocities, inst)


PK = Target(
    "pk",
    st.fixed_dictionaries({"c": reals(0.0, 20.0, weird=False), "density": reals(0.01, 3.0),
                           "velocities": _velocities, "max_iter": ints(1, 80),
                           "tol": st.sampled_from([1e-7, 1e-7, 1e-7, 1e-3, 0.0, -1.0,
                                                   math.nan])}),
    _pk, FLUTTER_NAMES, _pk_check)


def _rl(c, density, velocities):
    from asekit.aeroelastic.flutter import root_locus, root_locus_instabilities
    modal, _, fit = two_dof_coalescence(c)
    res = root_locus(modal, fit, density, velocities)
    return res, root_locus_instabilities(res, modal, fit)


def _rl_check(kw, out):
    res, inst = out
    return _unreported(res.elastic.real, res.velocities, inst)


ROOT_LOCUS = Target(
    "root_locus",
    st.fixed_dictionaries({"c": reals(0.0, 20.0, weird=False), "density": reals(0.01, 3.0),
                           "velocities": _velocities}),
    _rl, FLUTTER_NAMES, _rl_check)


def _td(c, density, velocities, t_end, window):
    from asekit.aeroelastic.flutter import time_domain_sweep
    modal, _, fit = two_dof_coalescence(c)
    return time_domain_sweep(modal, fit, density, velocities, coordinate=0, t_end=t_end,
                             window=window)


def _td_check(kw, td):
    if np.any(td.growth > 1.0) and td.onset_speed is None:
        j = int(np.argmax(td.growth))
        return f"growth {td.growth[j]:.3g} 1/s at U = {td.velocities[j]:.4g} but no onset"
    return ""


TIME_DOMAIN = Target(
    "time_domain",
    st.fixed_dictionaries({"c": reals(1.0, 20.0, weird=False), "density": reals(0.01, 3.0),
                           "velocities": st.lists(reals(1.0, 200.0), min_size=0, max_size=3),
                           "t_end": reals(0.05, 3.0),
                           "window": st.one_of(st.none(), st.none(), reals(1e-9, 0.5))}),
    _td, FLUTTER_NAMES, _td_check)


# ---- servo -------------------------------------------------------------------------------------
SERVO_NAMES = ("resistance", "inductance", "torque_constant", "back_emf_constant",
               "rotor_inertia", "viscous_damping", "ratio", "efficiency", "inertia", "gain",
               "kp", "kd", "fin_inertia", "supply_voltage", "current_limit", "t_final",
               "sample_time", "max_step", "command", "theta0", "limits", "controller",
               "params", "n_out", "current_loop_time_constant", "steps")


def _servo(scale_l, scale_r, ratio, efficiency, gain, kp, kd, supply, current_limit):
    from asekit.servo.actuator import (
        ActuatorParameters,
        DCMotor,
        PDController,
        Transmission,
        closed_loop_poles,
        open_loop_poles,
    )
    from asekit.servo.simulate import PowerLimits
    motor = DCMotor(resistance=5.78 * scale_r, inductance=550e-6 * scale_l)
    p = ActuatorParameters(motor=motor, transmission=Transmission(ratio, efficiency))
    ctrl = PDController(gain, kp, kd)
    lim = PowerLimits(supply_voltage=supply, current_limit=current_limit)
    return open_loop_poles(p), closed_loop_poles(p, ctrl, require_stable=False), lim


SERVO = Target(
    "servo",
    st.fixed_dictionaries({
        "scale_l": reals(1e-3, 1e3), "scale_r": reals(1e-3, 1e3), "ratio": reals(0.1, 200.0),
        "efficiency": reals(0.01, 1.5), "gain": reals(-20.0, 20.0), "kp": reals(0.0, 1000.0),
        "kd": reals(0.0, 10.0), "supply": st.one_of(st.none(), reals(1.0, 50.0)),
        "current_limit": st.one_of(st.none(), reals(0.5, 20.0))}),
    _servo, SERVO_NAMES)


def _simulate(scale_l, gain, kd, command, t_final, sample_time, limits):
    from asekit.servo.actuator import ActuatorParameters, DCMotor, PDController
    from asekit.servo.simulate import NO_LIMITS, THESIS_LIMITS, simulate
    lim = {"thesis": THESIS_LIMITS, "none": NO_LIMITS}.get(limits, limits)
    p = ActuatorParameters(motor=DCMotor(inductance=550e-6 * scale_l))
    return simulate(p, PDController(gain, 275.0, kd), command, t_final=t_final,
                    limits=lim, sample_time=sample_time, n_out=201)


def _sim_check(kw, r):
    lim = kw["limits"]
    if lim == "thesis" and np.max(np.abs(r.voltage)) > 24.0 * (1 + 1e-9):
        return f"|V| = {np.max(np.abs(r.voltage)):.4g} V past the 24 V supply"
    return ""


SIMULATE = Target(
    "simulate",
    st.fixed_dictionaries({
        "scale_l": st.sampled_from([1.0, 0.1, 1e-9, 10.0]),
        "gain": st.sampled_from([10.0, 1.0, 0.0, -5.0]),
        "kd": st.sampled_from([1.0, 0.0, 1e30, math.nan]),
        "command": reals(-0.5, 0.5), "t_final": reals(1e-4, 0.01),
        "sample_time": st.one_of(st.none(), st.sampled_from([1e-3, 1e-4, 1e-9, 0.0])),
        "limits": st.sampled_from(["thesis", "none", "x", None])}),
    _simulate, SERVO_NAMES, _sim_check)


# ---- OP4 round trip ----------------------------------------------------------------------------
def _op4(name, values, shape, cplx, digits):
    from asekit.io.op4 import read_op4, write_op4
    a = np.resize(np.asarray(values, float), shape) if values else np.zeros(shape)
    if cplx:
        a = a + 1j * a[::-1]
    with tempfile.TemporaryDirectory() as d:
        p = write_op4(Path(d) / "x.op4", {name: a}, digits=digits)
        back = read_op4(p)
    return a, back


def _op4_check(kw, out):
    a, back = out
    name = kw["name"]
    if name.strip() not in back:
        return f"matrix {name!r} not read back (got {list(back)})"
    b = back[name.strip()].data
    rtol = 10.0 ** (1 - kw["digits"])
    if b.shape != np.atleast_2d(a).shape or not np.allclose(b, np.atleast_2d(a), rtol=rtol,
                                                           atol=0.0):
        return "OP4 round trip changed the values"
    return ""


OP4 = Target(
    "op4",
    st.fixed_dictionaries({
        "name": st.one_of(st.sampled_from(["KHH", "A", "QHHL", "MHH1234"]),
                          st.text(min_size=0, max_size=10)),
        "values": st.lists(st.one_of(st.floats(-1e6, 1e6), st.sampled_from(
            [1e100, -3.5e-150, 1e300, 5e-324, 0.0, math.nan, math.inf])), max_size=12),
        "shape": st.tuples(st.integers(1, 4), st.integers(1, 4)), "cplx": st.booleans(),
        "digits": st.sampled_from([9, 9, 6, 15, 0])}),
    _op4, ("matrix", "name", "digits", "values", "OP4"), _op4_check)


TARGETS = (ATMOSPHERE, AIRSPEEDS, SURFACE_VLM, MESH_OVERLAP, DLM, RFA, GAF_AT_MACH, PK,
           ROOT_LOCUS, TIME_DOMAIN, SERVO, SIMULATE, OP4)


# ---- p-k continuation: the first flutter whatever the velocity grid (issue 22) ----------------
#: AGARD 445.6 weakened wing 3 at M 0.499 (data/cases/agard445_6.toml): the first flutter of
#: asekit's p-k on the case's own fine sweep (100-260 m/s, step 2), mode 1 (the issue's 182 m/s).
AGARD_FIRST_FLUTTER = 181.9386809


def agard_pk_model():
    """(modal model, TabulatedGaf at M 0.499, density) of the AGARD 445.6 case (pipeline)."""
    from asekit.case import load_case
    from asekit.case import pipeline as P
    from asekit.util.paths import CASES_DIR
    case = load_case(CASES_DIR / "agard445_6.toml")
    db = P.gaf_database(case, progress=False)
    return P.modal_model(case), db.at(case.aero.machs[0]), float(case.flight.densities[0])


def _grid(start, step, n, extra):
    """An ascending grid: ``n`` points from ``start`` by ``step``, plus ``extra`` points; it
    reaches past the flutter speed (a last point at 182.5 + its step when it would not)."""
    U = np.unique(np.r_[start + step * np.arange(n), extra])
    if U[-1] <= AGARD_FIRST_FLUTTER + 0.5:
        U = np.r_[U, AGARD_FIRST_FLUTTER + 0.5 + step]
    return [float(u) for u in U]


#: random velocity grids starting below the flutter speed, at least 2 points.
AGARD_GRIDS = st.builds(_grid, st.floats(1.0, 181.0), st.floats(0.5, 900.0),
                        st.integers(2, 14),
                        st.lists(st.floats(1.0, 3000.0), max_size=4))


# ---- silent NaN and loose types (issue 22) ------------------------------------------------------
#: a refusal that names the argument it is about (word-bounded): :func:`_expect` marks it so
NAMED = "<named>"


def _expect(arg: str, thunk):
    """Call ``thunk``; a ValueError/TypeError whose message names ``arg`` (as a word, or the
    file name for a file) comes back marked :data:`NAMED`, any other passes unchanged (so it
    counts as ``unnamed``)."""
    import re
    try:
        return thunk()
    except (ValueError, TypeError) as exc:
        if re.search(rf"(?<![\w.]){re.escape(arg)}(?!\w)", str(exc)):
            raise type(exc)(f"{NAMED} {exc}") from exc
        raise


def _loose(label, arg, thunk):
    """One loose-typed call: ``thunk`` must refuse the value of ``arg``; returning is a silent
    coercion (``implausible``)."""
    return (label, arg, thunk)


def _call_loose(case):
    label, arg, thunk = case
    return label, _expect(arg, thunk)


def _loose_check(kw, out):
    return f"{out[0]}: accepted silently"


def _loose_cases():
    """Strings, floats and bools where counts belong, complex values with an imaginary part:
    each must be refused naming its argument (issue 22's reproducers and their siblings)."""
    def dlm(**kw):
        from asekit.aero.dlm import normalwash_matrix
        a = {"mach": 0.5, "k": 0.1, "b_ref": 1.0} | kw
        return normalwash_matrix(_plate(2, 2), a["mach"], a["k"], a["b_ref"])

    def gaf(**kw):
        from asekit.aero.gaf import TabulatedGaf
        a = {"k": np.array([0.0, 0.5, 1.0]), "Q": np.ones((3, 2, 2), complex), "b_ref": 1.0}
        a |= kw
        return TabulatedGaf(a["k"], a["Q"], a["b_ref"])

    def roger(**kw):
        from asekit.rfa import roger_fit
        rng = np.random.default_rng(0)
        a = {"k": np.linspace(0.0, 1.0, 8), "Q": rng.normal(size=(8, 2, 2)) + 0j,
             "b_ref": 1.0} | kw
        return roger_fit(a.pop("k"), a.pop("Q"), a.pop("b_ref"), **a)

    def ms(**kw):
        from asekit.rfa import minimum_state_fit
        rng = np.random.default_rng(0)
        a = {"k": np.linspace(0.0, 1.0, 8), "Q": rng.normal(size=(8, 2, 2)) + 0j,
             "b_ref": 1.0} | kw
        return minimum_state_fit(a.pop("k"), a.pop("Q"), a.pop("b_ref"), max_iter=5, **a)

    def pk(**kw):
        from asekit.aeroelastic.flutter import pk_flutter
        modal, g, _ = two_dof_coalescence(1.0)
        a = {"density": 1.2, "velocities": [10.0, 20.0]} | kw
        return pk_flutter(modal, g, a.pop("density"), a.pop("velocities"), **a)

    def atm(altitude):
        from asekit.atmosphere import standard_atmosphere
        return standard_atmosphere(altitude)

    def tas(mach):
        from asekit.atmosphere import true_airspeed
        return true_airspeed(mach, 0.0)

    def step(**kw):
        from asekit.servo.actuator import ActuatorParameters, PDController, step_response
        return step_response(ActuatorParameters(), PDController(10.0, 275.0, 1.0), **kw)

    def section(**kw):
        from asekit.aeroelastic.typical_section import conner_1997, flutter_speed
        return flutter_speed(conner_1997(), 5.0, 40.0, **kw)

    def statespace(**kw):
        from asekit.aeroelastic.statespace import aeroelastic_matrices
        modal, _, fit = two_dof_coalescence(1.0)
        a = {"rho": 1.2, "velocity": 50.0} | kw
        return aeroelastic_matrices(modal, fit, a["rho"], a["velocity"])

    cz = np.array([0.0, 0.5, 1.0 + 0.5j])
    return [
        _loose("dlm b_ref str", "b_ref", lambda: dlm(b_ref="1.0")),
        _loose("dlm k complex", "k", lambda: dlm(k=0.1 + 0.5j)),
        _loose("dlm k complex numpy", "k", lambda: dlm(k=np.complex128(0.1 + 0.5j))),
        _loose("dlm mach str", "mach", lambda: dlm(mach="0.5")),
        _loose("dlm mach complex", "mach", lambda: dlm(mach=np.complex128(0.5 + 1j))),
        _loose("TabulatedGaf b_ref str", "b_ref", lambda: gaf(b_ref="1.0")),
        _loose("TabulatedGaf k complex", "k", lambda: gaf(k=cz)),
        _loose("TabulatedGaf k str", "k", lambda: gaf(k=["0", "0.5", "1"])),
        _loose("roger_fit b_ref str", "b_ref", lambda: roger(b_ref="1.0")),
        _loose("roger_fit n_lags float", "n_lags", lambda: roger(n_lags=2.5)),
        _loose("roger_fit n_lags bool", "n_lags", lambda: roger(n_lags=True)),
        _loose("roger_fit n_lags str", "n_lags", lambda: roger(n_lags="2")),
        _loose("roger_fit k complex", "k", lambda: roger(k=np.linspace(0, 1, 8) + 0.1j)),
        _loose("minimum_state_fit n_states float", "n_states", lambda: ms(n_states=4.5)),
        _loose("minimum_state_fit n_states bool", "n_states", lambda: ms(n_states=True)),
        _loose("minimum_state_fit k complex", "k", lambda: ms(k=np.linspace(0, 1, 8) + 0.1j)),
        _loose("minimum_state_fit max_iter float", "max_iter", lambda: ms(max_iter=2.5)),
        _loose("pk velocities complex", "velocities",
               lambda: pk(velocities=np.array([10.0, 20.0 + 1j]))),
        _loose("pk density complex", "density", lambda: pk(density=np.complex128(1.2 + 1j))),
        _loose("pk density str", "density", lambda: pk(density="1.2")),
        _loose("pk max_iter float", "max_iter", lambda: pk(max_iter=3.5)),
        _loose("atmosphere altitude complex", "altitude",
               lambda: atm(np.array([1000.0 + 5j]))),
        _loose("atmosphere altitude str", "altitude", lambda: atm("1000")),
        _loose("atmosphere altitude str list", "altitude", lambda: atm(["1000", "2000"])),
        _loose("true_airspeed mach complex", "mach", lambda: tas(np.array([0.5 + 1j]))),
        _loose("statespace velocity complex", "velocity",
               lambda: statespace(velocity=np.complex128(50 + 1j))),
        _loose("step_response n float", "n", lambda: step(n=2001.0)),
        _loose("step_response t_final str", "t_final", lambda: step(t_final="0.05")),
        _loose("step_response amplitude str", "amplitude", lambda: step(amplitude="1")),
        _loose("step_response amplitude complex", "amplitude", lambda: step(amplitude=1 + 1j)),
        _loose("flutter_speed n float", "n", lambda: section(n=10.5)),
        _loose("flutter_speed n bool", "n", lambda: section(n=True)),
    ]


LOOSE_TYPES = Target("loose_types", st.fixed_dictionaries({"case": st.sampled_from(
    _loose_cases())}), _call_loose, (NAMED,), _loose_check)


def _step(t_final, n, gain):
    from asekit.servo.actuator import ActuatorParameters, PDController, step_response
    return step_response(ActuatorParameters(), PDController(gain, 275.0, 1.0), t_final=t_final,
                         n=n)


STEP_RESPONSE = Target(
    "step_response",
    st.fixed_dictionaries({
        "t_final": st.one_of(reals(1e-4, 1.0), st.sampled_from([10.0, 1e3, 1e6, 1e12, 1e100,
                                                                  1e300])),
        "n": st.one_of(st.integers(2, 3000), st.sampled_from([0, 1, 2001])),
        "gain": st.sampled_from([10.0, 1.0, 0.1, -5.0])}),
    _step, (NAMED, "t_final", "n", "time step", "gain"))

_BAD = st.sampled_from([math.nan, math.inf, -math.inf, complex(0, math.inf),
                        complex(math.nan, 0), None])


def _gaf_pk(bad, where, velocities):
    """The 2-dof coalescence model of :func:`two_dof_coalescence` with one entry of its GAF table
    (3 reduced frequencies) replaced by ``bad`` (None: unchanged), through p-k."""
    import warnings

    from asekit.aero.gaf import TabulatedGaf
    from asekit.aeroelastic.flutter import pk_flutter, pk_instabilities
    modal, g, _ = two_dof_coalescence(1.0)
    Q = np.array([g.Q[0], g.Q[0] * 1.01, g.Q[0] * 1.02])
    if bad is not None:
        Q[where] = bad
    gaf = TabulatedGaf(np.array([0.0, 1.0, 10.0]), Q, 1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        res = pk_flutter(modal, gaf, 1.2, velocities)
    return res, pk_instabilities(res, modal, gaf)


_ENTRY = st.tuples(st.integers(0, 2), st.integers(0, 1), st.integers(0, 1))

GAF_TABLE = Target(
    "TabulatedGaf",
    st.fixed_dictionaries({"bad": _BAD, "where": _ENTRY,
                           "velocities": st.sampled_from([[10.0, 50.0, 100.0, 150.0],
                                                          [20.0, 40.0]])}),
    _gaf_pk, ("Q", "k", "b_ref", "velocities"), _pk_check)


def _statespace(bad, where, lag_bad, rho, velocity):
    """aeroelastic_matrices of the 2-dof model from a Roger fit whose A (one lag root) holds one
    bad entry; and a Roger fit of a table holding it."""
    import dataclasses as dc

    from asekit.aeroelastic.statespace import aeroelastic_matrices
    from asekit.rfa import roger_fit
    modal, _, fit = two_dof_coalescence(1.0)
    A = np.concatenate([fit.A, fit.A[:1] * 0.1])
    if bad is not None and not lag_bad:
        A[where] = np.real(bad)
    roots = np.array([math.nan if lag_bad and bad is not None else 0.5])
    fit = dc.replace(fit, A=A, lag_roots=roots)
    k = np.linspace(0.0, 1.0, 6)
    Q = np.array([fit.A[0] + 1j * kk * fit.A[0] for kk in k]).astype(complex)
    if bad is not None and lag_bad:
        Q[2, 0, 1] = bad
    return aeroelastic_matrices(modal, fit, rho, velocity), roger_fit(k, Q, 1.0, n_lags=1)


STATESPACE = Target(
    "statespace",
    st.fixed_dictionaries({"bad": _BAD, "where": _ENTRY, "lag_bad": st.booleans(),
                           "rho": reals(0.01, 3.0), "velocity": reals(1.0, 300.0)}),
    _statespace, ("A", "rfa", "lag_roots", "rho", "velocity", "Q"))


def _damaged_mat(kind):
    """A file written by save_mat, damaged by ``kind``, read by load_mat."""
    import control as ct

    from asekit.io.export import load_mat, save_mat
    with tempfile.TemporaryDirectory() as d:
        p = save_mat(Path(d) / "sys.mat", {"g": ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])})
        raw = bytearray(p.read_bytes())
        if kind == "truncated":
            raw = raw[:len(raw) * 2 // 3]
        elif kind == "flipped":
            for i in range(200, len(raw), 7):
                raw[i] ^= 0x5A
        elif kind == "header only":
            raw = raw[:128]
        elif kind == "empty":
            raw = bytearray()
        elif kind == "text":
            raw = bytearray(b"not a MATLAB file\n" * 20)
        p.write_bytes(bytes(raw))
        return _expect("sys.mat", lambda: load_mat(p))


def _misc_cases():
    """The issue's bare exceptions: divergence_speeds without Q0, flutter_speed with n < 2, a
    Mach number of 1e300, a damaged .mat file."""
    def div(Q0):
        from asekit.aeroelastic.flutter import divergence_speeds
        modal, _, _ = two_dof_coalescence(1.0)
        return divergence_speeds(modal, Q0, 1.2)

    def section(n):
        from asekit.aeroelastic.typical_section import conner_1997, flutter_speed
        return flutter_speed(conner_1997(), 5.0, 40.0, n=n)

    def piston(mach, order):
        from asekit.aero.piston import piston_pressure_matrices
        return piston_pressure_matrices(_plate(2, 2), mach, [0.1], 1.0, order=order,
                                        thickness_slope=0.05)

    def mach_box(mach):
        from asekit.aero.supersonic import supersonic_pressure_matrices
        return supersonic_pressure_matrices(_plate(2, 2), mach, [0.1], 1.0)

    cases = [("divergence_speeds Q0 None", "Q0", lambda: div(None)),
             ("divergence_speeds Q0 3x3", "Q0", lambda: div(np.eye(3))),
             ("divergence_speeds Q0 nan", "Q0", lambda: div(np.full((2, 2), math.nan))),
             ("divergence_speeds Q0 str", "Q0", lambda: div("Q0")),
             ("flutter_speed n 0", "n", lambda: section(0)),
             ("flutter_speed n 1", "n", lambda: section(1)),
             ("flutter_speed n -3", "n", lambda: section(-3))]
    cases += [(f"piston mach {m:g} order {o}", "mach", (lambda m=m, o=o: piston(m, o)))
              for m in (1e300, 1e160, 1e20) for o in (1, 2, 3)]
    cases += [(f"mach box mach {m:g}", "mach", (lambda m=m: mach_box(m))) for m in (1e300, 1e20)]
    cases += [(f"load_mat {kind}", "sys.mat", (lambda kind=kind: _damaged_mat(kind)))
              for kind in ("truncated", "flipped", "header only", "empty", "text")]
    return cases


def _call_misc(case):
    label, arg, thunk = case
    return _expect(arg, thunk)


MISC = Target("bare_errors", st.fixed_dictionaries({"case": st.sampled_from(_misc_cases())}),
              _call_misc, (NAMED,))

#: the targets of issue 22's "silent NaN and loose types"
TYPE_TARGETS = (LOOSE_TYPES, STEP_RESPONSE, GAF_TABLE, STATESPACE, MISC)
#: everything the fuzz counter (tests/benchmarks/fuzz_count.py) runs
ALL_TARGETS = TARGETS + TYPE_TARGETS
