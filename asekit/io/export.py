"""Exports for other tools: state spaces as MATLAB ``.mat`` files, modal matrices and GAF
databases as Nastran OUTPUT4 (OP4) files, and a case's state spaces as python-control objects.

MATLAB: :func:`save_mat` writes each system as a struct with fields ``A, B, C, D`` (double),
``inputs``, ``outputs``, ``states`` (cell arrays of char), ``name`` and ``dt`` (0 for
continuous time), so that in MATLAB::

    s = load('fin.mat'); g = s.aeroelastic;
    sys = ss(g.A, g.B, g.C, g.D, 'InputName', g.inputs, 'OutputName', g.outputs, ...
             'StateName', g.states);

:func:`load_mat` reads such a file back into named python-control ``StateSpace`` objects.

OP4: :func:`write_modal_op4` writes MHH, KHH, BHH (and PHG, the mode shapes on the grid DOFs)
and :func:`write_gaf_op4` one Mach of a GAF database as QHHL, the n_modes x (n_modes n_k)
matrix of the complex Q(k) blocks side by side (Nastran's layout, see
:func:`asekit.io.op4.split_qhhl`), with the reduced frequencies in a 1 x n_k matrix KLIST.
Both use :func:`asekit.io.op4.write_op4`.
"""

from __future__ import annotations

from pathlib import Path

import control as ct
import numpy as np
import scipy.io

from asekit.aeroelastic.statespace import aeroelastic_model, fin_outputs
from asekit.ase import loop as ase_mod
from asekit.atmosphere import standard_atmosphere
from asekit.case import pipeline as pl
from asekit.io.op4 import write_op4
from asekit.rfa import roger_fit


def _as_statespace(sys, name: str) -> ct.StateSpace:
    if not isinstance(sys, ct.StateSpace) and isinstance(getattr(sys, "aeroelastic", None),
                                                         ct.StateSpace):
        sys = sys.aeroelastic            # an AeroservoelasticModel: its aeroelastic part
    if isinstance(sys, ct.StateSpace):
        return sys
    if all(hasattr(sys, k) for k in ("A", "B", "C", "D")):
        return ct.ss(sys)
    raise TypeError(f"systems[{name!r}] must be a python-control StateSpace (or a linear "
                    f"interconnection), got {type(sys).__name__}")


def _cell(names) -> np.ndarray:
    out = np.empty((len(names), 1), dtype=object)
    for i, n in enumerate(names):
        out[i, 0] = str(n)
    return out


def save_mat(path, systems, metadata: dict | None = None) -> Path:
    """Write state spaces to a MATLAB ``.mat`` file (scipy.io.savemat, format 5).

    Parameters
    ----------
    path : the file (``.mat`` appended by scipy if missing).
    systems : a python-control ``StateSpace`` (stored as ``sys``) or ``{name: system}``;
        names must be valid MATLAB identifiers. Linear interconnections (``LinearICSystem``)
        are stored through their state-space realisation.
    metadata : optional ``{key: str | float}`` stored as the struct ``meta``.

    Returns the path. Signal names are stored as column cell arrays of char.
    """
    if isinstance(systems, ct.InputOutputSystem) or hasattr(systems, "A"):
        systems = {"sys": systems}
    if not isinstance(systems, dict) or not systems:
        raise TypeError("systems must be a StateSpace or a non-empty {name: StateSpace} dict")
    out = {}
    for name, sys in systems.items():
        if not str(name).isidentifier() or len(str(name)) > 63:
            raise ValueError(f"system name {name!r} is not a valid MATLAB identifier")
        s = _as_statespace(sys, name)
        out[str(name)] = {"A": np.asarray(s.A, float), "B": np.asarray(s.B, float),
                          "C": np.asarray(s.C, float), "D": np.asarray(s.D, float),
                          "inputs": _cell(s.input_labels), "outputs": _cell(s.output_labels),
                          "states": _cell(s.state_labels), "name": str(s.name or name),
                          "dt": float(s.dt or 0.0)}
    if metadata:
        out["meta"] = {str(k): v for k, v in metadata.items()}
    path = Path(path)
    scipy.io.savemat(str(path), out, do_compression=True, oned_as="column")
    return path


def _names(cell) -> list[str]:
    a = np.atleast_1d(cell)
    return [str(np.asarray(x).item() if np.ndim(x) else x) for x in a.ravel()]


class MatFileError(ValueError):
    """A ``.mat`` file that :func:`load_mat` cannot read (damaged, truncated, not a MATLAB
    file, or not written by :func:`save_mat`); the message names the file."""


def _system(key: str, rec) -> ct.StateSpace:
    """One struct of :func:`save_mat` as a named StateSpace."""
    f = {n: rec[n] for n in rec.dtype.names}
    A, B, C, D = (np.atleast_2d(np.asarray(f[k], float)) for k in "ABCD")
    nx, nu, ny = A.shape[0], len(_names(f["inputs"])), len(_names(f["outputs"]))
    A, B = A.reshape(nx, nx), B.reshape(nx, nu)
    C, D = C.reshape(ny, nx), D.reshape(ny, nu)
    for name, a in (("A", A), ("B", B), ("C", C), ("D", D)):
        if not np.all(np.isfinite(a)):
            raise ValueError(f"{key}.{name} holds non-finite values")
    dt = float(np.squeeze(f["dt"]))
    return ct.ss(A, B, C, D, dt if dt else 0, inputs=_names(f["inputs"]),
                 outputs=_names(f["outputs"]), states=_names(f["states"]),
                 name=str(np.squeeze(f["name"])))


