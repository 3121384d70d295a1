"""Trapezoidal lifting surfaces, thickness laws and materials.

Axes: x chordwise (downstream, the free-stream direction), y spanwise, z normal (up). A positive
rotation about +y moves the trailing edge down: nose-up, i.e. a positive angle of attack.

The reference fin is one case file, ``data/cases/nalci2013_fin.toml``, read by
:func:`asekit.case.load_case`; nothing here knows it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from asekit.util.validate import positive


@dataclass(frozen=True)
class Planform:
    """A flat trapezoid with streamwise root and tip chords (all lengths in m).

    Parameters
    ----------
    root_le, tip_le : (x, y) of the root and tip leading edges; tip_le[1] > root_le[1].
    root_chord, tip_chord : streamwise chords at root and tip, > 0.
    """

    root_le: tuple[float, float]
    root_chord: float
    tip_le: tuple[float, float]
    tip_chord: float

    def __post_init__(self):
        object.__setattr__(self, "root_le", tuple(float(v) for v in self.root_le))
        object.__setattr__(self, "tip_le", tuple(float(v) for v in self.tip_le))
        positive("root_chord", self.root_chord)
        positive("tip_chord", self.tip_chord)
        if not all(math.isfinite(v) for v in self.root_le + self.tip_le):
            raise ValueError("root_le and tip_le must be finite (x, y) pairs")
        if self.tip_le[1] - self.root_le[1] <= 0.0:
            raise ValueError(
                f"span must be > 0: tip_le y ({self.tip_le[1]}) must exceed root_le y ({self.root_le[1]})")

    @property
    def span(self) -> float:
        """Span (m), measured along y."""
        return self.tip_le[1] - self.root_le[1]

    @property
    def area(self) -> float:
        """Planform area (m^2)."""
        return 0.5 * (self.root_chord + self.tip_chord) * self.span

    @property
    def taper(self) -> float:
        return self.tip_chord / self.root_chord

    @property
    def mean_aerodynamic_chord(self) -> float:
        """Mean aerodynamic chord (m): (2/3) c_r (1 + l + l^2) / (1 + l)."""
        lam = self.taper
        return 2.0 / 3.0 * self.root_chord * (1 + lam + lam**2) / (1 + lam)

    @property
    def leading_edge_sweep(self) -> float:
        """Leading-edge sweep angle (rad)."""
        return math.atan2(self.tip_le[0] - self.root_le[0], self.span)

    @property
    def corners(self) -> np.ndarray:
        """(4, 2) array: root LE, root TE, tip TE, tip LE (counter-clockwise seen from +z)."""
        return np.array([
            self.root_le,
            (self.root_le[0] + self.root_chord, self.root_le[1]),
            (self.tip_le[0] + self.tip_chord, self.tip_le[1]),
            self.tip_le,
        ])

    def point(self, xi: np.ndarray, eta: np.ndarray) -> np.ndarray:
        """Map chord fraction ``xi`` in [0, 1] and span fraction ``eta`` in [0, 1] to (x, y).

        Returns an array of shape ``broadcast(xi, eta).shape + (2,)``.
        """
        xi, eta = np.broadcast_arrays(np.asarray(xi, float), np.asarray(eta, float))
        x_le = self.root_le[0] + eta * (self.tip_le[0] - self.root_le[0])
        chord = self.root_chord + eta * (self.tip_chord - self.root_chord)
        y = self.root_le[1] + eta * self.span
        return np.stack([x_le + xi * chord, y], axis=-1)

    def chord_at(self, y: np.ndarray) -> np.ndarray:
        """Local streamwise chord (m) at spanwise station ``y``."""
        eta = (np.asarray(y, float) - self.root_le[1]) / self.span
        return self.root_chord + eta * (self.tip_chord - self.root_chord)

    def leading_edge_at(self, y: np.ndarray) -> np.ndarray:
        """x of the leading edge (m) at spanwise station ``y``."""
        eta = (np.asarray(y, float) - self.root_le[1]) / self.span
        return self.root_le[0] + eta * (self.tip_le[0] - self.root_le[0])

    def contains(self, points: np.ndarray, tol: float = 1e-9) -> np.ndarray:
        """Boolean mask: which (x, y) points lie on the planform (within ``tol`` m)."""
        p = np.atleast_2d(np.asarray(points, float))
        y = p[:, 1]
        x_le = self.leading_edge_at(y)
        c = self.chord_at(y)
        return ((y >= self.root_le[1] - tol) & (y <= self.tip_le[1] + tol)
                & (p[:, 0] >= x_le - tol) & (p[:, 0] <= x_le + c + tol))


#: NACA 65A010 basic thickness form: stations x/c and half-thickness y_t/c in per cent of the
#: chord (Abbott & von Doenhoff, *Theory of Wing Sections*, 1959; the same ordinates are the
#: "NACA 65A010" thickness form of OpenProp). A 65A00t section scales the ordinates by t / 10;
#: the full thickness is twice the half-thickness.
NACA65A010_X = (0.0, 0.5, 0.75, 1.25, 2.5, 5.0, 7.5, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0,
                45.0, 50.0, 55.0, 60.0, 65.0, 70.0, 75.0, 80.0, 85.0, 90.0, 95.0, 100.0)
NACA65A010_YT = (0.0, 0.765, 0.928, 1.183, 1.623, 2.182, 2.65, 3.04, 3.658, 4.127, 4.483, 4.742,
                 4.912, 4.995, 4.983, 4.863, 4.632, 4.304, 3.899, 3.432, 2.912, 2.352, 1.771,
                 1.188, 0.604, 0.021)


@dataclass(frozen=True)
class ChordwiseProfile:
    """Thickness relative to the section's nominal maximum, t / t_max, as a function of the
    chord fraction x / c in [0, 1], linear between tabulated points.

    Build one with :func:`chordwise_profile` from a name (``"flat"``, ``"biconvex"``,
    ``"NACA 0012"``, ``"NACA 65A004"``) or a table. ``x_over_c`` must run from 0 to 1, strictly
    ascending; ``t_over_tmax`` in [0, 1] (zero at an edge allowed) with a positive maximum.
    For NACA sections the ratio is taken to the nominal thickness (last two digits), so a
    tabulated maximum slightly below 1 (65A010: 0.999) is kept as published.
    """

    x_over_c: tuple[float, ...]
    t_over_tmax: tuple[float, ...]
    name: str = "table"

    def __post_init__(self):
        x = np.asarray(self.x_over_c, float)
        t = np.asarray(self.t_over_tmax, float)
        if x.ndim != 1 or x.shape != t.shape or x.size < 2:
            raise ValueError("profile table must hold at least two [x_over_c, t_over_tmax] pairs")
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(t))):
            raise ValueError("profile table must be finite")
        if abs(x[0]) > 1e-12 or abs(x[-1] - 1.0) > 1e-12 or np.any(np.diff(x) <= 0):
            raise ValueError("profile x_over_c must run strictly ascending from 0 to 1, "
                             f"got {x.tolist()}")
        if np.any(t < 0) or np.any(t > 1 + 1e-9) or t.max() <= 0:
            raise ValueError("profile t_over_tmax must lie in [0, 1] with a positive maximum, "
                             f"got {t.tolist()}")
        object.__setattr__(self, "x_over_c", tuple(float(v) for v in x))
        object.__setattr__(self, "t_over_tmax", tuple(float(v) for v in t))

    @property
    def is_flat(self) -> bool:
        return all(v == 1.0 for v in self.t_over_tmax)

    def at(self, xi) -> np.ndarray:
        """t / t_max at chord fraction(s) ``xi`` (clipped to [0, 1])."""
        return np.interp(np.clip(np.asarray(xi, float), 0.0, 1.0), self.x_over_c, self.t_over_tmax)

    def mean(self) -> float:
        """Chordwise mean of t / t_max (section area over t_max c), trapezoidal rule."""
        return float(np.trapezoid(self.t_over_tmax, self.x_over_c))


FLAT = ChordwiseProfile((0.0, 1.0), (1.0, 1.0), "flat")


def chordwise_profile(spec) -> ChordwiseProfile:
    """A :class:`ChordwiseProfile` from a name or a table.

    Parameters
    ----------
    spec : ``"flat"``; ``"biconvex"`` (circular-arc section in the thin-section limit,
        t / t_max = 4 xi (1 - xi)); ``"NACA 00tt"`` (symmetric 4-digit section,
        t / t_max = 10 (0.2969 sqrt(xi) - 0.1260 xi - 0.3516 xi^2 + 0.2843 xi^3 - 0.1015 xi^4),
        Abbott & von Doenhoff 1959, Sec. 6.4, on 201 cosine-spaced points); ``"NACA 65A0tt"``
        (the 65A010 basic thickness form :data:`NACA65A010_YT`); or a sequence of
        ``[x_over_c, t_over_tmax]`` pairs.

    The name gives only the *shape*; the thickness in metres comes from :class:`Thickness`
    (``root``, ``tip`` are the section's nominal maximum thickness). Cambered sections are
    refused: the plate and the lifting surface are flat.
    """
    if isinstance(spec, ChordwiseProfile):
        return spec
    if isinstance(spec, str):
        s = spec.strip().upper().replace("NACA", "").replace("-", "").strip()
        if s == "FLAT":
            return FLAT
        if s == "BICONVEX":
            xi = np.linspace(0.0, 1.0, 201)
            return ChordwiseProfile(tuple(xi), tuple(4 * xi * (1 - xi)), "biconvex")
        if len(s) == 4 and s.isdigit():
            if s[:2] != "00":
                raise ValueError(f"profile {spec!r}: only symmetric NACA 4-digit sections "
                                 "(NACA 00tt) are allowed; camber does not enter a flat plate")
            xi = 0.5 * (1 - np.cos(np.linspace(0.0, math.pi, 201)))
            t = 10 * (0.2969 * np.sqrt(xi) - 0.1260 * xi - 0.3516 * xi**2 + 0.2843 * xi**3
                      - 0.1015 * xi**4)
            return ChordwiseProfile(tuple(xi), tuple(np.clip(t, 0.0, 1.0)), f"NACA {s}")
        if len(s) == 6 and s[:3] == "65A" and s[3:].isdigit():
            if s[3] != "0":
                raise ValueError(f"profile {spec!r}: only symmetric 65A0tt sections are allowed")
            return ChordwiseProfile(tuple(v / 100 for v in NACA65A010_X),
                                    tuple(v / 5.0 for v in NACA65A010_YT), f"NACA {s}")
        raise ValueError(f"profile {spec!r} is not known: use 'flat', 'biconvex', 'NACA 00tt', "
                         "'NACA 65A0tt' or a table [[x_over_c, t_over_tmax], ...]")
    try:
        table = np.asarray(spec, float)
    except (TypeError, ValueError):
        raise ValueError(f"profile must be a name or a table of [x_over_c, t_over_tmax] pairs, "
                         f"got {spec!r}") from None
    if table.ndim != 2 or table.shape[1] != 2:
        raise ValueError(f"profile table must be a list of [x_over_c, t_over_tmax] pairs, "
                         f"got shape {table.shape}")
    return ChordwiseProfile(tuple(table[:, 0]), tuple(table[:, 1]), "table")


@dataclass(frozen=True)
class Thickness:
    """Plate thickness: the section's maximum thickness varies linearly along the span from
    ``root`` to ``tip`` (m, > 0) and is multiplied by a chordwise ``profile`` (t / t_max of
    the chord fraction, default flat):

        h(x, y) = [root + eta (tip - root)] * profile((x - x_le(y)) / c(y)),  eta in [0, 1].
    """

    root: float
    tip: float
    profile: ChordwiseProfile = FLAT

    def __post_init__(self):
        positive("thickness root", self.root)
        positive("thickness tip", self.tip)
        object.__setattr__(self, "profile", chordwise_profile(self.profile))

    def at(self, eta: np.ndarray) -> np.ndarray:
        """Maximum (section) thickness (m) at span fraction ``eta`` in [0, 1]."""
        return self.root + np.asarray(eta, float) * (self.tip - self.root)

    @property
    def is_table(self) -> bool:
        """False: a root/tip law (:class:`ThicknessTable` says True)."""
        return False


def _grid(name: str, values) -> tuple[float, ...]:
    v = tuple(float(x) for x in values)
    if len(v) < 2 or v[0] != 0.0 or v[-1] != 1.0 or any(b <= a for a, b in zip(v, v[1:])):
        raise ValueError(f"{name} must be strictly ascending from 0 to 1 with at least two "
                         f"values, got {list(v)}")
    return v


def _hat_weights(grid: tuple[float, ...], t: np.ndarray) -> np.ndarray:
    """(t.shape + (len(grid),)) piecewise-linear interpolation weights of ``t`` (clipped to
    [0, 1]) on ``grid``: the hat functions, summing to one."""
    g = np.asarray(grid)
    t = np.clip(np.asarray(t, float), 0.0, 1.0)
    i = np.clip(np.searchsorted(g, t, side="right") - 1, 0, g.size - 2)
    f = (t - g[i]) / (g[i + 1] - g[i])
    w = np.zeros(t.shape + (g.size,))
    np.put_along_axis(w, i[..., None], (1.0 - f)[..., None], axis=-1)
    np.put_along_axis(w, (i + 1)[..., None], f[..., None], axis=-1)
    return w


def _check_table_cells(rows) -> None:
    """Refuse a thickness table with a cell (between neighbouring eta and x_over_c stations)
    whose four corner values are all zero: h = 0 over an area of the plate, which has no
    stiffness there. Zero at an edge or on a line (a sharp leading or trailing edge, the corner
    thicknesses of Nastran's bevelled CQUAD4 rows) is allowed: h > 0 inside every cell."""
    v = np.asarray(rows, float)
    empty = (v[:-1, :-1] == 0) & (v[1:, :-1] == 0) & (v[:-1, 1:] == 0) & (v[1:, 1:] == 0)
    if empty.any():
        i, j = (int(k) for k in np.argwhere(empty)[0])
        raise ValueError(f"values_m[{i}..{i + 1}][{j}..{j + 1}] are all zero: the plate would "
                         f"have no thickness between those stations; at least one corner of "
                         f"every cell must be > 0")


@dataclass(frozen=True)
class ThicknessTable:
    """Plate thickness tabulated over the panel and interpolated bilinearly (m):

        h(xi, eta) = sum_ij values[i][j] H_i(eta) H_j(xi),

    with xi the chord fraction, eta the span fraction (both in [0, 1]) and H the piecewise-linear
    hat functions of the grids ``eta`` and ``x_over_c`` (each strictly ascending from 0 to 1).
    ``values[i][j]`` (m, >= 0; zero allowed at a sharp edge, but every cell of the grid needs a
    corner > 0) is the thickness at span station ``eta[i]`` and chord fraction ``x_over_c[j]``. h is linear in the values, so dh/dvalues[i][j] = H_i(eta) H_j(xi)
    (:meth:`weights`).

    Examples
    --------
    >>> t = ThicknessTable((0.0, 1.0), (0.0, 1.0), ((0.004, 0.004), (0.002, 0.002)))
    >>> float(t.at(0.3, 0.5)), t.root, t.tip
    (0.003, 0.004, 0.002)
    """

    x_over_c: tuple[float, ...]
    eta: tuple[float, ...]
    values: tuple[tuple[float, ...], ...]

    def __post_init__(self):
        object.__setattr__(self, "x_over_c", _grid("x_over_c", self.x_over_c))
        object.__setattr__(self, "eta", _grid("eta", self.eta))
        rows = tuple(tuple(float(v) for v in row) for row in self.values)
        if len(rows) != len(self.eta) or any(len(r) != len(self.x_over_c) for r in rows):
            raise ValueError(f"values_m must hold {len(self.eta)} rows (one per eta) of "
                             f"{len(self.x_over_c)} values (one per x_over_c)")
        for i, r in enumerate(rows):
            for j, v in enumerate(r):
                if not (math.isfinite(v) and v >= 0.0):
                    raise ValueError(f"values_m[{i}][{j}] must be a finite number >= 0, got {v!r}")
        _check_table_cells(rows)
        object.__setattr__(self, "values", rows)

    @property
    def is_table(self) -> bool:
        return True

    @property
    def shape(self) -> tuple[int, int]:
        """(len(eta), len(x_over_c))."""
        return len(self.eta), len(self.x_over_c)

    @property
    def root(self) -> float:
        """The root section's maximum thickness (m)."""
        return max(self.values[0])

    @property
    def tip(self) -> float:
        """The tip section's maximum thickness (m)."""
        return max(self.values[-1])

    def weights(self, xi, eta) -> np.ndarray:
        """dh/dvalues: (xi.shape + (n_eta, n_xc)) bilinear weights H_i(eta) H_j(xi)."""
        xi, eta = np.broadcast_arrays(np.asarray(xi, float), np.asarray(eta, float))
        return (_hat_weights(self.eta, eta)[..., :, None]
                * _hat_weights(self.x_over_c, xi)[..., None, :])

    def at(self, xi, eta) -> np.ndarray:
        """h (m) at chord fraction ``xi`` and span fraction ``eta`` (clipped to [0, 1])."""
        return np.einsum("...ij,ij->...", self.weights(xi, eta), np.asarray(self.values))


#: The reference fin's law (flat, linear along the span) is a :class:`Thickness` with the
#: default flat profile; the old name is kept.
LinearThickness = Thickness


@dataclass(frozen=True)
class ThicknessField:
    """h(x, y) (m) over a surface of one or more trapezoidal ``panels`` joined spanwise: the
    spanwise law of ``thickness`` runs over the whole span (first root to last tip), the
    chord fraction is taken in the panel that holds the point. A :class:`ThicknessTable` is
    interpolated at (chord fraction, span fraction)."""

    panels: tuple[Planform, ...]
    thickness: Thickness | ThicknessTable

    def fractions(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(xi, eta): the chord fraction in the panel holding (x, y) and the span fraction."""
        x, y = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float))
        y0, y1 = self.panels[0].root_le[1], self.panels[-1].tip_le[1]
        xi = np.zeros_like(x)
        for i, p in enumerate(self.panels):
            sel = (y >= p.root_le[1] - 1e-12) if i else np.ones(y.shape, bool)
            xi = np.where(sel, (x - p.leading_edge_at(y)) / p.chord_at(y), xi)
        return xi, (y - y0) / (y1 - y0)

    def __call__(self, x, y) -> np.ndarray:
        xi, eta = self.fractions(x, y)
        if self.thickness.is_table:
            return self.thickness.at(xi, eta)
        h = self.thickness.at(eta)
        if self.thickness.profile.is_flat:
            return h
        return h * self.thickness.profile.at(xi)


def _check_material_number(name: str, value) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0 or v > 1e15:
        raise ValueError(f"{name} must be > 0 and at most 1e15 (SI units), got {value!r}")
    return v


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material: E (Pa), nu (-), density (kg/m^3)."""

    youngs_modulus: float
    poisson_ratio: float
    density: float
    name: str = ""

    def __post_init__(self):
        _check_material_number("youngs_modulus", self.youngs_modulus)
        _check_material_number("density", self.density)
        nu = float(self.poisson_ratio)
        if not (-1.0 < nu < 0.5):
            raise ValueError(f"poisson_ratio must lie in (-1, 0.5), got {nu!r}")

    def plane_stress_matrix(self) -> np.ndarray:
        """Plane-stress stiffness Q (3 x 3, Pa) relating [s_xx, s_yy, s_xy] to the engineering
        strains [e_xx, e_yy, g_xy]: E / (1 - nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu)/2]]."""
        E, nu = self.youngs_modulus, self.poisson_ratio
        return E / (1 - nu**2) * np.array([[1, nu, 0], [nu, 1, 0], [0, 0, (1 - nu) / 2]])

    def transverse_shear_matrix(self) -> np.ndarray:
        """Transverse shear moduli (2 x 2, Pa) relating [s_xz, s_yz] to [g_xz, g_yz]: G I."""
        return self.youngs_modulus / (2 * (1 + self.poisson_ratio)) * np.eye(2)


@dataclass(frozen=True)
class OrthotropicMaterial:
    """Orthotropic lamina in plane stress (laminated wood, a unidirectional composite).

    e1, e2 : Young's moduli along and across the fibres (Pa); g12 in-plane shear modulus (Pa);
    nu12 major Poisson ratio (nu21 = nu12 e2 / e1); density (kg/m^3); g13, g23 transverse shear
    moduli (Pa; default g12 -- the transverse shear of a thin plate hardly matters);
    fibre_angle : angle of the fibre direction 1 from +x toward +y (rad).

    Q in material axes is [[e1, nu12 e2, 0], [nu12 e2, e2, 0], [0, 0, g12 d]] / d,
    d = 1 - nu12 nu21; in the x-y axes Q_xy = T^T Q T with the engineering-strain rotation
    [e_11, e_22, g_12] = T [e_xx, e_yy, g_xy], T = [[c^2, s^2, c s], [s^2, c^2, -c s],
    [-2 c s, 2 c s, c^2 - s^2]] (c, s of the fibre angle; strain energy is invariant; cf. Jones,
    *Mechanics of Composite Materials*, 2nd ed., Sec. 2.6). Positive definiteness needs
    nu12^2 < e1 / e2.
    """

    e1: float
    e2: float
    g12: float
    nu12: float
    density: float
    g13: float | None = None
    g23: float | None = None
    fibre_angle: float = 0.0
    name: str = ""

    def __post_init__(self):
        for nm in ("e1", "e2", "g12", "density"):
            _check_material_number(nm, getattr(self, nm))
        for nm in ("g13", "g23"):
            if getattr(self, nm) is None:
                object.__setattr__(self, nm, float(self.g12))
            _check_material_number(nm, getattr(self, nm))
        nu = float(self.nu12)
        lim = math.sqrt(self.e1 / self.e2)
        if not math.isfinite(nu) or not -lim < nu < lim:
            raise ValueError(f"nu12 must satisfy nu12^2 < e1/e2 = {self.e1 / self.e2:.4g} "
                             f"(positive definite), got {self.nu12!r}")
        if not math.isfinite(float(self.fibre_angle)):
            raise ValueError(f"fibre_angle must be finite (rad), got {self.fibre_angle!r}")

    def plane_stress_matrix(self) -> np.ndarray:
        """Q_xy (3 x 3, Pa) for engineering strains [e_xx, e_yy, g_xy] in the x-y axes."""
        nu21 = self.nu12 * self.e2 / self.e1
        d = 1 - self.nu12 * nu21
        Q = np.array([[self.e1 / d, self.nu12 * self.e2 / d, 0.0],
                      [self.nu12 * self.e2 / d, self.e2 / d, 0.0],
                      [0.0, 0.0, self.g12]])
        c, s = math.cos(self.fibre_angle), math.sin(self.fibre_angle)
        T = np.array([[c * c, s * s, c * s], [s * s, c * c, -c * s],
                      [-2 * c * s, 2 * c * s, c * c - s * s]])
        Qxy = T.T @ Q @ T
        return 0.5 * (Qxy + Qxy.T)                 # exactly symmetric

    def transverse_shear_matrix(self) -> np.ndarray:
        """Transverse shear moduli in x-y axes (2 x 2, Pa): R^T diag(g13, g23) R with
        [g_1z, g_2z] = R [g_xz, g_yz], R = [[c, s], [-s, c]]."""
        c, s = math.cos(self.fibre_angle), math.sin(self.fibre_angle)
        R = np.array([[c, s], [-s, c]])
        G = R.T @ np.diag([self.g13, self.g23]) @ R
        return 0.5 * (G + G.T)


