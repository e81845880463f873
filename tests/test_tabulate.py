"""``bk.tabulate(..., format="rgl")``: models written as RGL ``.bsdf`` files, read back by
Mitsuba 3's ``measured`` plugin (the independent reader) and by brdfkit's.

For each model, one file at the default resolution (64 x 64 samples, 32 elevations, 10 azimuths
per quarter turn for anisotropic models, 64 x 64 NDF), written once per module:

* Mitsuba (``scalar_rgb``, float32) and brdfkit read the same file alike: on 2000 random pairs
  ``|mitsuba − brdfkit| <= 1e-4 |brdfkit| + 1e-6 max|brdfkit|`` (the floor: Mitsuba's float32
  interpolation of values ~1e-6 of the peak; measured: largest difference 0.5-5e-6 of the peak,
  largest relative difference on values above 1e-3 of the peak 2e-5 to 1.1e-4);
* both agree with the source model: the tabulation error, the relative RMS of
  ``f_r cos θi cos θo`` on pairs uniform over the hemispheres (20000 pairs for brdfkit's reader,
  the 2000 pairs for Mitsuba's), is at most 2 % (printed; run with ``-s`` to see the figures).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import brdfkit as bk
from brdfkit.measured import rgl_writer
from brdfkit.measured.rgl import _Params, _Warp, load_rgl
from brdfkit.measured.tabulation import tabulation_error
from brdfkit.models.base import BRDF
from _mitsuba_helpers import mitsuba_f_r
from _numeric_helpers import hemisphere_pairs

RTOL, FLOOR = 1e-4, 1e-6
MAX_ERROR = 0.02

#: isotropic cases first (Mitsuba 3.9 reads an uninitialised m_reduction for isotropic files, see
#: brdfkit.measured.rgl; after a reduction-4 file it mirrors them)
CASES = {
    "ggx": ("microfacet", dict(alpha=0.2)),
    "beckmann": ("microfacet", dict(distribution="beckmann", alpha=0.2)),
    "measured": ("merl/gold-metallic-paint", {}),
    "ggx-anisotropic": ("microfacet", dict(alpha_x=0.1, alpha_y=0.3)),
    "beckmann-anisotropic": ("microfacet", dict(distribution="beckmann", alpha_x=0.3, alpha_y=0.15)),
    "ward": ("ward", dict(kd=0.3, ks=0.15, alpha_x=0.15, alpha_y=0.3)),
    "lafortune": ("lafortune", dict(kd=0.2, ks_1=0.5, n_1=20.0)),
}


def weighted_rms(model_f, file_f, wi, wo) -> float:
    w = (wi[:, 2] * wo[:, 2])[:, None]
    return float(np.sqrt(np.sum(((file_f - model_f) * w) ** 2) / np.sum((model_f * w) ** 2)))


@pytest.fixture(scope="module")
def written(mi, tmp_path_factory):
    """name -> (source model, TabulateResult, wi, wo, Mitsuba's f_r, brdfkit's f_r), every file
    written at the default resolution, Mitsuba evaluated in the order of CASES."""
    d = tmp_path_factory.mktemp("tabulate")
    out = {}
    for i, (case, (name, params)) in enumerate(CASES.items()):
        model = bk.model(name, **params)
        res = bk.tabulate(model, d / f"{case}.bsdf", "rgl")
        wi, wo = hemisphere_pairs(2000, 300 + i)
        theirs = mitsuba_f_r(mi, {"type": "measured", "filename": res.path}, wi, wo)
        out[case] = (model, res, wi, wo, theirs, load_rgl(res.path).eval(wi, wo))
    return out


@pytest.mark.parametrize("case", list(CASES))
def test_mitsuba_reads_the_file_as_brdfkit_does(written, case):
    _, res, wi, wo, theirs, ours = written[case]
    assert ours.shape == (2000, 3) and (ours > 0).any()
    np.testing.assert_allclose(theirs, ours, rtol=RTOL, atol=FLOOR * np.abs(ours).max())


@pytest.mark.parametrize("case", list(CASES))
def test_tabulation_error_at_the_default_resolution(written, case):
    model, res, wi, wo, theirs, ours = written[case]
    mitsuba_error = weighted_rms(model.eval(wi, wo), theirs, wi, wo)
    sh = res.shape
    print(f"\n{case}: {res.bytes / 1e6:.2f} MB, {sh['n_phi']} x {sh['n_theta']} x {sh['resolution']}^2 "
          f"(reduction {sh['reduction']}); tabulation error (relative RMS of f cos cos) brdfkit "
          f"{100 * res.error:.2f} % on {res.error_pairs} pairs, Mitsuba {100 * mitsuba_error:.2f} % on 2000")
    assert res.error <= MAX_ERROR
    assert mitsuba_error <= MAX_ERROR
    assert sh["resolution"] == 64 and sh["n_theta"] == 32 and sh["ndf"][1] == 64
    assert sh["isotropic"] == ("anisotropic" not in case and case not in ("ward", "lafortune"))
    if not sh["isotropic"]:
        assert sh["reduction"] == 4 and sh["n_phi"] == 11  # mirror-symmetric models: one quarter, 10 steps


def test_default_sizes(written):
    """~2.6 MB per isotropic file, ~29 MB per anisotropic one (float32 vndf + luminance + 3 rgb)."""
    iso, aniso = written["ggx"][1], written["ward"][1]
    assert iso.bytes == pytest.approx(4 * 32 * 64 * 64 * 5, rel=0.01)
    assert aniso.bytes == pytest.approx(4 * 11 * 32 * 64 * 64 * 5, rel=0.01)


def test_samples_are_the_model_exactly(written):
    """At the pairs the samples stand for (the VNDF warp of each grid point of a measured incident
    direction), the file returns the model itself: the Jacobian D(m) / (4 σ(v)) is undone exactly."""
    model, res, *_ = written["ggx"]
    from brdfkit.measured.tensor_file import read_tensor_file

    fields = read_tensor_file(res.path)
    theta = float(fields["theta_i"][7])
    v = rgl_writer.direction(theta, 0.0)
    grid = np.stack(np.meshgrid(np.linspace(0, 1, 64), np.linspace(0, 1, 64)), axis=-1).reshape(-1, 2)
    u_m = rgl_writer.warp_sample(np.asarray(fields["vndf"][0, 7], np.float64), grid)
    m = rgl_writer.direction(rgl_writer.u2theta(u_m[:, 0]), rgl_writer.u2phi(u_m[:, 1]))
    l = 2 * (m @ v)[:, None] * m - v
    keep = l[:, 2] > 0.05
    l = l[keep] / np.linalg.norm(l[keep], axis=1, keepdims=True)
    vv = np.broadcast_to(v, l.shape)
    want = model.eval(l, vv)
    got = load_rgl(res.path).eval(l, vv)
    assert keep.sum() > 1000
    np.testing.assert_allclose(got, want, rtol=2e-5, atol=1e-6 * want.max())


# ----------------------------------------------------------------- the warp
def test_forward_warp_is_the_readers_inverse():
    rng = np.random.default_rng(4)
    data = rng.uniform(0.0, 2.0, (9, 13))
    data[:, 0] = 0.0  # a zero column, as the VNDF's at u_x = 0
    s = rng.uniform(0, 1, (500, 2))
    u = rgl_writer.warp_sample(data, s)
    warp = _Warp(data[None])
    prm = _Params(np.zeros(1), np.zeros(1), np.zeros(len(s)), np.zeros(len(s)))
    np.testing.assert_allclose(warp.invert(u, prm), s, atol=1e-9)
    assert (u >= 0).all() and (u <= 1).all()


@settings(max_examples=60, deadline=None)
@given(st.integers(2, 7), st.integers(2, 7), st.integers(0, 2**31 - 1), st.booleans())
def test_forward_warp_inverts_on_any_density(h, w, seed, zero_column):
    """Any positive bilinear density (optionally zero along u_x = 0, as a VNDF is): the reader's
    inverse of the writer's warp is the identity."""
    rng = np.random.default_rng(seed)
    data = rng.uniform(0.01, 5.0, (h, w)) ** 2
    if zero_column:
        data[:, 0] = 0.0
    s = rng.uniform(0, 1, (64, 2))
    u = rgl_writer.warp_sample(data, s)
    prm = _Params(np.zeros(1), np.zeros(1), np.zeros(len(s)), np.zeros(len(s)))
    np.testing.assert_allclose(_Warp(data[None]).invert(u, prm), s, atol=1e-9)


