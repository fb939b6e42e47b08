#!/usr/bin/env python3
"""uq-driver's builtin:wheel-scm written with OpenTURNS + fmpy (a peer in `make bench`):

    .venv/bin/python bench/wheel_scm_openturns.py target/fmu/Wheel.fmu OUT_DIR

6 × 6 Gauss–Hermite nodes (GaussProductExperiment), the FMU run at each by fmpy (one
FMU2Slave reset between points), a total-order-5 chaos projected on the same nodes
(FunctionalChaosAlgorithm, FixedStrategy + IntegrationStrategy), mean and Std over time from
the quadrature and from the chaos, Sobol' indices over time (FunctionalChaosSobolIndices),
4 000 draws of the chaos (its metamodel) for the quantiles and the PDFs over time, the CSV
files uq-driver writes. Prints its own timing as JSON.
"""
import time

STARTED = time.perf_counter()

import sys  # noqa: E402
import os  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
import openturns as ot  # noqa: E402

import peer_common as pc  # noqa: E402


def main(fmu_path, out_dir):
    dist = ot.JointDistribution([ot.Normal(pc.K_MEAN, pc.K_STD), ot.Normal(pc.C_MEAN, pc.C_STD)])
    experiment = ot.GaussProductExperiment(dist, [pc.NODES, pc.NODES])
    nodes, weights = experiment.generateWithWeights()
    y, runs_s = pc.run_wheel(fmu_path, np.array(nodes))
    mean, std = pc.quadrature_moments(np.array(weights), y)

    basis = ot.OrthogonalProductPolynomialFactory([ot.HermiteFactory()] * 2)
    size = basis.getEnumerateFunction().getBasisSizeFromTotalDegree(pc.ORDER)
    algo = ot.FunctionalChaosAlgorithm(
        nodes, weights, ot.Sample(y), dist, ot.FixedStrategy(basis, size),
        ot.IntegrationStrategy())
    algo.run()
    result = algo.getResult()
    coeffs = np.array(result.getCoefficients())  # terms × times (orthonormal basis)
    std_chaos = np.sqrt((coeffs[1:] ** 2).sum(axis=0))
    sobol = ot.FunctionalChaosSobolIndices(result)
    s1 = np.array([[sobol.getSobolIndex(i, k) for k in range(pc.NT)] for i in range(2)])
    st = np.array([[sobol.getSobolTotalIndex(i, k) for k in range(pc.NT)] for i in range(2)])

    ot.RandomGenerator.SetSeed(42)
    draws = np.array(result.getMetaModel()(dist.getSample(pc.DRAWS)))
    pc.write_outputs(out_dir, mean, std, std_chaos, draws, s1, st)
    pc.report(STARTED, runs_s, library=f"openturns {ot.__version__}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
