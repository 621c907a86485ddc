#!/usr/bin/python3
"""Accelerated projected gradient in numpy/scipy, run by contactbench as a `command` solver.

    minimize 1/2 x'Ax - b'x  subject to  Jx >= c,  J with decoupled rows

The protocol (docs/INTERFACES.md "The command protocol"): contactbench runs
``python3 examples/pgd_solver.py {settings}``; settings.json names the snapshot, the folder
``out`` to write into and the common settings (tol, max_iterations, time_limit_s, seed). This
program writes ``out/x.npy``, ``out/lambda.npy`` and ``out/result.json`` (status, iterations,
self-reported times, its residual, a history with iterates every ``STRIDE`` iterations).

Rows must not share a column ("accepts": "decoupled" in the suite): then the projection onto
{Jx >= c} is one independent step per row and exact. The harness decouples a coupled J first and
judges the answer on the original QP.

Method: FISTA (Beck & Teboulle 2009) with step 1/L, L = max row sum of |A| (an upper bound of the
largest eigenvalue, so the step is always safe), restarted when the objective goes up
(O'Donoghue & Candes 2015). Its stop test mirrors the harness's accuracy measure (docs/accuracy.md)
in a simplified form: stationarity (|D^-1 r|_inf and each body's translation under r, r = Ax - b -
J'lambda; the measure's rotations left out) and penetration, both as
fractions of the scene size, with lambda from the rows on their face.
"""

import json
import os
import sys
import time

import numpy as np
import scipy.sparse
import scipy.sparse.csgraph

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
from plots.qpsnap import matrices, read_qpsnap  # noqa: E402  (the repository's numpy-only reader)

STRIDE = 25        # iterations between saved iterates (the harness measures each one)
MAX_ITERATES = 40  # iterates saved at most
MARGIN = 0.05      # stop at MARGIN * tol on our own test, so the harness's measure (with rotations) agrees


def scene_size(x0):
    """Largest axis extent of x0 read as 3-D points (the measure's length scale), else its range."""
    pts = x0.reshape(-1, 3) if x0.size % 3 == 0 and x0.size else x0.reshape(-1, 1)
    extent = float(np.max(pts.max(axis=0) - pts.min(axis=0))) if x0.size else 0.0
    return extent if extent > 0 else 1.0


def body_translations(A):
    """T (n x 3 bodies, or n x bodies when n is no multiple of 3) and diag(T'AT): the translations of
    the bodies, the connected components of A's vertex graph."""
    n = A.shape[0]
    per_node = 3 if n % 3 == 0 else 1
    nodes = n // per_node
    coo = A.tocoo()
    keep = coo.data != 0
    graph = scipy.sparse.coo_matrix((np.ones(int(keep.sum())), (coo.row[keep] // per_node, coo.col[keep] // per_node)),
                                    shape=(nodes, nodes))
    _, body = scipy.sparse.csgraph.connected_components(graph, directed=False)
    dof = np.arange(n)
    column = body[dof // per_node] * per_node + dof % per_node
    T = scipy.sparse.csr_matrix((np.ones(n), (dof, column)), shape=(n, int(column.max()) + 1 if n else 1))
    mass = np.asarray((T.T @ (A @ T)).diagonal()).ravel()
    return T, np.where(mass > 0, mass, np.inf)


def main(settings_path):
    t_start = time.perf_counter()
    with open(settings_path) as f:
        cfg = json.load(f)
    snap = read_qpsnap(cfg["snapshot"])
    A, J = matrices(snap)
    arrays = snap["arrays"]
    b, c, x0 = arrays["b"], arrays["c"], np.array(arrays["x0"], dtype=float)
    out = cfg["out"]
    tol, max_it, limit = cfg["tol"], cfg["max_iterations"], cfg["time_limit_s"]

    row_norm2 = np.asarray(J.multiply(J).sum(axis=1)).ravel()
    live = row_norm2 > 0
    inv_norm2 = np.where(live, 1.0 / np.where(live, row_norm2, 1.0), 0.0)
    if np.any(np.asarray((J != 0).astype(np.int64).sum(axis=0)).ravel() > 1):
        sys.exit("pgd_solver: two rows of J share a column; declare \"accepts\": \"decoupled\"")
    diag = A.diagonal()
    length = scene_size(x0)
    lipschitz = float(abs(A).sum(axis=1).max())
    translate, translate_mass = body_translations(A)

    def project(x):
        return x + J.T @ (np.maximum(0.0, c - J @ x) * inv_norm2)

    def objective(x):
        return 0.5 * x @ (A @ x) - b @ x

    def measure(x):
        """(error, lambda): our stop test and the multipliers of the rows on their face."""
        g = A @ x - b
        gap = (J @ x - c) * np.sqrt(inv_norm2)
        on_face = live & (gap <= 1e-12 * length)
        lam = np.where(on_face, np.maximum(0.0, (J @ g) * inv_norm2), 0.0)
        r = g - J.T @ lam
        # the Jacobi step, and each body's translation under the residual (the measure's rigid
        # motion without its rotations)
        moved = np.abs(translate.T @ r) / translate_mass if x.size else np.zeros(1)
        stationarity = max(np.max(np.abs(r / diag)), np.max(moved)) / length if x.size else 0.0
        primal = np.max(np.maximum(0.0, -gap)) / length if gap.size else 0.0
        return max(stationarity, primal), lam

    t_setup = time.perf_counter()
    x = project(x0)
    y, x_prev, t = x.copy(), x.copy(), 1.0
    f_prev = objective(x)
    history, saved = [], 0
    status, it = "max_iterations", 0
    error, lam = measure(x)
    for it in range(1, max_it + 1):
        x = project(y - (A @ y - b) / lipschitz)
        f = objective(x)
        if f > f_prev:  # restart the momentum: plain projected gradient from x_prev
            t, y = 1.0, x_prev
            x = project(y - (A @ y - b) / lipschitz)
            f = objective(x)
        t_next = 0.5 * (1.0 + np.sqrt(1.0 + 4.0 * t * t))
        y = x + ((t - 1.0) / t_next) * (x - x_prev)
        x_prev, t, f_prev = x, t_next, f
        error, lam = measure(x)
        row = {"iteration": it, "time_s": time.perf_counter() - t_setup, "residual": error}
        if it % STRIDE == 0 and saved < MAX_ITERATES:
            name = "x_%06d.npy" % it
            np.save(os.path.join(out, name), x)
            row["x"] = name
            saved += 1
        if len(history) < 2000:
            history.append(row)
        if error <= MARGIN * tol:
            status = "converged"
            break
        if limit > 0 and time.perf_counter() - t_start > 0.9 * limit:
            status = "time_limit"
            break
    t_end = time.perf_counter()

    np.save(os.path.join(out, "x.npy"), x)
    np.save(os.path.join(out, "lambda.npy"), lam)
    result = {"status": status, "iterations": it, "setup_s": t_setup - t_start, "solve_s": t_end - t_setup,
              "residual": error, "history": history,
              "message": "pgd_solver: FISTA, step 1/L with L = %.3g, own error %.3g" % (lipschitz, error)}
    with open(os.path.join(out, "result.json"), "w") as f:
        json.dump(result, f)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: pgd_solver.py SETTINGS.json")
    main(sys.argv[1])
