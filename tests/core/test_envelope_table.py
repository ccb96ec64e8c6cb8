"""Tests of the vectorized star envelopes (gerbs_core.gauge.envelope_table).

The table must build, for every star, the envelope :class:`RadialEnvelope` builds: the
certified blend where it exists and otherwise the per-star fallbacks (fillet or constant
lines). With kappa close to 1 the blend of stars with very unequal edges cannot be
certified, so the fallback branch runs; the envelopes it gives must keep the guarantees of
the main path: kappa * shrink * rho <= rho~ <= shrink * rho, a C^2 (smooth) u~ = 1/rho~,
periodicity for closed stars.
"""
import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError, InvalidPointSetError
from gerbs_core.gauge.envelope import RadialEnvelope
from gerbs_core.gauge.envelope_table import envelope_table

KAPPA, SHRINK = 0.98, 0.95

# stars (theta incl. the repeated end for closed ones, radius, closed): at kappa = 0.98 the
# first takes the certified blend, the others not (found by a random search over star
# polygons with log-normal radii)
STARS = [
    ([0.6533018043817873, 2.029761216768713, 2.1588612831967158, 3.437182227344358,
      4.046064969131297, 4.049383628007188, 6.936487111561373],
     [1.6691027390420696, 0.8095576260587363, 4.363824788547062, 0.5945970689097553,
      7.7791748955983975, 0.48276947555239424, 1.6691027390420696], True),
    ([0.3367319131558175, 0.9362064603490937, 2.013699150911598, 3.496181180615698,
      3.910414673953902, 4.568467514245981, 5.934185877909283, 6.143133350644327,
      6.619917220335404],
     [0.6099214024149794, 0.7716074397604122, 1.6113047090418622, 0.634428466195168,
      1.0072908250260297, 1.0906290452867125, 0.3010259567880622, 0.7605013613961608,
      0.6099214024149794], True),
    ([2.901654664826587, 3.695871145192755, 4.447344830117692, 5.911700797129195,
      6.1150784362812365, 6.1395716519126475, 9.184839972006174],
     [0.7342258129175072, 1.3748551758131455, 0.10562346447877752, 0.46320305789314137,
      3.115391755628635, 0.5113505666121335, 0.7342258129175072], True),
    ([0.0, 0.13112702645341956, 2.3298255514665365],
     [0.10538434602682643, 1.4716284806181057, 0.5589804182473841], False),
    ([0.0, 2.4701933279528205, 3.0155907638259705, 5.262781346318892, 5.531958502431375],
     [2.2141997864182557, 0.6185075133556451, 0.8128035817632817, 0.5593205292834084,
      1.7010593697164735], False),
]
FALLBACK = range(1, len(STARS))


def _hexagon():
    th = np.linspace(0.0, 2 * np.pi, 7) + 0.1
    return th.tolist(), [1.0] * 7, True


def _table(stars, **kw):
    theta = np.concatenate([s[0] for s in stars])
    radius = np.concatenate([s[1] for s in stars])
    ptr = np.concatenate([[0], np.cumsum([len(s[0]) for s in stars])])
    closed = np.array([s[2] for s in stars])
    return envelope_table(theta, radius, ptr, closed, kappa=KAPPA, shrink=SHRINK, **kw)


def _samples(th, closed, n=2000):
    t = np.linspace(th[0], th[-1], n)
    return t if closed else t[1:-1]


@pytest.fixture(scope="module")
def table():
    return _table(STARS)


@pytest.fixture(scope="module")
def refs():
    return [RadialEnvelope(th, r, closed=c, kappa=KAPPA, shrink=SHRINK) for th, r, c in STARS]


def test_fallback_stars_get_the_envelope_radial_envelope_builds(table, refs):
    assert str(table.method[0]) == refs[0].method == "blend"
    assert all(refs[i].method in ("fillet", "constant") for i in FALLBACK)   # fallbacks ran
    for i, (th, _, closed) in enumerate(STARS):
        assert table.min_ratio[i] == pytest.approx(refs[i].min_ratio, rel=1e-12)
        t = _samples(np.asarray(th), closed)
        np.testing.assert_allclose(table.u_derivs(i, t, 2), refs[i].u_derivs(t, 2),
                                   rtol=1e-11, atol=1e-11)
        np.testing.assert_allclose(table.envelope(i).u_derivs(t, 2), refs[i].u_derivs(t, 2),
                                   rtol=1e-11, atol=1e-11)


def test_fallback_stars_report_their_method(table, refs):
    assert [str(m) for m in table.method] == [e.method for e in refs]


