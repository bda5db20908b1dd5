"""The linear projector pair's speed-up over Siddon's lines is stated as one measured number
(about 20× at 256², the reconstruction guide's SIRT example): every speed claim in the
reconstruction package's code says that number or refers to it; none states another
(LinearProjector's docstring said "about ten times" while projector_name said 20×). Texts
only: no timing is measured here."""

from __future__ import annotations

import pathlib
import re

import meshladar.reconstruct as reconstruct
from meshladar.reconstruct.operators import LinearProjector, projector_name

PACKAGE = pathlib.Path(reconstruct.__file__).parent
CLAIM = re.compile(r"(\S+)\s*(?:×|times)\s+faster")


def test_every_speed_claim_states_the_one_measured_number():
    claims = {(path.name, m.group(0)) for path in sorted(PACKAGE.glob("*.py"))
              for m in CLAIM.finditer(path.read_text(encoding="utf-8"))}
    assert claims, "the measured speed-up is stated somewhere"
    assert {c for c in claims if not c[1].startswith("20×")} == set()


def test_the_projector_refers_to_the_measurement_instead_of_repeating_it():
    doc = " ".join(LinearProjector.__doc__.split())
    assert "Faster than Siddon lines (the measured speed-up is in :func:`projector_name`)" \
        in doc
    assert "measured on the reconstruction guide's SIRT example" in " ".join(
        projector_name.__doc__.split())