def test_forward_warp_follows_the_density():
    """Uniform points warped by a density land with that density: a step density 1 | 3 along x
    puts 3/4 of them in the right half (bilinear: the ramp between the nodes is accounted for)."""
    data = np.ones((3, 3))
    data[:, 2] = 3.0
    s = np.stack(np.meshgrid((np.arange(400) + 0.5) / 400, [0.5]), axis=-1).reshape(-1, 2)
    u = rgl_writer.warp_sample(data, s)
    # mass of the interpolant left of x = 1/2: 1/2; right: (1 + 3)/2 * 1/2 = 1; total 1.5
    assert np.mean(u[:, 0] > 0.5) == pytest.approx(1.0 / 1.5, abs=0.003)


# ----------------------------------------------------------------- the NDF (Dupuy et al. 2015)
class _RetroGGX(BRDF):
    """A BRDF whose backscattering is exactly a microfacet surface's: ``D(ω) / (4 cos θ σ(ω))``
    (F = 1, G1 = cos θ / σ) for the anisotropic GGX D, with Smith's σ = cos θ (1 + Λ(ω))."""

    name = "retro-ggx-test"
    isotropic = False

    def __init__(self, ax=0.2, ay=0.4):
        self.ax, self.ay = ax, ay
        super().__init__()

    def D(self, m):
        x, y, z = m[..., 0], m[..., 1], m[..., 2]
        return 1.0 / (np.pi * self.ax * self.ay * (x * x / self.ax ** 2 + y * y / self.ay ** 2 + z * z) ** 2)

    def sigma(self, w):
        x, y, z = w[..., 0], w[..., 1], w[..., 2]
        lam = 0.5 * (-1.0 + np.sqrt(1.0 + ((self.ax * x) ** 2 + (self.ay * y) ** 2) / (z * z)))
        return z * (1.0 + lam)

    def _eval(self, wi, wo, p):
        h = wi + wo
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        f = self.D(h) / (4.0 * h[..., 2] * self.sigma(h))
        return np.repeat(f[..., None], 3, axis=-1)