@pytest.mark.parametrize("i", FALLBACK)
def test_fallback_envelope_keeps_the_certified_bounds(i, table, refs):
    th, _, closed = STARS[i]
    t = _samples(np.asarray(th), closed, 5000)
    rho_t = 1.0 / table.u_derivs(i, t, 0)[0]
    ratio = rho_t / refs[i].exact_radius(t)
    assert ratio.max() <= SHRINK * (1 + 1e-9)            # below the star's radius
    assert ratio.min() >= KAPPA * SHRINK * (1 - 1e-9)    # and not far below it
    assert ratio.min() >= table.min_ratio[i] * (1 - 1e-9)  # the certified min holds


@pytest.mark.parametrize("i", FALLBACK)
def test_fallback_envelope_is_smooth_across_its_knots(i, table):
    """u~, u~' and u~'' are continuous at every interior knot (their jumps over a step
    small against the knot spacing are small against the function's range), and the
    derivatives are those of the values (central differences)."""
    a, b = table.knot_ptr[i], table.knot_ptr[i + 1]
    th, _, closed = STARS[i]
    kn = table.knots[a:b]
    h = 1e-4 * np.diff(kn).min()
    kn = kn[(kn > th[0] + h) & (kn < th[-1] - h)]
    assert len(kn)
    lo, hi = table.u_derivs(i, kn - h, 2), table.u_derivs(i, kn + h, 2)
    scale = np.abs(table.u_derivs(i, _samples(th, True, 3000), 2)).max(axis=1)
    for k in range(3):
        assert np.all(np.abs(hi[k] - lo[k]) <= 1e-2 * scale[k]), k
    t = _samples(th, closed, 200)[1:-1]
    u = table.u_derivs(i, t, 2)
    np.testing.assert_allclose((table.u_derivs(i, t + h, 0)[0] - table.u_derivs(i, t - h, 0)[0])
                               / (2 * h), u[1], atol=1e-5 * scale[1])
    np.testing.assert_allclose((table.u_derivs(i, t + h, 1)[1] - table.u_derivs(i, t - h, 1)[1])
                               / (2 * h), u[2], atol=1e-5 * scale[2])


def test_closed_fallback_envelope_is_periodic(table):
    th = np.asarray(STARS[1][0])
    t = np.linspace(th[0], th[-1], 50)
    np.testing.assert_allclose(table.u_derivs(1, t + (th[-1] - th[0]), 2),
                               table.u_derivs(1, t, 2), rtol=1e-12, atol=1e-12)


def test_table_without_a_kernel_uses_erbs():
    from gerbs_core.kernels import ERBS
    th, r, closed = _hexagon()
    table = envelope_table(th, r, [0, 7], [closed])
    assert isinstance(table.kernel, ERBS)
    ref = RadialEnvelope(th, r, closed=True)
    t = np.linspace(0.0, 6.0, 50)
    np.testing.assert_allclose(table.u_derivs(0, t), ref.u_derivs(t), rtol=1e-12)


# ------------------------------------------------------------------ input checks
# (RadialEnvelope and envelope_table share validate_stars)

def _raises(cls, match, theta, radius, closed):
    with pytest.raises(cls, match=match) as exc:
        RadialEnvelope(theta, radius, closed=closed)
    return exc.value


def test_too_few_vertices_are_refused():
    _raises(InvalidParameterError, "theta: need at least 2 boundary vertices", [0.0], [1.0],
            False)
    _raises(InvalidPointSetError, "closed star needs at least 2 edges", [0.0, 2 * np.pi],
            [1.0, 1.0], True)


def test_non_finite_and_non_positive_radii_name_the_vertex():
    th = [0.0, 1.0, 2.0, 3.0]
    e = _raises(InvalidPointSetError, "non-finite boundary vertex", th,
                [1.0, np.nan, 1.0, 1.0], False)
    assert e.indices == (1,)
    e = _raises(InvalidPointSetError, "radius must be > 0", th, [1.0, 1.0, 0.0, 1.0], False)
    assert e.indices == (2,)


def test_closed_star_must_repeat_its_first_radius():
    th = np.linspace(0.0, 2 * np.pi, 5)
    e = _raises(InvalidPointSetError, "last vertex must repeat the first",
                th, [1.0, 1.0, 1.0, 1.0, 1.5], True)
    assert e.indices == (0, 4)


def test_centre_on_the_line_of_an_edge_is_refused():
    # vertices at (1, 0) and (-1, 0) seen from the origin: the edge between them (angle
    # step pi - 1e-14 < pi) passes through the centre
    e = _raises(InvalidPointSetError, "centre lies on .the line of. a boundary edge",
                [0.0, np.pi - 1e-14, 4.0], [1.0, 1.0, 1.0], False)
    assert e.indices == (0, 1)


def test_table_errors_name_the_bad_star():
    hexa = _hexagon()
    bad = (hexa[0], hexa[1][:-1] + [2.0], True)
    with pytest.raises(InvalidPointSetError, match="star 1: closed star"):
        _table([hexa, bad])
