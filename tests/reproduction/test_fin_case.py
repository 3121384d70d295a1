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