def load_mat(path) -> dict[str, ct.StateSpace]:
    """Read a file written by :func:`save_mat` back into ``{name: StateSpace}`` with its
    input, output and state names (the ``meta`` struct, if any, is returned under
    ``"meta"`` as a dict).

    Raises FileNotFoundError for a missing file and :class:`MatFileError` (a ValueError)
    naming the file when it is damaged, truncated, not a MATLAB file or holds no system
    written by :func:`save_mat` (fields A, B, C, D, inputs, outputs, states, name, dt)."""
    import zlib

    path = Path(path)
    if not path.is_file():
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such .mat file")
        raise MatFileError(f"{path} is not a file (a .mat file written by save_mat)")
    try:
        raw = scipy.io.loadmat(str(path), squeeze_me=False, struct_as_record=True)
        out = {}
        for key, val in raw.items():
            if key.startswith("__"):
                continue
            rec = val[0, 0]
            if key == "meta":
                out["meta"] = {n: np.squeeze(rec[n]).tolist() for n in rec.dtype.names}
                continue
            out[key] = _system(key, rec)
    except (ValueError, TypeError, KeyError, IndexError, AttributeError, OSError, EOFError,
            MemoryError, zlib.error, NotImplementedError, scipy.io.matlab.MatReadError) as exc:
        raise MatFileError(f"{path.name} cannot be read as a .mat file of save_mat (damaged or "
                           f"not written by asekit): {type(exc).__name__}: "
                           f"{str(exc).splitlines()[0] if str(exc) else ''}") from exc
    if not any(k != "meta" for k in out):
        raise MatFileError(f"{path.name} holds no state space written by save_mat")
    return out


def write_modal_op4(path, model, digits: int = 9) -> Path:
    """Modal matrices of a :class:`~asekit.structure.modes.ModalModel` as OP4: MHH (kg ...),
    KHH, BHH (modal damping) and PHG (3 n_nodes x n_modes: w, theta_x, theta_y per node)."""
    phg = np.asarray(model.shapes, float).reshape(-1, np.asarray(model.M).shape[0])
    return write_op4(path, {"MHH": np.asarray(model.M, float), "KHH": np.asarray(model.K, float),
                            "BHH": np.asarray(model.C, float), "PHG": phg}, digits=digits)


def write_gaf_op4(path, db, mach: float, digits: int = 9) -> Path:
    """One Mach of a :class:`~asekit.aero.gaf.GafDatabase` as OP4: QHHL (n x n n_k complex,
    the Q(k) blocks side by side, per unit dynamic pressure) and KLIST (1 x n_k)."""
    Q = db.at(mach).Q
    qhhl = np.concatenate(list(Q), axis=1)
    return write_op4(path, {"QHHL": qhhl, "KLIST": np.asarray(db.k, float)[None, :]},
                     digits=digits)


def case_state_spaces(case, mach: float | None = None, altitude: float | None = None,
                      velocity: float | None = None, n_lags: int = 4) -> dict:
    """The case's state spaces as python-control objects with named signals.

    Returns ``{"aeroelastic": StateSpace}`` (thesis Eq. 2.63; inputs theta, theta_dot,
    theta_ddot with a rigid mode; outputs the hinge moment, the modal coordinates and the four
    corner displacements), and with an ``[actuator]`` also ``"AEM1"``, ``"AEM2"`` (the linear
    closed loops from theta_cmd, :func:`asekit.ase.loop.closed_loop`). The flight condition
    defaults to ``[actuator.condition]`` (else the first Mach and altitude), at the speed
    M a unless ``velocity`` (m/s) is given.
    """
    a = case.actuator
    mach = (a.mach if a is not None else case.aero.machs[0]) if mach is None else mach
    if altitude is None:
        altitude = a.altitude if a is not None else (case.flight.altitudes or (0.0,))[0]
    atm = standard_atmosphere(altitude)
    rho = float(atm.density)
    U = mach * float(atm.speed_of_sound) if velocity is None else float(velocity)
    model = pl.modal_model(case)
    db = pl.gaf_database(case, progress=False)
    g = db.at(mach, interpolate=True)
    rfa = roger_fit(g.k, g.Q, db.b_ref, n_lags=n_lags, mach=mach)
    corners = pl.corner_points(case)
    shaft = case.support.axis_point if case.support.kind == "shaft" else None
    rows = fin_outputs(model, np.array(list(corners.values())), names=list(corners),
                       shaft_point=shaft)
    out = {"aeroelastic": aeroelastic_model(model, rfa, rho, U, outputs=rows)}
    if a is not None:
        act, ctl, _ = pl.actuator_setup(case)
        m = ase_mod.build_model(model, rfa, rho, U, rows, actuator=act, mach=mach)
        for topo in ase_mod.TOPOLOGIES:
            out[topo] = ase_mod.closed_loop(m, ctl, topo)
    return out
