"""The analytic references against independent routes to the same numbers.

Each closed form is checked against adaptive quadrature of the MDR integrals
(paper Eqs. 2, 12, 13) evaluated from the profile's slope, or against another
closed form that must coincide with it.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from wearcheck import cases
from wearcheck.cases import reference as ref
from conftest import write_table_case

E = 2.0e11
R = 0.01


def indenter(**kw):
    base = dict(youngs_modulus=210e9, poisson_ratio=0.3)
    base.update(kw)
    return cases.from_dict({
        "indenter": base, "loading": {"control": "depth", "depth": 1e-6},
        "wear": {"k": 1e-4, "mu": 0.3, "hardness": 2e9}}).indenter


def test_hertz_pressure_integrates_to_force():
    h = ref.hertz(E, R, depth=1e-6)
    a = h["contact_radius"]
    F, _ = integrate.quad(lambda r: 2 * math.pi * r * ref.hertz_pressure(r, E, R, a), 0, a,
                          epsrel=1e-12)
    assert F == pytest.approx(h["force"], rel=1e-10)
    # force control inverts depth control
    back = ref.hertz(E, R, force=h["force"])
    assert back["depth"] == pytest.approx(1e-6, rel=1e-12)


def test_quadrature_transform_reproduces_known_pairs():
    # paraboloid r²/2R <-> x²/R; cone r tanθ <-> (π/2) x tanθ (docs/theory.md §2)
    par = indenter(profile="paraboloid", radius=R)
    cone = indenter(profile="cone", slope_angle=0.1)
    for x in (1e-5, 7e-5, 2e-4):
        assert ref.mdr_transform_quad(par, x) == pytest.approx(x**2 / R, rel=1e-10)
        assert ref.mdr_transform_quad(cone, x) == pytest.approx(math.pi / 2 * x * math.tan(0.1),
                                                                rel=1e-10)


@pytest.mark.parametrize("kw, closed", [
    (dict(profile="sphere", radius=R), lambda load: ref.sphere(E, R, **load)),
    (dict(profile="cone", slope_angle=0.02), lambda load: ref.cone(E, 0.02, **load)),
    (dict(profile="power_law", coefficient=3e3, exponent=3.0),
     lambda load: ref.power_law(E, 3e3, 3.0, **load)),
    (dict(profile="truncated_paraboloid", radius=R, flat_radius=5e-5),
     lambda load: ref.truncated_paraboloid(E, R, 5e-5, **load)),
])
@pytest.mark.parametrize("load", [dict(depth=1e-6), dict(force=20.0)])
def test_closed_forms_match_quadrature(kw, closed, load):
    ind = indenter(**kw)
    got = closed(load)

    # independent route: quadrature of g (Eq. 2) and of the force (Eq. 12)
    def g(x):
        return ref.mdr_transform_quad(ind, x)

    a = got["contact_radius"]
    assert g(a) == pytest.approx(got["depth"], rel=1e-8)
    kink = [kw["flat_radius"]] if "flat_radius" in kw else None  # g is not smooth at b
    F, _ = integrate.quad(lambda x: got["depth"] - g(x), 0, a, epsrel=1e-11, points=kink)
    # g ~ sqrt(x - b) just past the flat tip slows quad's convergence there
    assert 2 * E * F == pytest.approx(got["force"], rel=1e-5 if kink else 1e-8)
    if "depth" in load:
        assert got["depth"] == pytest.approx(load["depth"], rel=1e-12)
    else:
        assert got["force"] == pytest.approx(load["force"], rel=1e-10)


def test_power_law_two_is_hertz():
    got = ref.power_law(E, 1 / (2 * R), 2.0, depth=1e-6)
    h = ref.hertz(E, R, depth=1e-6)
    for k in h:
        assert got[k] == pytest.approx(h[k], rel=1e-12)


def test_sphere_tends_to_hertz_for_small_contact():
    # g = x atanh(x/R) = x²/R (1 + x²/3R² + ...): relative difference O((a/R)²)
    s, h = ref.sphere(E, R, depth=1e-8), ref.hertz(E, R, depth=1e-8)
    assert s["force"] == pytest.approx(h["force"], rel=1e-5)


def test_truncated_pressure_integrates_to_force_and_is_singular_at_b():
    b = 5e-5
    t = ref.truncated_paraboloid(E, R, b, depth=1e-6)
    a = t["contact_radius"]

    def p(r):
        return float(ref.truncated_paraboloid_pressure(np.array([r]), E, R, b, a)[0])

    inner, _ = integrate.quad(lambda r: 2 * math.pi * r * p(r), 0, b, epsrel=1e-9, limit=200)
    outer, _ = integrate.quad(lambda r: 2 * math.pi * r * p(r), b, a, epsrel=1e-9, limit=200)
    assert inner + outer == pytest.approx(t["force"], rel=1e-7)
    # logarithmic singularity: p(b ± ε) grows like -log ε
    eps = np.array([1e-3, 1e-5, 1e-7]) * b
    near = ref.truncated_paraboloid_pressure(b + eps, E, R, b, a)
    steps = np.diff(near) / np.diff(-np.log(eps))
    assert np.all(steps > 0)
    assert steps[1] == pytest.approx(steps[0], rel=0.05)
    assert np.isinf(ref.truncated_paraboloid_pressure(np.array([b]), E, R, b, a)[0])


def test_table_profile_matches_closed_form_paraboloid(tmp_path):
    r = np.linspace(0, 3e-4, 301)
    path = write_table_case(tmp_path, "\n".join(f"{float(x)!r},{float(x * x / (2 * R))!r}"
                                                 for x in r))
    case = cases.load(path)
    sc = ref.scales(case)
    h = ref.hertz(case.E_star, R, depth=1e-6)
    # PCHIP slope error O(h²) with h = 1 µm on a 100 µm contact
    assert sc["a0"] == pytest.approx(h["contact_radius"], rel=1e-4)
    assert sc["F0"] == pytest.approx(h["force"], rel=1e-4)


def test_scales_of_paper_case():
    case = cases.load(cases.shipped("hertz"))
    sc = ref.scales(case)
    assert sc["a0"] == pytest.approx(math.sqrt(0.01 * 1e-6), rel=1e-14)
    assert sc["p0"] == pytest.approx(2 * case.E_star * sc["a0"] / (math.pi * 0.01), rel=1e-13)
    assert sc["s_hat_per_m"] == pytest.approx(
        case.wear.k * case.wear.mu * case.E_star / (case.wear.hardness * sc["a0"]), rel=1e-14)


@pytest.mark.parametrize("n", [1.0, 2.0, 3.5])
def test_worn_sphere_asymptote_is_the_spherical_cap(n):
    # the cap of height h worn by dh/ds = K_n (F/(π b²))^n with b² = 2Rh - h²:
    # ∫_0^h (2Rη - η²)^n dη = K_n (F/π)^n s, solved here by quadrature and a
    # root (the reference uses the incomplete beta function); 1e-10: the
    # quadrature's tolerance
    from scipy import optimize
    Rb, F, K, H = 0.005, 2.0, 1e-15, 6e9
    Kn = K * H ** (1.0 - n)
    for s in (2.0, 2e3, 2e5):
        out = ref.worn_sphere_asymptote(Rb, F, s, K, exponent=n, hardness=H)
        rhs = Kn * (F / math.pi) ** n * s

        def lhs(h):
            return integrate.quad(lambda e: (2 * Rb * e - e * e) ** n, 0.0, h,
                                  epsabs=0, epsrel=1e-13)[0] - rhs
        h = optimize.brentq(lhs, 0.0, Rb, xtol=1e-30, rtol=1e-14)
        assert float(out["wear_center"]) == pytest.approx(h, rel=1e-10)
        assert float(out["scar_radius"]) == pytest.approx(math.sqrt(2 * Rb * h - h * h), rel=1e-10)
        if n == 1.0:
            # Archard: the cap's volume is K F s (round-off)
            assert float(out["wear_volume"]) == pytest.approx(K * F * s, rel=1e-12)
    # the paraboloid's law is the small-cap limit: larger by (b/R)²/12 in b for
    # n = 1 (series of the cap's volume), 5.3e-4 at b/R = 0.08
    if n == 1.0:
        for s in (2.0, 2e3):
            b = float(ref.worn_sphere_asymptote(Rb, F, s, K)["scar_radius"])
            bp = float(ref.worn_sphere_asymptote(Rb, F, s, K, profile="paraboloid")["scar_radius"])
            assert bp / b - 1 == pytest.approx((b / Rb) ** 2 / 12, rel=0.1)
    # past the hemisphere there is no cap
    assert math.isnan(float(ref.worn_sphere_asymptote(Rb, F, 1e40, K, exponent=n,
                                                      hardness=H)["scar_radius"]))
