#!/usr/bin/env python3
"""The cone programme of saddle's `socp` solved by cvxpy + Clarabel (issue 14's conic baseline).

Reads the JSON of `cargo run --release --example export_cone -- SCENE cone.json`
(minimise ½xᵀPx + qᵀx subject to Ax + s = b, s in zero / nonnegative / second-order cones,
rows in order; P upper triangle) and solves it as a cvxpy model with Clarabel at its default
tolerances. The cones of one size are stated as one vectorised `cp.SOC(..., axis=1)` constraint
(cvxpy's fast path; one constraint per cone is several times slower). Prints and writes JSON:
the wall time of the model (building and canonicalisation included) and of Clarabel's own
solve, its iterations, status and objective.

    .venv-peer/bin/pip install cvxpy clarabel
    .venv-peer/bin/python examples/peers/cvxpy_socp.py cone.json --json cvxpy.json
"""

import argparse
import json
import time

import cvxpy as cp
import numpy as np
import scipy.sparse as sp


def csc(d):
    return sp.csc_matrix((d["nzval"], d["rowval"], d["colptr"]), shape=(d["m"], d["n"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cone", help="the JSON of examples/export_cone.rs")
    ap.add_argument("--json", help="write the timings here")
    args = ap.parse_args()
    d = json.load(open(args.cone))
    n, m = d["n"], d["m"]
    upper = csc(d["P"])
    P = (upper + upper.T - sp.diags(upper.diagonal())).tocsc()
    A, b, q = csc(d["A"]).tocsr(), np.array(d["b"]), np.array(d["q"])

    t0 = time.perf_counter()
    x = cp.Variable(n)
    cons, row = [], 0
    socs = {}
    for kind, dim in d["cones"]:
        if kind == "zero":
            cons.append(A[row:row + dim] @ x == b[row:row + dim])
        elif kind == "nonneg":
            cons.append(A[row:row + dim] @ x <= b[row:row + dim])
        elif kind == "soc":
            socs.setdefault(dim, []).append(row)
        else:
            raise SystemExit(f"unknown cone {kind}")
        row += dim
    assert row == m, (row, m)
    for dim, starts in socs.items():
        rows = (np.array(starts)[:, None] + np.arange(dim)[None, :]).ravel()
        s = b[rows] - A[rows] @ x  # cone k's entries at k*dim .. k*dim+dim
        s = cp.reshape(s, (len(starts), dim), order="C")
        cons.append(cp.SOC(s[:, 0], s[:, 1:], axis=1))
    objective = cp.Minimize(0.5 * cp.quad_form(x, cp.psd_wrap(P)) + q @ x)
    problem = cp.Problem(objective, cons)
    problem.solve(solver=cp.CLARABEL)
    wall = time.perf_counter() - t0
    stats = problem.solver_stats
    out = dict(variables=n, constraints=m, soc_cones=sum(len(v) for v in socs.values()), wall_s=wall,
               solve_s=stats.solve_time, setup_s=stats.setup_time, iterations=stats.num_iters,
               status=problem.status, objective=problem.value)
    print(json.dumps(out, indent=1))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
