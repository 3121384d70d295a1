"""Shared checks of the stick-deck tests (tests/io): a deck read back equals the beam it was
written from."""

import numpy as np


def assert_deck_is_the_beam(sm, beam, n_modes: int = 6) -> None:
    """The stick model ``sm`` (:func:`asekit.io.bdf_beam.read_stick_deck`) of a deck written
    from ``beam`` has the beam's stiffness and mass (root node's six DOFs aside: the deck
    clamps them) to 1e-12 of their largest entry, and its first ``n_modes`` frequencies to
    1e-9 (:func:`asekit.structure.beam.beam_modes`)."""
    from asekit.io.bdf_beam import stick_modes
    from asekit.structure.beam import assemble, beam_modes

    K, M = assemble(beam)
    free = slice(6, None)
    assert np.abs(sm.K[free, free] - K[free, free]).max() <= 1e-12 * np.abs(K).max()
    assert np.abs(sm.M[free, free] - M[free, free]).max() <= 1e-12 * np.abs(M).max()
    np.testing.assert_allclose(stick_modes(sm, n_modes).frequencies_hz,
                               beam_modes(beam, n_modes).frequencies_hz, rtol=1e-9)
