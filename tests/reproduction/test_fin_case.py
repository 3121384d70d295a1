"""The reproduction runs on the fin's case: ``asekit.reproduction.fin`` defines no model of its
own, its variants are replacements of the case, and the shipped GAF database
(``data/gaf_fin.npz``) is the one the pipeline asks for."""

from __future__ import annotations

import dataclasses
import inspect

from asekit.aero.gaf import GAF_FILE, database_settings, mode_set_fingerprint
from asekit.case import load_case, pipeline
from asekit.reproduction import fin
from asekit.util.cache import load_npz
from asekit.util.paths import FIN_FILE


def test_fin_module_defines_no_model_class():
    own = [n for n, v in vars(fin).items()
           if inspect.isclass(v) and v.__module__ == fin.__name__]
    assert own == []


def _changed(a, b) -> set[str]:
    return {f.name for f in dataclasses.fields(a) if getattr(a, f.name) != getattr(b, f.name)}


def test_variants_replace_only_what_they_vary():
    case = fin.fin_case()
    assert case == load_case(FIN_FILE)
    assert _changed(fin.fn1_case(), case) == {"support", "modes", "actuator"}
    d = fin.distributed_case(12, 14)
    assert _changed(d, case) == {"support", "panels"}
    assert d.support.radius == fin.DEFAULT_SHAFT_RADIUS
    assert (d.panels[0].n_chord, d.panels[0].n_span) == (12, 14)
    assert pipeline.modal_model(fin.fn1_case()).n_rigid == 0


def test_shipped_gaf_database_is_the_pipelines():
    """The fingerprint the pipeline asks for is the shipped file's, so no rebuild happens."""
    case = fin.fin_case()
    a = case.aero
    settings = database_settings(a.machs, pipeline.reduced_frequencies(case),
                                 a.reference_semichord, pipeline.box_mesh(case),
                                 a.symmetry == "wall", a.kernel)
    _, meta = load_npz(GAF_FILE)
    assert meta["fingerprint"] == mode_set_fingerprint(pipeline.modal_model(case), settings)
    db = pipeline.gaf_database(case, progress=False)
    assert db.metadata["fingerprint"] == meta["fingerprint"]


def test_fig4_thickness_comes_from_the_case_law():
    """Issue 30: Fig 4 and its check read the thickness from the case (not from the reference
    numbers): a fin with a 3 -> 1 mm law gives 3 and 1 mm at the root and tip chords, and the
    assembled mass equals rho * integral of c(y) h(y) dy. For the trapezoid (chord 156 -> 78
    mm, span 150 mm, data/cases/nalci2013_fin.toml) and h = 3 - 2 eta mm that integral is
    0.150 m * (156*3 - (156*2 + 78*3)/2 + 78*2/3) mm^2 = 0.150 * 247 mm^2 = 37.05 mm^2 m,
    times 2700 kg/m^3: 100.035 g."""
    from asekit.geometry import Thickness
    from asekit.reproduction import structure as rs

    case = dataclasses.replace(fin.fin_case(), thickness=Thickness(0.003, 0.001))
    c = rs.thickness_check(case)
    assert abs(c.root_mm - 3.0) < 1e-9 and abs(c.tip_mm - 1.0) < 1e-9
    assert abs(c.exact_mass / 0.100035 - 1) < 1e-9
    assert abs(c.fe_mass / c.exact_mass - 1) < 1e-9
