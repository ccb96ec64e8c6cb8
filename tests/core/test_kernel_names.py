"""Kernels by name (gerbs_core.kernels.as_kernel): every ``kernel=`` argument takes the
names the add-on and the CLI use, as the kernel with its default parameters, and refuses
anything else with an InvalidParameterError naming ``kernel`` and listing the names
(GERBSInterpolator used to fail with an AttributeError deep in gauge/blend.py, and
BlendingSurface refused the names)."""
import numpy as np
import pytest

from gerbs_core import (BFBS, ERBS, Affine, BlendingSurface, GERBSBasis, GERBSInterpolator,
                        LogisticStep, RadialEnvelope, StarGauge)
from gerbs_core.datasets import primitives as P
from gerbs_core.errors import InvalidParameterError
from gerbs_core.kernels import KERNEL_NAMES, as_kernel

OBJECTS = {"erbs": ERBS(), "bfbs": BFBS(), "logistic": LogisticStep(), "affine": Affine()}
ACCEPTED = "one of 'erbs', 'bfbs', 'logistic', 'affine'"
PTS = np.random.default_rng(3).random((40, 2))
CLOSED = np.linspace(0.0, 2 * np.pi, 7)       # a closed star: the last ray repeats the first
THETA = CLOSED[:-1]


def _builders():
    V, F = P.icosphere(1)
    return {
        "BlendingSurface": lambda k: BlendingSurface(V, F, kernel=k).tessellate(2)[0],
        "GERBSInterpolator": lambda k: GERBSInterpolator(PTS, np.sin(3 * PTS).sum(1),
                                                         kernel=k)(PTS[:7] * 0.9 + 0.05),
        "GERBSBasis": lambda k: GERBSBasis([0.0, 1.0, 2.5, 3.0], k)(np.linspace(0, 3, 11)),
        "RadialEnvelope": lambda k: RadialEnvelope(CLOSED, 1 + 0.1 * np.cos(CLOSED),
                                                   kernel=k).kernel,
        "StarGauge": lambda k: StarGauge.from_polygon(
            [0.0, 0.0], np.c_[np.cos(THETA), np.sin(THETA)], kernel=k).kernel,
    }


def test_the_names_are_the_add_on_and_cli_names_with_default_parameters():
    assert list(KERNEL_NAMES) == ["erbs", "bfbs", "logistic", "affine"]
    for name, obj in OBJECTS.items():
        assert as_kernel(name) == obj
    assert as_kernel(None) == ERBS()
    k = BFBS(3, 2)
    assert as_kernel(k) is k


@pytest.mark.parametrize("where", sorted(_builders()))
@pytest.mark.parametrize("name", sorted(OBJECTS))
def test_every_kernel_argument_takes_a_name_as_its_kernel(where, name):
    build = _builders()[where]
    by_name, by_object = build(name), build(OBJECTS[name])
    if isinstance(by_object, np.ndarray):
        assert np.array_equal(by_name, by_object, equal_nan=True)   # bit for bit
    else:
        assert by_name == by_object


@pytest.mark.parametrize("where", sorted(_builders()))
@pytest.mark.parametrize("bad", ["bogus", "ERBS", 3, 2.5, object(), b"erbs"])
def test_anything_else_is_refused_naming_kernel_and_the_accepted_names(where, bad):
    with pytest.raises(InvalidParameterError) as info:
        _builders()[where](bad)
    err = info.value
    assert err.name == "kernel"
    assert str(err).startswith("kernel: must be a gerbs_core.kernels.Kernel or " + ACCEPTED)
    got = repr(bad) if isinstance(bad, (str, int, float)) else type(bad).__name__
    assert str(err).endswith(f"got {got}")


def test_a_kernel_list_takes_names_and_names_a_bad_entry():
    ks = GERBSBasis([0.0, 1.0, 2.5, 3.0], ["erbs", BFBS(), "affine"])
    ref = GERBSBasis([0.0, 1.0, 2.5, 3.0], [ERBS(), BFBS(), Affine()])
    t = np.linspace(0, 3, 13)
    assert np.array_equal(ks(t), ref(t))
    with pytest.raises(InvalidParameterError, match=f"kernel: entry 1 must be .*{ACCEPTED}, "
                       "got 'bogus'"):
        GERBSBasis([0.0, 1.0, 2.5, 3.0], ["erbs", "bogus", "affine"])


def test_one_table_names_labels_and_parameters_of_every_kernel():
    """KERNELS is the one table: KERNEL_NAMES is its view, each entry's parameters are
    keywords of its constructor, and make_kernel builds the kernel from them."""
    from gerbs_core.kernels import KERNELS, make_kernel

    assert list(KERNELS) == list(KERNEL_NAMES) == ["erbs", "bfbs", "logistic", "affine"]
    assert [e.label for e in KERNELS.values()] == ["ERBS", "BFBS", "Logistic", "Affine"]
    assert all(KERNEL_NAMES[n] is e.kernel for n, e in KERNELS.items())
    assert make_kernel("erbs", alpha=2.0, beta=0.5, gamma=3.0, lam=0.25, sigma=2.0) == \
        ERBS(alpha=2.0, beta=0.5, gamma=3.0, lam=0.25, sigma=2.0)
    assert make_kernel("bfbs", i_left=3, i_right=1) == BFBS(3, 1)
    assert make_kernel("bfbs", i_right=4) == BFBS(2, 4)
    for name, obj in OBJECTS.items():
        assert make_kernel(name) == obj


@pytest.mark.parametrize("name,params,bad", [
    ("gauss", {}, "kernel"), (None, {}, "kernel"), ("ERBS", {}, "kernel"),
    ("logistic", {"alpha": 1.0}, "alpha"), ("erbs", {"i_left": 2}, "i_left"),
    ("erbs", {"alpha": -1.0}, "alpha"), ("bfbs", {"i_left": -1}, "i_left"),
])
def test_make_kernel_refuses_a_bad_name_or_parameter_naming_it(name, params, bad):
    from gerbs_core.kernels import make_kernel

    with pytest.raises(InvalidParameterError) as info:
        make_kernel(name, **params)
    assert info.value.name == bad
    if bad == "kernel":
        assert ACCEPTED in str(info.value)
