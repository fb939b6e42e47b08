"""OpenTURNS' sparse regression chaos, a peer in bench/hd_goals.py.

FunctionalChaosAlgorithm on the design's physical values with the input law as an OpenTURNS
JointDistribution, the orthonormal basis of each input's germ (Legendre for a uniform input,
Hermite for a normal or lognormal one, OpenTURNS mapping the lognormal through the
isoprobabilistic transformation) truncated by a hyperbolic q-norm at total degree 1, 2, ... up to the
largest degree uq-driver is given (FixedStrategy), and least squares with basis selection by least-angle
regression and the corrected leave-one-out error (LeastSquaresStrategy,
LeastSquaresMetaModelSelectionFactory(LARS(), CorrectedLeaveOneOut())): OpenTURNS' own
sparse chaos, for each degree up to the largest; the degree of smallest corrected
leave-one-out error is kept, as uq-driver does. Mean, Std and Sobol' indices from the chaos (FunctionalChaosRandomVector,
FunctionalChaosSobolIndices).
"""
import math

import numpy as np
import openturns as ot

ot.Log.Show(ot.Log.NONE)


def marginal(law):
    if law[0] == "uniform":
        return ot.Uniform(law[1], law[2]), ot.LegendreFactory()
    if law[0] == "normal":
        return ot.Normal(law[1], law[2]), ot.HermiteFactory()
    if law[0] == "lognormal":
        return ot.LogNormal(law[1], law[2]), ot.HermiteFactory()
    raise ValueError(law)


def fit_degree(dist, facts, x, y, degree, q):
    """OpenTURNS' LARS chaos on the candidate basis of total degree `degree` (q-norm q);
    returns (corrected leave-one-out error of the selected model, result, basis size)."""
    enum = ot.HyperbolicAnisotropicEnumerateFunction(len(facts), q)
    basis = ot.OrthogonalProductPolynomialFactory(list(facts), enum)
    size = enum.getBasisSizeFromTotalDegree(degree)
    selection = ot.LeastSquaresMetaModelSelectionFactory(ot.LARS(), ot.CorrectedLeaveOneOut())
    algo = ot.FunctionalChaosAlgorithm(
        ot.Sample(np.asarray(x)), ot.Sample(np.asarray(y).reshape(-1, 1)), dist,
        ot.FixedStrategy(basis, size), ot.LeastSquaresStrategy(selection))
    algo.run()
    res = algo.getResult()
    history = np.asarray(res.getErrorHistory(), dtype=float)
    return (float(history.min()) if history.size else math.inf), res, size


def fit(laws, x, y, max_degree, q=1.0):
    """Sparse chaos of y on the physical design x (N × d): for each total degree 1, 2, ...
    up to max_degree, OpenTURNS' LARS selection; the degree of smallest corrected
    leave-one-out error is kept (stopping after two degrees without improvement).
    Returns its statistics."""
    margs, facts = zip(*(marginal(law) for law in laws))
    dist = ot.JointDistribution(list(margs))
    best, worse = None, 0
    for degree in range(1, max_degree + 1):
        loo, res, size = fit_degree(dist, facts, x, y, degree, q)
        if best is None or loo < best[0]:
            best, worse = (loo, res, size, degree), 0
        else:
            worse += 1
            if worse == 2:
                break
    loo, res, size, degree = best
    d = len(laws)
    vec = ot.FunctionalChaosRandomVector(res)
    sob = ot.FunctionalChaosSobolIndices(res)
    return {"mean": float(vec.getMean()[0]), "std": math.sqrt(vec.getCovariance()[0, 0]),
            "first": [sob.getSobolIndex(i) for i in range(d)],
            "total": [sob.getSobolTotalIndex(i) for i in range(d)],
            "terms": len(res.getIndices()), "order": degree, "loo": loo}
