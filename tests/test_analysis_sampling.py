"""Sampling routines: χ² goodness of fit against their own pdf (as Mitsuba 3 / pbrt-v4 test),
and Monte Carlo albedo with them agrees with the quadrature."""

from __future__ import annotations

import math
import zlib

import numpy as np
import pytest

import brdfkit as bk
from brdfkit.analysis import albedo
from brdfkit.analysis.sampling import (
    BlinnLobe,
    CosineHemisphere,
    GGXVisible,
    MicrofacetH,
    Mixture,
    PhongLobe,
    albedo_mc,
    chi2_test,
    sampler_for,
)

WOS = {
    "normal": np.array([0.0, 0.0, 1.0]),
    "57deg": np.array([math.sin(1.0), 0.0, math.cos(1.0)]),
    "80deg-offaxis": np.array([math.sin(1.4) * math.cos(0.5), math.sin(1.4) * math.sin(0.5), math.cos(1.4)]),
}
SAMPLERS = {
    "cosine": CosineHemisphere(),
    "phong-2": PhongLobe(2.0),
    "phong-50": PhongLobe(50.0),
    "blinn-50": BlinnLobe(50.0),
    "beckmann-0.2x0.5": MicrofacetH("beckmann", 0.2, 0.5),
    "ggx-0.3": MicrofacetH("ggx", 0.3, 0.3),
    "ggx-vndf-0.3": GGXVisible(0.3, 0.3),
    "ggx-vndf-0.1x0.4": GGXVisible(0.1, 0.4),
    "mixture": Mixture([CosineHemisphere(), PhongLobe(30.0)], [0.3, 0.7]),
}
# 27 tests at a family-wise level of 1 %: Šidák per-test level ≈ 3.7e-4
ALPHA = 1 - 0.99 ** (1 / (len(WOS) * len(SAMPLERS)))


@pytest.mark.parametrize("wo_name", list(WOS))
@pytest.mark.parametrize("name", list(SAMPLERS))
def test_chi2(name, wo_name):
    r = chi2_test(SAMPLERS[name], WOS[wo_name], n=100_000, seed=zlib.crc32(f"{name}/{wo_name}".encode()))
    assert r["stray"] == 0
    assert r["p_value"] > ALPHA, r


class _WrongPdf(PhongLobe):
    """Samples exponent s, claims the pdf of exponent 1.1 s."""

    def pdf(self, wo, wi):
        return PhongLobe(self.s * 1.1).pdf(wo, wi)


@pytest.mark.parametrize("bad", [_WrongPdf(20.0), MicrofacetH("ggx", 0.33, 0.3)])
def test_chi2_rejects_a_wrong_pdf(bad):
    if isinstance(bad, MicrofacetH):  # sample with α = 0.33, claim the pdf of α = 0.3
        good_pdf = MicrofacetH("ggx", 0.3, 0.3).pdf

        class _B(MicrofacetH):
            def pdf(self, wo, wi):
                return good_pdf(wo, wi)

        bad = _B("ggx", 0.33, 0.3)
    assert chi2_test(bad, WOS["57deg"], n=100_000)["p_value"] < 1e-6


def test_vndf_pdf_integrates_to_visible_fraction():
    """∫ pdf over all wi equals 1 minus the share of h with wo·h ≤ 0 (none for VNDF)."""
    s = GGXVisible(0.3, 0.3)
    wo = WOS["57deg"]
    n = 400
    mu = (np.arange(n) + 0.5) / n * 2 - 1
    ph = (np.arange(2 * n) + 0.5) / (2 * n) * 2 * math.pi
    M, P = np.meshgrid(mu, ph, indexing="ij")
    st = np.sqrt(1 - M**2)
    wi = np.stack([st * np.cos(P), st * np.sin(P), M], -1).reshape(-1, 3)
    upper = float((s.pdf(wo, wi) * (wi[:, 2] > 0)).sum() * (2 / n) * (math.pi / n))
    r = chi2_test(s, wo, n=200_000)
    assert upper == pytest.approx(r["observed_upper"] / 200_000, abs=5e-3)


@pytest.mark.parametrize(
    "name, params",
    [
        ("phong", {"kd": 0.2, "ks": 0.7, "shininess": 40.0}),
        ("blinn-phong", {"kd": 0.2, "ks": 0.7, "shininess": 100.0}),
        ("microfacet", {"alpha": 0.2, "fresnel": "none"}),
        ("microfacet", {"distribution": "beckmann", "alpha_x": 0.1, "alpha_y": 0.4}),
        ("ward", {"alpha_x": 0.1, "alpha_y": 0.3}),
        ("cook-torrance", {"m": 0.2}),
    ],
)
def test_mc_albedo_matches_quadrature(name, params):
    m = bk.model(name, **params)
    assert not isinstance(sampler_for(m), CosineHemisphere)
    mean, se = albedo_mc(m, 0.8, n=200_000, seed=3)
    q = albedo(m, 0.8)
    assert np.all(np.abs(mean - q) <= 5 * se + 1e-9), (mean, se, q)
