"""Codim-2 points (:mod:`impactcont.detection.codim2`): a strong resonance has one name on
every curve, and every codim-2 label has its standard name in the docs."""

from __future__ import annotations

import numpy as np
import pytest

import impactcont as ic


@pytest.mark.parametrize("kind, multipliers, label", [
    ("SN", [1.0, 1.0 + 1e-5, 0.3], "R1"),          # a double +1: the 1:1 resonance
    ("SN", [1.0, 1.0 + 2e-5j, 0.3], "R1"),         # its Jordan block split into a pair
    ("PD", [-1.0, -1.0 - 1e-5, 0.2], "R2"),        # a double -1: the 1:2 resonance
    ("SN", [1.0, np.exp(0.4j), np.exp(-0.4j)], "SN+NS"),
])
def test_a_strong_resonance_has_one_name_on_every_curve(kind, multipliers, label):
    """The NS curve ends at R1/R2; the SN and PD curves meeting them there name them so."""
    from types import SimpleNamespace

    from impactcont.detection.codim2 import _name
    from impactcont.vocabulary import CODIM2_LABELS

    assert _name(kind, "NS", SimpleNamespace(multipliers=np.array(multipliers))) == label
    assert not {"SN+SN", "PD+PD"} & set(CODIM2_LABELS)


def test_every_codim2_label_has_its_standard_name_in_the_docs():
    from pathlib import Path

    from impactcont.vocabulary import CODIM2_LABELS

    docs = Path(ic.__file__).resolve().parents[1] / "docs" / "two_parameter.md"
    rows = {line.split("|")[1].strip().strip("`") for line in docs.read_text().splitlines()
            if line.startswith("| `")}
    assert set(CODIM2_LABELS) <= rows, sorted(set(CODIM2_LABELS) - rows)
