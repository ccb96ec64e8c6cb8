"""User kernels at their edges: a CDF that is not vectorized or whose derivative is not
finite is refused naming the argument; kernels stay immutable; a kernel whose parameters
do not hash (a callable dataclass) still gives the gauge the hashable equivalent gives
(its overshoot profile is memoized by its values instead).
"""
import math
from dataclasses import dataclass

import numpy as np
import pytest

from gerbs_core.errors import InvalidParameterError
from gerbs_core.gauge.blend import overshoot_profile
from gerbs_core.gauge.envelope import RadialEnvelope
from gerbs_core.kernels import ERBS, CustomCDF


def _smoothstep(x):
    return x * x * (3.0 - 2.0 * x)


@dataclass
class Smoothstep:
    """A callable with value semantics (eq=True, so __hash__ is None: unhashable)."""
    order: int = 3

    def __call__(self, x):
        return _smoothstep(x)


def test_a_cdf_that_is_not_vectorized_is_refused():
    with pytest.raises(InvalidParameterError, match="calling it on an array failed") as exc:
        CustomCDF(lambda x: math.sin(0.5 * math.pi * x) ** 2)
    assert exc.value.name == "f"


def test_a_derivative_with_non_finite_values_is_refused():
    with pytest.raises(InvalidParameterError, match="entry 1 .order 2. has non-finite") as exc:
        CustomCDF(_smoothstep, derivatives=[lambda x: 6 * x * (1 - x),
                                            lambda x: np.where(x < 0.5, 6 - 12 * x, np.nan)])
    assert exc.value.name == "derivatives"


def test_kernels_are_immutable():
    k = ERBS()
    with pytest.raises(AttributeError, match="immutable"):
        del k.max_order
    with pytest.raises(AttributeError, match="immutable"):
        k.max_order = 3
    assert k.max_order == ERBS().max_order


def test_an_unhashable_kernel_gives_the_gauge_of_its_hashable_equivalent():
    deriv = [lambda x: 6 * x * (1 - x), lambda x: 6 - 12 * x]
    plain = CustomCDF(_smoothstep, derivatives=deriv, smoothness=1)
    odd = CustomCDF(Smoothstep(), derivatives=deriv, smoothness=1)
    with pytest.raises(TypeError):
        hash(odd)
    G = overshoot_profile(odd, n=129)
    np.testing.assert_array_equal(G, overshoot_profile(plain, n=129))
    assert overshoot_profile(odd, n=129) is G          # memoized by its values
    np.testing.assert_array_equal(overshoot_profile(odd, n=129, mirrored=True),
                                  overshoot_profile(plain, n=129, mirrored=True))
    th = np.linspace(0.0, 2 * np.pi, 6) + 0.2
    r = [1.0, 1.4, 0.8, 1.1, 0.9, 1.0]
    a = RadialEnvelope(th, r, kernel=odd)
    b = RadialEnvelope(th, r, kernel=plain)
    assert a.method == b.method
    t = np.linspace(0.0, 7.0, 101)
    np.testing.assert_array_equal(a.u_derivs(t), b.u_derivs(t))


def test_the_profile_memo_keeps_its_newest_entries(monkeypatch):
    # a full memo drops its oldest entry, not every entry: a profile just made is still
    # memoized after the next one (a full clear made the memo test above depend on which
    # tests ran before it in the same process)
    from gerbs_core.gauge import blend
    monkeypatch.setattr(blend, "_G_CACHE", {})
    for i in range(32):
        overshoot_profile(ERBS(lam=0.01 * (i + 1)), n=17)
    G = overshoot_profile(ERBS(lam=0.5), n=17)
    overshoot_profile(ERBS(lam=0.6), n=17)
    assert overshoot_profile(ERBS(lam=0.5), n=17) is G
    assert len(blend._G_CACHE) == 32
