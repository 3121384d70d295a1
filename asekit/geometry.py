"""Trapezoidal lifting surfaces and the reference fin definition.

Axes: x chordwise (downstream, the free-stream direction), y spanwise, z normal (up). A positive
rotation about +y moves the trailing edge down: nose-up, i.e. a positive angle of attack.

The reference fin is defined once, in ``data/fin.toml``; :func:`load_fin` reads it.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .paths import FIN_FILE
from .validate import positive


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


@dataclass(frozen=True)
class LinearThickness:
    """Plate thickness varying linearly along the span from ``root`` to ``tip`` (m)."""

    root: float
    tip: float

    def __post_init__(self):
        positive("thickness root", self.root)
        positive("thickness tip", self.tip)

    def at(self, eta: np.ndarray) -> np.ndarray:
        """Thickness (m) at span fraction ``eta`` in [0, 1]."""
        return self.root + np.asarray(eta, float) * (self.tip - self.root)


@dataclass(frozen=True)
class Material:
    """Isotropic linear-elastic material: E (Pa), nu (-), density (kg/m^3)."""

    youngs_modulus: float
    poisson_ratio: float
    density: float
    name: str = ""

    def __post_init__(self):
        positive("youngs_modulus", self.youngs_modulus)
        positive("density", self.density)
        nu = float(self.poisson_ratio)
        if not (-1.0 < nu < 0.5):
            raise ValueError(f"poisson_ratio must lie in (-1, 0.5), got {nu!r}")


@dataclass(frozen=True)
class Shaft:
    """The fin's pitch shaft: a spanwise axis through ``axis_point`` (x, y) in m.

    torsional_stiffness (N m/rad) is the FN1 spring; radius (m) the physical shaft region used by
    the distributed (rigid multi-point) shaft model; fictitious_inertia_factor the FN2 multiplier.
    """

    axis_point: tuple[float, float]
    torsional_stiffness: float
    radius: float
    fictitious_inertia_factor: float = 1.0e6

    def __post_init__(self):
        object.__setattr__(self, "axis_point", tuple(float(v) for v in self.axis_point))
        positive("torsional_stiffness", self.torsional_stiffness)
        positive("radius", self.radius)
        positive("fictitious_inertia_factor", self.fictitious_inertia_factor)


@dataclass(frozen=True)
class AeroSettings:
    """Aerodynamic analysis settings of a fin (SI): reference semi-chord b for k = omega b / U,
    Mach numbers of the GAF database, the highest structural frequency of interest (Hz), the
    analysis speed range (m/s) and altitudes (m)."""

    reference_semichord: float
    machs: tuple[float, ...]
    f_max: float
    u_min: float
    u_max: float
    altitudes: tuple[float, ...]

    @property
    def k_max(self) -> float:
        """Highest reduced frequency needed: 2 pi f_max b / U_min."""
        return 2.0 * math.pi * self.f_max * self.reference_semichord / self.u_min


@dataclass(frozen=True)
class FinDefinition:
    """Everything that defines a fin: planform, thickness law, material, shaft, default FE mesh
    (n_chord x n_span elements) and aerodynamic settings."""

    planform: Planform
    thickness: LinearThickness
    material: Material
    shaft: Shaft
    n_chord: int
    n_span: int
    aero: AeroSettings


def load_fin(path: str | Path = FIN_FILE) -> FinDefinition:
    """Read a fin definition from a TOML file (default: the reference fin, ``data/fin.toml``)."""
    with open(path, "rb") as fh:
        d = tomllib.load(fh)
    p, t, m, s, mesh, a = (d["planform"], d["thickness"], d["material"], d["shaft"], d["mesh"],
                          d["aero"])
    return FinDefinition(
        planform=Planform(tuple(p["root_leading_edge"]), p["root_chord"],
                          tuple(p["tip_leading_edge"]), p["tip_chord"]),
        thickness=LinearThickness(t["root"], t["tip"]),
        material=Material(m["youngs_modulus"], m["poisson_ratio"], m["density"], m.get("name", "")),
        shaft=Shaft(tuple(s["axis_point"]), s["torsional_stiffness"], s["radius"],
                    s.get("fictitious_inertia_factor", 1.0e6)),
        n_chord=int(mesh["n_chord"]),
        n_span=int(mesh["n_span"]),
        aero=AeroSettings(a["reference_semichord"], tuple(a["machs"]), a["f_max"], a["u_min"],
                          a["u_max"], tuple(a["altitudes"])),
    )
