"""An imported structural model and doublet-lattice boxes that a :class:`~asekit.case.Case`
carries instead of its declarative panels, thickness and material (e.g. a Nastran deck read by
:func:`asekit.io.bdf.read_bdf`).

The case pipeline (:mod:`asekit.case.pipeline`) uses it when ``case.structure`` is not None:
the mesh, the global stiffness and mass (plus the case's point masses) and the deck's own
supports -- the reduction u = T q of its SPC / GRID PS constraints and RBE2 rigid links, its
CELAS springs already in K -- replace the plate assembly and the support kind; its boxes
replace the panels' box mesh. Everything downstream (modes, GAF database, p-k flutter,
report, sweeps of the aero and flight keys) is the pipeline's.

An :class:`ImportedModel` is frozen and hashable by content: :attr:`ImportedModel.digest`,
the SHA-256 of its arrays, is its ``__hash__`` / ``__eq__`` (so ``lru_cache`` on a case works)
and enters :meth:`asekit.case.schema.Case.fingerprint`.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from asekit.aero.boxes import BoxMesh
from asekit.structure.assembly import SupportedSystem
from asekit.structure.mesh import PlateMesh

#: The support kind of a case whose supports are those of its imported model.
IMPORTED_SUPPORT = "imported"


def _update(h, a) -> None:
    a = np.ascontiguousarray(a)
    h.update(str((a.dtype.str, a.shape)).encode())
    h.update(a.tobytes())


def _update_sparse(h, A) -> None:
    A = sp.csr_matrix(A)
    A.sum_duplicates()
    A.sort_indices()
    _update(h, np.asarray(A.shape))
    for a in (A.indptr, A.indices, A.data):
        _update(h, a)


@dataclass(frozen=True, eq=False)
class ImportedModel:
    """A structure (and optionally boxes) built outside the case's declarative specs, in SI.

    Parameters
    ----------
    mesh : PlateMesh
        The plate mesh (nodes (n_nodes, 2) m, elements, corner thicknesses m).
    K, M : scipy.sparse matrix, (3 n_nodes, 3 n_nodes)
        Global stiffness (N/m, N m/rad...) and mass (kg, kg m^2) over the DOFs (w, theta_x,
        theta_y) of every node, springs in K, point masses and non-structural mass in M.
    T : scipy.sparse matrix, (3 n_nodes, n_q)
        The support reduction u = T q: the constrained DOFs removed, the dependent DOFs of
        rigid links written in terms of their independent ones (K_q = T^T K T, M_q = T^T M T).
    boxes : BoxMesh or None
        The doublet-lattice boxes (m, in the structure's plane z = 0); None: no aerodynamics.
    damping_g : tuple of (frequency Hz, g) or None
        A structural-damping table applied at each mode's frequency (g interpolated, zeta =
        g / 2) when the case's ``damping`` gives nothing (e.g. Nastran's TABDMP1).
    support : str
        What holds the structure, in words (e.g. "SPC1 345 on 7 grids"), for reports.
    label : str
        A description of the model, e.g. "BDF ha145e.bdf: 40 CQUAD4, 55 GRID".
    deck : object
        The importer's own record of the source (e.g. :class:`asekit.io.bdf.BdfModel`, with the
        Nastran ids for the export); not part of the digest, equality or hash.
    panels : tuple of TrapezoidSurface
        The lifting surfaces the boxes were made of (e.g. the CAERO1 cards), for the control
        surfaces' hinged boxes (:func:`asekit.case.pipeline.control_surface_mesh`); () when
        not needed. In the digest when given.

    Attributes
    ----------
    digest : str
        SHA-256 (hex) of mesh, K, M, T, boxes and damping table: the model's identity.
    """

    mesh: PlateMesh
    K: sp.csr_matrix
    M: sp.csr_matrix
    T: sp.csr_matrix
    boxes: BoxMesh | None = None
    damping_g: tuple[tuple[float, float], ...] | None = None
    support: str = "the imported model's constraints"
    label: str = "imported model"
    deck: object = field(default=None, repr=False)
    panels: tuple = ()
    digest: str = field(init=False, repr=False)

    def __post_init__(self):
        n = 3 * self.mesh.n_nodes
        for name in ("K", "M", "T"):
            A = sp.csr_matrix(getattr(self, name))
            if A.shape[0] != n or (name != "T" and A.shape[1] != n):
                raise ValueError(f"ImportedModel.{name} must have {n} rows (3 DOFs x "
                                 f"{self.mesh.n_nodes} nodes){'' if name == 'T' else ' and columns'}"
                                 f", got shape {A.shape}")
            object.__setattr__(self, name, A)
        h = hashlib.sha256()
        for a in (self.mesh.nodes, self.mesh.elements, self.mesh.corner_thickness
                  if self.mesh.corner_thickness is not None else np.zeros(0)):
            _update(h, np.asarray(a))
        for A in (self.K, self.M, self.T):
            _update_sparse(h, A)
        if self.boxes is not None:
            for a in (self.boxes.corners, self.boxes.strip, self.boxes.surface):
                _update(h, np.asarray(a))
        _update(h, np.asarray(self.damping_g if self.damping_g else [], float))
        for p in self.panels:          # (absent: the digests of models without panels stay)
            _update(h, np.r_[p.root_le, p.root_chord, p.tip_le, p.tip_chord, p.n_chord,
                             p.n_span])
        object.__setattr__(self, "digest", h.hexdigest())

    def __eq__(self, other):
        if not isinstance(other, ImportedModel):
            return NotImplemented
        return self.digest == other.digest

    def __hash__(self):
        return hash(self.digest)

    def supported_system(self, K=None, M=None) -> SupportedSystem:
        """The supported system K_q = T^T K T, M_q = T^T M T for the eigen-analysis.

        Parameters
        ----------
        K, M : scipy.sparse matrix, optional
            Global matrices to reduce (default the model's own; the pipeline passes M with the
            case's point masses added).

        Returns
        -------
        SupportedSystem
            With no shaft (shaft_index = ground_index = None): the imported constraints hold
            the structure as they are.
        """
        K = self.K if K is None else K
        M = self.M if M is None else M
        Kq = (self.T.T @ K @ self.T).tocsr()
        Mq = (self.T.T @ M @ self.T).tocsr()
        return SupportedSystem(K=Kq, M=Mq, T=self.T, shaft_index=None, ground_index=None,
                               fictitious_inertia=0.0,
                               shaft_nodes=np.array([], dtype=np.int64), mesh=self.mesh,
                               label=f"{self.label}; held by {self.support}")

    def structural_g_at(self, frequencies_hz) -> np.ndarray | None:
        """The damping table's g at ``frequencies_hz`` (Hz; linear interpolation, constant
        beyond the ends), or None without a table."""
        if not self.damping_g:
            return None
        f, g = np.array(self.damping_g, float).T
        return np.interp(np.asarray(frequencies_hz, float), f, g)
