"""chaospy's point-collocation (regression) chaos, a peer in bench/hd_goals.py.

chaospy has no basis selection: the expansion of each total order (chaospy.generate_expansion,
orthonormal, hyperbolic `cross_truncation` = q) is fitted by ordinary least squares on the
design, and the order is chosen here among those with at most N/2 terms (twice as many runs
as terms, the usual rule) by the leave-one-out error, computed from the hat matrix. The chaos
is built in the germs (U(-1, 1) for a uniform input, N(0, 1) for a normal or lognormal one,
chaospy's recommended generalized chaos); the model is evaluated at the physical values they
map to. Statistics from the orthonormal coefficients (mean, Std, Sobol' indices).
"""
import functools

import numpy as np
import chaospy

import hd_common as hc

MAX_ORDER = 20


def germ_dist(kinds):
    return chaospy.J(*[chaospy.Uniform(-1, 1) if k == "uniform" else chaospy.Normal(0, 1)
                       for k in kinds])


def multi_index_set(d, order, q):
    """Multi-indices of total degree <= order whose q-norm is <= order (graded order)."""
    out = [()]
    for _ in range(d):
        out = [a + (k,) for a in out for k in range(order + 1) if sum(a) + k <= order]
    out = [a for a in out if sum(x ** q for x in a) ** (1 / q) <= order + 1e-9]
    return np.array(sorted(out, key=lambda a: (sum(a), tuple(-x for x in a))), dtype=int)


@functools.lru_cache(maxsize=None)
def one_d_expansion(kind, order):
    return chaospy.generate_expansion(order, germ_dist([kind]), normed=True)


def design_matrix(kinds, alphas, z):
    """Φ_α(z) = ∏_i φ_{α_i}(z_i), the product of chaospy's one-dimensional orthonormal
    polynomials of each germ (chaospy.generate_expansion(order, germ, normed=True))."""
    order = int(alphas.max()) if alphas.size else 0
    cols = np.ones((len(z), len(alphas)))
    for j, kind in enumerate(kinds):
        one_d = one_d_expansion(kind, order)
        vals = np.asarray(one_d(z[:, j]))  # (order + 1) × N
        cols *= vals[alphas[:, j]].T
    return cols


def fit(kinds, z, y, q=1.0):
    """Fits the regression chaos on germs z (N × d) and values y; returns the statistics
    and the order chosen (None when even order 1 has more than N/2 terms)."""
    n, d = z.shape
    best = None
    for order in range(1, MAX_ORDER + 1):
        alphas = multi_index_set(d, order, q)
        if len(alphas) > n // 2:
            break
        a = design_matrix(kinds, alphas, z)
        c, loo = hc.loo_ols(a, y)
        if best is None or loo < best[0]:
            best = (loo, order, alphas, c)
    if best is None:
        return None
    loo, order, alphas, c = best
    st = hc.sobol_from_chaos(alphas, c)
    st.update(order=order, terms=len(c), loo=loo)
    return st
