"""The documentation's corrected figures, measured (issue 14).

* docs/models.md (the README's model table until issue 30) / docs/physics.md: Oren-Nayar is **not** energy conserving at small
  roughness near grazing (kd = 1: full model 1.044 at sigma = 0.3, qualitative
  1.014 at sigma = 0.2, both at 89°).
* docs/htsg.md: the Kirchhoff series' worst measured error is 1.6e-7 (at the
  asymptotic tier's lower corner, g = 40), not the 4e-8 stated before.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis import check


def test_full_oren_nayar_exceeds_one_near_grazing():
    r = check(bk.model("oren-nayar", kd=1.0, sigma=0.3, variant="full"), level="fast")
    assert not r["energy_conserving"]
    assert r["max_albedo"] == pytest.approx(1.044, abs=2e-3)  # the figure written in models.md and physics.md
    assert r["max_albedo_theta_deg"] >= 85
    q = check(bk.model("oren-nayar", kd=1.0, sigma=0.2, variant="qualitative"), level="fast")
    assert not q["energy_conserving"] and q["max_albedo"] == pytest.approx(1.014, abs=2e-3)
    q = check(bk.model("oren-nayar", kd=1.0, sigma=0.5, variant="qualitative"), level="fast")
    assert q["energy_conserving"] and q["max_albedo"] == pytest.approx(0.948, abs=2e-3)


def test_documents_state_the_oren_nayar_figures():
    """The figures checked above are the ones written (the model table moved from the README to docs/models.md)."""
    docs = Path(__file__).resolve().parents[1] / "docs"
    row = next(ln for ln in (docs / "models.md").read_text().splitlines() if ln.startswith("| `oren-nayar`"))
    assert "full 1.044 at σ = 0.3" in row and "qualitative 1.014 at σ = 0.2" in row and "θ = 89°" in row
    physics = (docs / "physics.md").read_text()
    assert "1.044" in physics and "1.014" in physics


def test_htsg_series_error_is_as_documented():
    pytest.importorskip("mpmath")
    from brdfkit.models import htsg as H
    from _htsg_reference import mp_series

    worst = 0.0
    for g in (40.0, 41.5, 43.0, 45.0, 60.0):
        amax = H.ASYMPTOTIC_A_SCALE * g**H.ASYMPTOTIC_A_POWER
        for a in np.linspace(0.0, amax, 7):
            got = float(H.htsg_series(np.array([g]), np.array([a * g]))[0])
            worst = max(worst, abs(got / float(mp_series(g, a * g)) - 1))
    assert worst <= 1.7e-7  # docs/htsg.md: worst 1.6e-7 (and always inside the tests' 1e-6)