@pytest.mark.parametrize("isotropic", [True, False])
def test_power_iteration_recovers_the_ndf_and_sigma(isotropic):
    """The NDF's nodes are GGX's D, and σ at them Smith's cos θ (1 + Λ): the power iteration's
    fixed point and the σ quadrature, checked against closed forms."""
    model = _RetroGGX(0.3, 0.3) if isotropic else _RetroGGX(0.2, 0.4)
    ndf = rgl_writer.power_iteration_ndf(model, 48, isotropic)
    h, w = ndf.ndf.shape
    nodes = rgl_writer.backscatter_nodes(h, w, isotropic)
    want_d, want_s = model.D(nodes), model.sigma(np.where(nodes[..., 2:] > 1e-3, nodes, [0, 0, 1e-3]))
    big = want_d > 1e-2 * want_d.max()
    np.testing.assert_allclose(ndf.ndf[big], want_d[big], rtol=0.02)
    ok = nodes[..., 2] > 0.05
    np.testing.assert_allclose(ndf.sigma[ok], want_s[ok], rtol=0.02)
    assert ndf.sigma[:, 0] == pytest.approx(1.0, abs=1e-12)  # normalised: ∫ D cos θm dm = 1
    assert ndf.change < 1e-6


# ----------------------------------------------------------------- symmetries
class _Skewed(BRDF):
    """Smooth test BRDFs with less symmetry: ``kind`` 2 is symmetric under a rotation by π only,
    ``kind`` 1 under nothing."""

    name = "skewed-test"
    isotropic = False

    def __init__(self, kind):
        self.kind = kind
        super().__init__()

    def _eval(self, wi, wo, p):
        a = 0.3 + 0.2 * wi[..., 0] * wo[..., 1] + 0.1 * (wi[..., 2] + wo[..., 2])
        if self.kind == 1:
            a = a + 0.1 * wi[..., 0] + 0.05 * wo[..., 1]
        return np.stack([a, 0.8 * a, 0.6 * a], axis=-1)


@pytest.mark.parametrize("kind", [1, 2])
def test_less_symmetric_models_use_the_wider_wedge(mi, tmp_path, kind):
    model = _Skewed(kind)
    assert rgl_writer.symmetry_reduction(model) == kind
    res = bk.tabulate(model, tmp_path / "skewed.bsdf", resolution=16, n_theta=8, n_phi=16 // kind + 1,
                      ndf_resolution=16)
    assert res.shape["reduction"] == kind
    phi = load_rgl(res.path)
    assert phi.reduction == kind
    wi, wo = hemisphere_pairs(500, 9)
    ours = phi.eval(wi, wo)
    theirs = mitsuba_f_r(mi, {"type": "measured", "filename": res.path}, wi, wo)
    np.testing.assert_allclose(theirs, ours, rtol=RTOL, atol=FLOOR * ours.max())
    print(f"\nskewed model, reduction {kind}: tabulation error {100 * res.error:.2f} % at 16^2 x 8 x {16 // kind + 1}")
    assert res.error < 0.05  # coarse on purpose (fast); at the defaults ~0.6 %


def test_error_measure_sees_a_wrong_file(written):
    """The tabulation error is not blind: the GGX file compared with the Beckmann model is far off."""
    ggx_file = load_rgl(written["ggx"][1].path)
    assert tabulation_error(written["beckmann"][0], ggx_file, 5000) > 0.1
    assert tabulation_error(written["ggx"][0], ggx_file, 5000) < MAX_ERROR
