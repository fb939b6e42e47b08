#!/usr/bin/env python3
"""uq-driver's builtin:wheel-scm written with chaospy + fmpy (a peer in `make bench`):

    .venv/bin/python bench/wheel_scm_chaospy.py target/fmu/Wheel.fmu OUT_DIR

6 × 6 Gauss–Hermite nodes (generate_quadrature, order 5, rule "gaussian"), the FMU run at
each by fmpy (one FMU2Slave reset between points), a total-order-5 chaos projected on the
same nodes (generate_expansion + fit_quadrature), mean and Std over time from the quadrature
and from the chaos (E, Std), Sobol' indices over time (Sens_m, Sens_t), 4 000 draws of the
chaos for the quantiles and the PDFs over time, the CSV files uq-driver writes. Prints its
own timing as JSON.
"""
import time

STARTED = time.perf_counter()

import sys  # noqa: E402
import os  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import chaospy as cp  # noqa: E402

import peer_common as pc  # noqa: E402


def main(fmu_path, out_dir):
    dist = cp.J(cp.Normal(pc.K_MEAN, pc.K_STD), cp.Normal(pc.C_MEAN, pc.C_STD))
    nodes, weights = cp.generate_quadrature(pc.NODES - 1, dist, rule="gaussian")
    y, runs_s = pc.run_wheel(fmu_path, nodes.T)
    mean, std = pc.quadrature_moments(weights, y)

    expansion = cp.generate_expansion(pc.ORDER, dist)
    model = cp.fit_quadrature(expansion, nodes, weights, y)
    std_chaos = cp.Std(model, dist)
    s1 = cp.Sens_m(model, dist)
    st = cp.Sens_t(model, dist)

    draws = model(*dist.sample(pc.DRAWS, seed=42)).T  # draws × times
    pc.write_outputs(out_dir, mean, std, std_chaos, draws, s1, st)
    pc.report(STARTED, runs_s, library=f"chaospy {cp.__version__}")


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
