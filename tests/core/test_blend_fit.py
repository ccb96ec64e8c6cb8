"""closed_form_fit's shrink loop against its plain statement (issue 15: the loop may be
written faster, never with other widths: the certificates and the mesh stencils depend on
them bit for bit)."""
import numpy as np
import pytest

from gerbs_core.gauge.blend import (_allowances, _grid_index, closed_form_fit,
                                    overshoot_profile)
from gerbs_core.kernels import ERBS

KAPPA = 0.8


def _plain_fit(nA, pA, cA, nB, pB, cB, roomA, roomB, kappa, kernel, factor, iters=200):
    """The loop as first written: all corners tested every pass until both sides pass,
    a failing side times ``factor`` (np.where), ok recorded per pass."""
    tau = np.abs(nB - nA)
    allowA, allowB = _allowances(nA, cA, nB, cB, kappa)
    G, GB = overshoot_profile(kernel), overshoot_profile(kernel, mirrored=True)
    n = len(G) - 1
    a, b = roomA.astype(float).copy(), roomB.astype(float).copy()
    ok = (tau <= 1e-15) & (np.abs(pA - pB) <= 1e-15 * pA)
    for _ in range(iters):
        t = np.flatnonzero(~ok)
        at, bt = a[t], b[t]
        W = at + bt
        al = at / W
        eA = np.minimum(np.cos(-at - nA[t]) ** 2, np.cos(nA[t]) ** 2)
        eB = np.minimum(np.cos(bt - nB[t]) ** 2, np.cos(nB[t]) ** 2)
        okA = (W * (pA[t] / pB[t]) * np.sin(tau[t]) * G[_grid_index(al, n)]
               <= allowA[t] * eA * (1 - 1e-9))
        okB = (W * (pB[t] / pA[t]) * np.sin(tau[t]) * GB[_grid_index(1.0 - al, n)]
               <= allowB[t] * eB * (1 - 1e-9))
        ok[t[okA & okB]] = True
        a[t] = np.where(okA, at, at * factor)
        b[t] = np.where(okB, bt, bt * factor)
    return a, b, ok


def _corners(n, seed):
    rng = np.random.default_rng(seed)
    nA = rng.uniform(-1.55, 1.2, n)
    nB = np.clip(nA + rng.choice([-1, 1], n) * rng.uniform(0.01, 2.0, n), -1.55, 1.55)
    nB[:5] = nA[:5]                                  # straight corners: nothing to fit
    pA = rng.uniform(0.2, 1.0, n)
    pB = pA * np.cos(nB) / np.cos(nA)
    # c as the scale rule picks it (below 1 beside a convex corner), and a few with c = 1
    # there (no allowance: never certified)
    convex = nB > nA
    cA = np.where(convex, rng.choice([0.8, 0.9, 0.95], n), rng.choice([0.9, 0.95, 1.0], n))
    cB = np.where(convex, rng.choice([0.8, 0.9, 0.95], n), rng.choice([0.9, 0.95, 1.0], n))
    cA[5:15] = cB[5:15] = 1.0
    # rooms from tiny to wide (up to ~70 shrinks), one side often much wider
    roomA = np.minimum(10.0 ** rng.uniform(-3, 0, n), 0.99 * (np.pi / 2 - nA))
    roomB = np.minimum(10.0 ** rng.uniform(-3, 0, n), 0.99 * (np.pi / 2 + nB))
    return nA, pA, cA, nB, pB, cB, roomA, roomB


@pytest.mark.parametrize("kern", [ERBS(), ERBS(lam=0.1)], ids=repr)
@pytest.mark.parametrize("iters", [200, 3])
def test_closed_form_fit_is_the_plain_loop_bit_for_bit(kern, iters):
    """Same widths and ok flags to the bit, also when the passes run out (iters=3: some
    corners are left uncertified, with the widths they had then)."""
    args = _corners(3000, 7)
    got = closed_form_fit(*args, KAPPA, kern, 0.85, iters=iters)
    ref = _plain_fit(*args, KAPPA, kern, 0.85, iters=iters)
    for g, r in zip(got, ref):
        assert g.dtype == r.dtype and g.tobytes() == r.tobytes()
    assert ref[2][:5].all()                          # straight corners: certified as they are
    if iters == 3:
        assert (~ref[2]).any() and ref[2].any()      # the cut-off case does occur
    else:
        assert ref[2].mean() > 0.95 and (~ref[2]).any()
        assert (ref[0] < args[6]).any() and (ref[0] == args[6]).any()   # some shrank
