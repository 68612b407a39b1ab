#!/usr/bin/python3
"""Solve a 2D frictional contact problem exported by kergs (FCLib HDF5, -fclib_step/-fclib_output) with
Siconos, and check both Siconos's and kergs's solutions with the same residual.

  siconos_solve.py problem.fclib.h5 [--solver nsgs|cpg|lemke|enum] [--tol 1e-10] [--max-it N]
                   [--fixed-sweeps N] [--storage sbm|dense] [--start zero|kergs] [--json]
                   [--check-residual TOL] [--check-u TOL] [--expect-frictionless | --expect-frictional]
                   [--check-min-contacts N] [--same-as OTHER.fclib.h5 [--same-tol TOL]] [--no-solve]

The problem (docs/results.md, "FCLib file"): find u, r in R^m, m = 2 nc, unknowns per contact normal then
tangential, with u = W r + q and Coulomb's law with coefficients mu (Signorini-Coulomb in velocity).

Residual (kergs's own definition, docs/solver.md "Convergence criteria" / src/solver/law.c): per contact, with
u = W r + q, De Saxce's modified velocity u~ = (u_n + mu |u_t|, u_t), rho = 1 / W_nn of that contact (1 if
W_nn <= 0), e = r - proj_K(r - rho u~) with K = {|r_t| <= mu r_n} the Coulomb cone; residual = ||e||_2 / ||r||_2
(||e||_2 when r = 0). It is recomputed here from r: Siconos's info and error are not a convergence certificate.

Siconos 4.4 (Debian's python3-siconos, importable only from /usr/bin/python3) is built without FCLib, so the
file is read with h5py. W goes to Siconos as a sparse block matrix (SBM, 2 x 2 blocks, through
SBM_from_csparse and NM_new_SBM), which fc2d_driver accepts for all four 2D solvers. NSGS then runs
Siconos's sparse NSGS, whose sweep costs O(nnz(W)) like kergs's (its per-sweep stopping test is the relative
change of r; its full error is computed once at the end), so --fixed-sweeps N times the sweep fairly against
kergs. --storage dense gives Siconos a dense numpy W instead (O(m^2) per sweep: 0.3 s per sweep at 8,000
unknowns against 0.6 ms sparse). CPG, LEMKE and ENUM work on either storage; ENUM is exponential.

Exit status: 0 success, 1 a --check-*/--expect-*/--same-as assertion failed, 2 bad usage or malformed file
(the message names the dataset at fault).
"""
import argparse
import json
import math
import os
import sys
import time
import warnings

import numpy as np

TINY = 1e-300
EXIT_CHECK_FAILED = 1
EXIT_BAD_INPUT = 2
SOLVERS = ("nsgs", "cpg", "lemke", "enum")


class InputError(Exception):
    """Bad input: the file is not a readable 2D FCLib local problem (the message names the dataset), or the
    options cannot be applied to it."""


# --------------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------------

def _dataset(f, path, path_in_file):
    if path_in_file not in f:
        raise InputError(f"{path}: missing dataset {path_in_file}")
    obj = f[path_in_file]
    if not hasattr(obj, "shape"):
        raise InputError(f"{path}: {path_in_file} is a group, expected a dataset")
    return np.asarray(obj[()])


def _scalar_int(f, path, name):
    value = _dataset(f, path, name).ravel()
    if value.size != 1 or not np.issubdtype(value.dtype, np.integer):
        raise InputError(f"{path}: {name} must hold one integer, found {value.size} value(s) of type {value.dtype}")
    return int(value[0])


def _vector(f, path, name, length, kind=np.floating):
    value = _dataset(f, path, name).ravel()
    if not np.issubdtype(value.dtype, kind):
        raise InputError(f"{path}: {name} has type {value.dtype}, expected {kind.__name__}")
    if length is not None and value.size != length:
        raise InputError(f"{path}: {name} has {value.size} entries, expected {length}")
    if kind is np.floating and not np.all(np.isfinite(value)):
        bad = int(np.flatnonzero(~np.isfinite(value))[0])
        raise InputError(f"{path}: {name}[{bad}] = {value[bad]} is not finite")
    return value


def _string(f, name):
    if name not in f:
        return ""
    value = f[name][()]
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)


def _read_matrix(f, path, m):
    """W from /fclib_local/W: compressed columns (nz = -1), compressed rows (nz = -2) or triplets (nz >= 0)."""
    import scipy.sparse as sp

    base = "fclib_local/W"
    rows, cols = _scalar_int(f, path, base + "/m"), _scalar_int(f, path, base + "/n")
    nz, nzmax = _scalar_int(f, path, base + "/nz"), _scalar_int(f, path, base + "/nzmax")
    if rows != cols:
        raise InputError(f"{path}: {base} is {rows} x {cols}, expected square")
    if rows != m:
        raise InputError(f"{path}: {base}/m = {rows} but fclib_local/vectors/q has {m} entries")
    if nzmax < 0:
        raise InputError(f"{path}: {base}/nzmax = {nzmax} is negative")
    p = _vector(f, path, base + "/p", None, np.integer).astype(np.int64)
    i = _vector(f, path, base + "/i", None, np.integer).astype(np.int64)
    x = _vector(f, path, base + "/x", None)
    if nz in (-1, -2):
        if p.size != m + 1:
            raise InputError(f"{path}: {base}/p has {p.size} entries, expected m + 1 = {m + 1} (nz = {nz})")
        if p[0] != 0 or np.any(np.diff(p) < 0):
            raise InputError(f"{path}: {base}/p is not a pointer array (must start at 0 and never decrease)")
        count = int(p[-1])
        if count > nzmax or i.size < count or x.size < count:
            raise InputError(f"{path}: {base}/p ends at {count} but nzmax = {nzmax}, {base}/i has {i.size} and {base}/x {x.size} entries")
        if count and (i[:count].min() < 0 or i[:count].max() >= m):
            raise InputError(f"{path}: {base}/i holds an index outside [0, {m})")
        if nz == -1:
            W = sp.csc_matrix((x[:count], i[:count], p), shape=(m, m))
        else:
            W = sp.csr_matrix((x[:count], i[:count], p), shape=(m, m)).tocsc()
    elif nz >= 0:
        # fclib.h: triplet p = row indices, i = column indices
        if p.size < nz or i.size < nz or x.size < nz:
            raise InputError(f"{path}: {base} has nz = {nz} triplets but p, i, x have {p.size}, {i.size}, {x.size} entries")
        if nz and (min(p[:nz].min(), i[:nz].min()) < 0 or max(p[:nz].max(), i[:nz].max()) >= m):
            raise InputError(f"{path}: {base}/p or {base}/i holds an index outside [0, {m})")
        W = sp.coo_matrix((x[:nz], (p[:nz], i[:nz])), shape=(m, m)).tocsc()
    else:
        raise InputError(f"{path}: {base}/nz = {nz}: expected -1 (compressed columns), -2 (compressed rows) or a triplet count")
    W.sum_duplicates()
    W.sort_indices()
    W.indices = W.indices.astype(np.int64)  # Siconos's CSparse uses 64-bit indices
    W.indptr = W.indptr.astype(np.int64)
    return W


def read_problem(path):
    """The local problem and, when present, the solution stored with it (kergs's r and u)."""
    import h5py

    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file")
    try:
        f = h5py.File(path, "r")
    except OSError as err:
        raise InputError(f"{path}: not an HDF5 file ({err})") from None
    with f:
        if "fclib_local" not in f:
            raise InputError(f"{path}: missing group /fclib_local (not an FCLib local problem)")
        spacedim = _scalar_int(f, path, "fclib_local/spacedim")
        if spacedim != 2:
            raise InputError(f"{path}: fclib_local/spacedim = {spacedim}; this script solves 2D problems only")
        q = _vector(f, path, "fclib_local/vectors/q", None)
        m = q.size
        if m % 2:
            raise InputError(f"{path}: fclib_local/vectors/q has {m} entries, not a multiple of spacedim = 2")
        nc = m // 2
        mu = _vector(f, path, "fclib_local/vectors/mu", nc)
        if np.any(mu < 0):
            raise InputError(f"{path}: fclib_local/vectors/mu[{int(np.flatnonzero(mu < 0)[0])}] is negative")
        W = _read_matrix(f, path, m)
        r_kergs = u_kergs = None
        if "solution" in f and "r" in f["solution"]:
            r_kergs = _vector(f, path, "solution/r", m)
            if "u" in f["solution"]:
                u_kergs = _vector(f, path, "solution/u", m)
        title = _string(f, "fclib_local/info/title")
    if m == 0 and r_kergs is None:  # kergs writes no /solution for an empty problem: its solution is r = ()
        r_kergs = np.zeros(0)
    if nc:
        wnn = W.diagonal()[0::2]
        if np.any(wnn < 0):
            raise InputError(f"{path}: fclib_local/W has a negative diagonal entry W_nn of contact {int(np.flatnonzero(wnn < 0)[0])}")
    return {"path": path, "title": title, "W": W, "q": q, "mu": mu, "nc": nc, "m": m,
            "r_kergs": r_kergs, "u_kergs_stored": u_kergs}


# --------------------------------------------------------------------------------------------------------
# Residual and complementarity (kergs's definitions, recomputed from r)
# --------------------------------------------------------------------------------------------------------

def project_coulomb_cone(zn, zt, mu):
    """Projection on K = {r_n >= 0, |r_t| <= mu r_n}, contact by contact. K is spanned by the rays (1, +mu) and
    (1, -mu); its polar cone is {z_n <= -mu |z_t|}; outside both the projection lies on the ray (1, mu sign z_t),
    p_n = (z_n + mu |z_t|) / (1 + mu^2). r_n >= 0 is tested explicitly so that mu = 0 (K a half-line) is right."""
    at = np.abs(zt)
    inside = (zn >= 0) & (at <= mu * zn)
    polar = ~inside & (mu * at <= -zn)
    pn = np.where(inside, zn, np.where(polar, 0.0, (zn + mu * at) / (1.0 + mu * mu)))
    pt = np.where(inside, zt, np.where(polar, 0.0, np.copysign(mu * pn, zt)))
    return pn, pt


def contact_rho(W):
    """rho = 1 / W_nn per contact (1 where W_nn <= 0): the scale of kergs's natural map and of its newton."""
    wnn = W.diagonal()[0::2]
    return np.where(wnn > 0, 1.0 / np.where(wnn > 0, wnn, 1.0), 1.0)


def natural_residual(prob, r):
    """(relative residual, ||e||, u): e = r - proj_K(r - rho u~), u~ = (u_n + mu |u_t|, u_t), rho = 1 / W_nn; the residual
    is ||e|| / max(||r||, ||p||), p = r - e (kergs's KergsLawNaturalResidualScaled): 1 at r = 0 unless e = 0."""
    W, q, mu = prob["W"], prob["q"], prob["mu"]
    u = W @ r + q
    if prob["nc"] == 0:
        return 0.0, 0.0, u
    rho = contact_rho(W)
    rn, rt, un, ut = r[0::2], r[1::2], u[0::2], u[1::2]
    pn, pt = project_coulomb_cone(rn - rho * (un + mu * np.abs(ut)), rt - rho * ut, mu)
    enorm = math.sqrt(float(np.sum((rn - pn) ** 2) + np.sum((rt - pt) ** 2)))
    scale = max(float(np.linalg.norm(r)), math.sqrt(float(np.sum(pn**2) + np.sum(pt**2))))
    return (enorm / scale if scale > 0 else 0.0), enorm, u


def complementarity(prob, r, u):
    """Violations of r in K, u~ in K* (i.e. u_n >= 0) and r . u~ = 0, relative to max|r| and max(|u|, |q|)."""
    if prob["nc"] == 0:
        return {"cone": 0.0, "dual": 0.0, "gap": 0.0}
    mu = prob["mu"]
    rn, rt, un, ut = r[0::2], r[1::2], u[0::2], u[1::2]
    rscale = max(float(np.max(np.abs(r))), TINY)
    uscale = max(float(np.max(np.abs(u))), float(np.max(np.abs(prob["q"]))), TINY)
    cone = float(np.max(np.maximum(np.maximum(np.abs(rt) - mu * rn, -rn), 0.0))) / rscale
    dual = float(np.max(np.maximum(-un, 0.0))) / uscale
    gap = float(np.max(np.abs(rn * (un + mu * np.abs(ut)) + rt * ut))) / (rscale * uscale)
    return {"cone": cone, "dual": dual, "gap": gap}


# --------------------------------------------------------------------------------------------------------
# Siconos
# --------------------------------------------------------------------------------------------------------

class StdoutToStderr:
    """Siconos's C code may print on file descriptor 1: keep stdout for the JSON line."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        os.dup2(2, 1)
        return self

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self.saved, 1)
        os.close(self.saved)
        return False


def siconos_problem(prob, storage):
    """FrictionContactProblem with W as a sparse block matrix (2 x 2 blocks) or a dense array. The objects
    SBM_from_csparse and NM_new_SBM return are kept alive with the problem (returned alongside it)."""
    import siconos.numerics as sn

    if storage == "dense":
        return sn.FrictionContactProblem(2, prob["W"].toarray(), prob["q"], prob["mu"]), ()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # int32/int64 conversion notes; indices are int64 already
        info, sbm = sn.SBM_from_csparse(2, prob["W"])
    if info != 0:
        raise RuntimeError(f"Siconos SBM_from_csparse failed (info {info}) on {prob['path']}")
    nm = sn.NM_new_SBM(prob["m"], prob["m"], sbm)
    if nm.storageType != sn.NM_SPARSE_BLOCK:
        raise RuntimeError("Siconos NM_new_SBM did not give a sparse block matrix")
    return sn.FrictionContactProblem(2, nm, prob["q"], prob["mu"]), (sbm, nm)


def solve_siconos(prob, solver, tol, max_it, storage, r0):
    """Run fc2d_driver; returns r, Siconos's info and error, iterations done, solve and setup seconds."""
    import siconos.numerics as sn

    ident = {"nsgs": sn.SICONOS_FRICTION_2D_NSGS, "cpg": sn.SICONOS_FRICTION_2D_CPG,
             "lemke": sn.SICONOS_FRICTION_2D_LEMKE, "enum": sn.SICONOS_FRICTION_2D_ENUM}[solver]
    t0 = time.perf_counter()
    problem, keep = siconos_problem(prob, storage)
    options = sn.SolverOptions(ident)
    options.iparam[sn.SICONOS_IPARAM_MAX_ITER] = max_it
    options.dparam[sn.SICONOS_DPARAM_TOL] = tol
    r = np.array(r0, dtype=float)
    u = np.zeros(prob["m"])
    t1 = time.perf_counter()
    with StdoutToStderr():
        info = sn.fc2d_driver(problem, r, u, options)
    t2 = time.perf_counter()
    iterations = int(options.iparam[sn.SICONOS_IPARAM_ITER_DONE])
    error = float(options.dparam[sn.SICONOS_DPARAM_RESIDU])
    del keep
    return r, int(info), error, iterations, t2 - t1, t1 - t0


# --------------------------------------------------------------------------------------------------------
# Comparing two exports of the same step (1 and 2 ranks): same problem up to the order of the contacts
# --------------------------------------------------------------------------------------------------------

def _block_rows(W, nc):
    """Per contact a, {b: 2 x 2 block W_ab} for the nonzero blocks of its block row."""
    C = W.tocoo()
    rows = [dict() for _ in range(nc)]
    for i, j, x in zip(C.row.tolist(), C.col.tolist(), C.data.tolist()):
        blk = rows[i // 2].setdefault(j // 2, np.zeros((2, 2)))
        blk[i % 2, j % 2] += x
    return rows


def _contact_features(prob):
    """Per contact, numbers that do not depend on the contact order: mu, q_a, the diagonal block W_aa, and the
    sum and largest absolute value of the entries of its off-diagonal blocks."""
    W, nc = prob["W"].tocoo(), prob["nc"]
    own = (W.row // 2) == (W.col // 2)
    off = ~own
    a = W.row[off] // 2
    offsum = np.bincount(a, weights=np.abs(W.data[off]), minlength=nc)
    offmax = np.zeros(nc)
    np.maximum.at(offmax, a, np.abs(W.data[off]))
    Wc = prob["W"]
    diag = np.stack([Wc.diagonal()[0::2], Wc.diagonal(1)[0::2], Wc.diagonal(-1)[0::2], Wc.diagonal()[1::2]], axis=1)
    return np.column_stack([prob["mu"], prob["q"][0::2], prob["q"][1::2], diag, offsum, offmax])


def match_contacts(A, B, tol, budget=None):
    """(perm, None) with contact a of A = contact perm[a] of B, or (None, reason). Candidates are contacts whose
    features agree within tol (relative); ties (symmetric scenes) are resolved by a depth-first search over the
    contacts in breadth-first order, which must keep every block W_ab equal."""
    nc = A["nc"]
    budget = budget or max(200000, 50 * nc)
    fa, fb = _contact_features(A), _contact_features(B)
    scale = np.maximum(np.maximum(np.abs(fa).max(axis=0), np.abs(fb).max(axis=0)), TINY)
    # one scalar key per contact, a fixed combination of the scaled features: contacts that agree within tol
    # have keys within tol * sum(weights), so a sorted search finds the candidates without an nc^2 scan
    weights = np.linspace(1.0, 2.0, fa.shape[1])
    ka, kb = (fa / scale) @ weights, (fb / scale) @ weights
    sorted_b = np.argsort(kb, kind="stable")
    lo = np.searchsorted(kb[sorted_b], ka - tol * weights.sum() * 1.001, side="left")
    hi = np.searchsorted(kb[sorted_b], ka + tol * weights.sum() * 1.001, side="right")
    cand = []
    for a in range(nc):
        window = sorted_b[lo[a]:hi[a]]
        close = window[np.all(np.abs(fb[window] - fa[a]) <= tol * scale, axis=1)]
        if close.size == 0:
            worst = np.abs(fb - fa[a]) / (tol * scale)
            names = ("mu", "q_n", "q_t", "W_nn", "W_nt", "W_tn", "W_tt", "sum |W_ab|", "max |W_ab|")
            nearest = int(np.argmin(worst.max(axis=1)))
            return None, (f"contact {a} of {A['path']} has no counterpart in {B['path']} (nearest: contact {nearest}, "
                          f"which differs most in {names[int(np.argmax(worst[nearest]))]})")
        cand.append(sorted(close.tolist()))
    if all(len(c) == 1 for c in cand) and len({c[0] for c in cand}) == nc:
        return [c[0] for c in cand], None  # no tie: the full comparison of W follows in compare_problems
    rowsA, rowsB = _block_rows(A["W"], nc), _block_rows(B["W"], nc)
    wscale = max(abs(A["W"]).max(), abs(B["W"]).max(), TINY)
    zero = np.zeros((2, 2))
    order, parent = _breadth_first(rowsA, cand)
    perm, inverse = [-1] * nc, [-1] * nc

    def consistent(a, b):
        for a2, blk in rowsA[a].items():
            b2 = b if a2 == a else perm[a2]
            if b2 >= 0 and np.abs(blk - rowsB[b].get(b2, zero)).max() > tol * wscale:
                return False
        for b2, blk in rowsB[b].items():
            a2 = a if b2 == b else inverse[b2]
            if a2 >= 0 and np.abs(blk - rowsA[a].get(a2, zero)).max() > tol * wscale:
                return False
        return True

    def choices(a):  # a neighbour of an assigned contact maps to a neighbour of its image
        if parent[a] < 0:
            return cand[a]
        near = rowsB[perm[parent[a]]]
        return [b for b in cand[a] if b in near]

    # depth-first search without recursion (tens of thousands of contacts)
    k, steps = 0, 0
    options, pointer = [None] * nc, [0] * nc
    while 0 <= k < nc:
        a = order[k]
        if options[k] is None:
            options[k], pointer[k] = choices(a), 0
        elif perm[a] >= 0:  # back here: undo this level's assignment, try the next candidate
            inverse[perm[a]], perm[a] = -1, -1
        while pointer[k] < len(options[k]):
            b = options[k][pointer[k]]
            pointer[k] += 1
            steps += 1
            if steps > budget:
                return None, f"contact matching gave up after {budget} trials (too many identical contacts)"
            if inverse[b] < 0 and consistent(a, b):
                perm[a], inverse[b] = b, a
                break
        if perm[a] >= 0:
            k += 1
            if k < nc:
                options[k] = None
        else:
            options[k] = None
            k -= 1
    if k == nc:
        return perm, None
    return None, "no ordering of the contacts makes the blocks W_ab agree"


def _breadth_first(rows, cand):
    """Contacts in breadth-first order over the block graph of W, each component started at its contact with
    the fewest candidates; parent[a] is the contact it was reached from (-1 for a start)."""
    nc = len(rows)
    order, parent, seen = [], [-1] * nc, [False] * nc
    for start in sorted(range(nc), key=lambda a: len(cand[a])):
        if seen[start]:
            continue
        seen[start] = True
        queue = [start]
        for a in queue:
            order.append(a)
            for b in rows[a]:
                if not seen[b]:
                    seen[b], parent[b] = True, a
                    queue.append(b)
    return order, parent


def compare_problems(A, B, tol):
    """Relative differences of W, q, mu after matching the contacts of A to those of B."""
    out = {"same_as": B["path"], "contacts": [A["nc"], B["nc"]]}
    if A["nc"] != B["nc"]:
        out["same"] = False
        out["reason"] = f"{A['nc']} contacts against {B['nc']}"
        return out
    perm, reason = match_contacts(A, B, tol) if A["nc"] else ([], None)
    if perm is None:
        out["same"] = False
        out["reason"] = reason
        return out
    idx = np.array([[2 * b, 2 * b + 1] for b in perm], dtype=np.int64).ravel()
    WB = B["W"][idx][:, idx]
    dW = abs(A["W"] - WB).max() if A["nc"] else 0.0
    out["W_difference"] = float(dW) / max(abs(A["W"]).max() if A["nc"] else 0.0, abs(B["W"]).max() if B["nc"] else 0.0, TINY)
    qscale = max(float(np.max(np.abs(A["q"]), initial=0.0)), float(np.max(np.abs(B["q"]), initial=0.0)), TINY)
    out["q_difference"] = float(np.max(np.abs(A["q"] - B["q"][idx]), initial=0.0)) / qscale
    out["mu_difference"] = float(np.max(np.abs(A["mu"] - B["mu"][np.array(perm, dtype=np.int64)]), initial=0.0))
    out["nnz"] = [int(A["W"].nnz), int(B["W"].nnz)]
    out["permuted"] = bool(perm != list(range(A["nc"])))
    out["same"] = bool(out["W_difference"] <= tol and out["q_difference"] <= tol and out["mu_difference"] <= tol)
    if A["r_kergs"] is not None and B["r_kergs"] is not None:
        uA = A["W"] @ A["r_kergs"] + A["q"]
        uB = B["W"] @ B["r_kergs"] + B["q"]
        out["kergs_u_difference"] = float(np.max(np.abs(uA - uB[idx]), initial=0.0)) / max(qscale, float(np.max(np.abs(uA), initial=0.0)))
    return out


# --------------------------------------------------------------------------------------------------------
# Driver
# --------------------------------------------------------------------------------------------------------

def parse_args(argv):
    head, _, rest = __doc__.partition("\n\n")
    ap = argparse.ArgumentParser(description=head, epilog=rest.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("problem", help="FCLib HDF5 file written by kergs -fclib_step N -fclib_output FILE")
    ap.add_argument("--solver", choices=SOLVERS, default="nsgs", help="Siconos fc2d solver (default nsgs)")
    ap.add_argument("--tol", type=float, default=1e-10, help="Siconos tolerance (its own error measure; default 1e-10)")
    ap.add_argument("--max-it", type=int, default=10000, help="Siconos iteration cap (default 10000)")
    ap.add_argument("--fixed-sweeps", type=int, metavar="N", help="run exactly N iterations (tol 0, cap N) to time the sweep alone")
    ap.add_argument("--storage", choices=("sbm", "dense"), default="sbm",
                    help="W for Siconos: sparse block matrix (default) or dense numpy array")
    ap.add_argument("--start", choices=("zero", "kergs"), default="zero", help="initial r for Siconos: 0 or kergs's solution")
    ap.add_argument("--enum-max-contacts", type=int, default=8, help="refuse --solver enum above this many contacts (it is exponential)")
    ap.add_argument("--dense-max-gib", type=float, default=4.0, help="refuse --storage dense when W would take more (default 4 GiB)")
    ap.add_argument("--json", action="store_true", help="print one JSON line instead of a summary")
    ap.add_argument("--no-solve", action="store_true", help="do not run Siconos (checks of kergs's solution and --same-as only)")
    ap.add_argument("--check-residual", type=float, metavar="TOL", help="fail unless Siconos's and kergs's residuals are <= TOL")
    ap.add_argument("--check-u", type=float, metavar="TOL", help="fail unless max|u_siconos - u_kergs| / scale <= TOL")
    ap.add_argument("--check-min-contacts", type=int, metavar="N", help="fail unless the problem has at least N contacts")
    fr = ap.add_mutually_exclusive_group()
    fr.add_argument("--expect-frictionless", action="store_true", help="fail unless every mu is 0")
    fr.add_argument("--expect-frictional", action="store_true", help="fail unless some mu is positive")
    ap.add_argument("--same-as", metavar="FILE", help="fail unless FILE holds the same W, q, mu up to the order of the contacts")
    ap.add_argument("--same-tol", type=float, default=1e-8, help="relative tolerance of --same-as (default 1e-8)")
    args = ap.parse_args(argv)
    if args.fixed_sweeps is not None and args.fixed_sweeps < 1:
        ap.error("--fixed-sweeps must be at least 1")
    if args.max_it < 1:
        ap.error("--max-it must be at least 1")
    if args.no_solve and (args.check_u is not None or args.fixed_sweeps is not None):
        ap.error("--no-solve cannot be combined with --check-u or --fixed-sweeps")
    return args


def run(args):
    """Everything the JSON line reports, and the list of checks (name, value, limit, passed)."""
    prob = read_problem(args.problem)
    nc, m, W = prob["nc"], prob["m"], prob["W"]
    frictionless = bool(np.all(prob["mu"] == 0))
    out = {"problem": args.problem, "title": prob["title"], "contacts": nc, "unknowns": m, "nnz": int(W.nnz),
           "frictionless": frictionless,
           "symmetry_error": float(abs(W - W.T).max() / max(abs(W).max(), TINY)) if nc else 0.0}
    checks = []
    if args.same_as:
        other = read_problem(args.same_as)
        out["comparison"] = compare_problems(prob, other, args.same_tol)
        checks.append(("same problem as " + args.same_as, out["comparison"].get("reason", "W, q, mu agree") if not out["comparison"]["same"] else
                       max(out["comparison"]["W_difference"], out["comparison"]["q_difference"], out["comparison"]["mu_difference"]),
                       args.same_tol, out["comparison"]["same"]))

    if prob["r_kergs"] is not None:
        res_k, _, u_k = natural_residual(prob, prob["r_kergs"])
        out["residual_kergs"] = res_k
        out["complementarity_kergs"] = complementarity(prob, prob["r_kergs"], u_k)
        if prob["u_kergs_stored"] is not None:  # the exporter's u must be W r + q
            scale = max(float(np.max(np.abs(u_k), initial=0.0)), float(np.max(np.abs(prob["q"]), initial=0.0)), TINY)
            out["kergs_u_stored_error"] = float(np.max(np.abs(prob["u_kergs_stored"] - u_k), initial=0.0)) / scale
    else:
        out["residual_kergs"] = None

    if not args.no_solve:
        solver = args.solver
        storage = args.storage
        if solver == "enum" and nc > args.enum_max_contacts:
            raise InputError(f"--solver enum on {nc} contacts: ENUM enumerates exponentially many cases; raise --enum-max-contacts to insist")
        if storage == "dense" and 8.0 * m * m > args.dense_max_gib * 2**30:
            raise InputError(f"--storage dense on {m} unknowns needs {8.0 * m * m / 2**30:.1f} GiB (limit --dense-max-gib {args.dense_max_gib:g}); use --storage sbm")
        tol, max_it = (0.0, args.fixed_sweeps) if args.fixed_sweeps else (args.tol, args.max_it)
        if args.start == "kergs" and prob["r_kergs"] is None:
            raise InputError(f"{args.problem}: --start kergs but the file has no solution/r")
        r0 = prob["r_kergs"] if args.start == "kergs" else np.zeros(m)
        out.update({"solver": solver, "storage": storage, "tol": tol, "max_it": max_it})
        if nc:
            r_s, info, error, its, seconds, setup = solve_siconos(prob, solver, tol, max_it, storage, r0)
        else:  # empty problem: nothing to solve
            r_s, info, error, its, seconds, setup = np.zeros(0), 0, 0.0, 0, 0.0, 0.0
        res_s, _, u_s = natural_residual(prob, r_s)
        out.update({"siconos_info": info, "siconos_error": error, "iterations": its, "seconds": seconds, "setup_seconds": setup,
                    "seconds_per_iteration": seconds / its if its else None,
                    "seconds_per_sweep": seconds / its if its and solver == "nsgs" else None,
                    "residual_siconos": res_s, "complementarity_siconos": complementarity(prob, r_s, u_s),
                    "r_norm_siconos": float(np.linalg.norm(r_s))})
        if args.fixed_sweeps and its != args.fixed_sweeps:
            out["warning"] = f"asked for {args.fixed_sweeps} iterations, Siconos did {its}"
        if prob["r_kergs"] is not None:
            Wr_s, Wr_k = W @ r_s, W @ prob["r_kergs"]
            qmax = float(np.max(np.abs(prob["q"]), initial=0.0))
            uscale = max(float(np.max(np.abs(u_s), initial=0.0)), float(np.max(np.abs(u_k), initial=0.0)), qmax, TINY)
            wscale = max(float(np.max(np.abs(Wr_s), initial=0.0)), float(np.max(np.abs(Wr_k), initial=0.0)), qmax, TINY)
            out["u_difference"] = float(np.max(np.abs(u_s - u_k), initial=0.0)) / uscale
            out["Wr_difference"] = float(np.max(np.abs(Wr_s - Wr_k), initial=0.0)) / wscale
            out["r_difference"] = float(np.max(np.abs(r_s - prob["r_kergs"]), initial=0.0)) / max(float(np.max(np.abs(r_s), initial=0.0)), TINY)
            out["r_norm_kergs"] = float(np.linalg.norm(prob["r_kergs"]))
            out["unique_quantities"] = "u and W r (frictionless)" if frictionless else "none guaranteed (friction): residuals only"
        if args.check_residual is not None:
            checks.append(("Siconos residual", res_s, args.check_residual, res_s <= args.check_residual))
    if args.check_residual is not None:
        ok = out["residual_kergs"] is not None and out["residual_kergs"] <= args.check_residual
        checks.append(("kergs residual", out["residual_kergs"] if out["residual_kergs"] is not None else "no solution/r in the file", args.check_residual, ok))
    if args.check_u is not None:
        value = out.get("u_difference")
        checks.append(("u difference Siconos-kergs", value if value is not None else "no solution/r in the file", args.check_u,
                       value is not None and value <= args.check_u))
    if args.check_min_contacts is not None:
        checks.append(("contacts", nc, args.check_min_contacts, nc >= args.check_min_contacts))
    if args.expect_frictionless:
        checks.append(("frictionless (max mu)", float(np.max(prob["mu"], initial=0.0)), 0.0, frictionless))
    if args.expect_frictional:
        checks.append(("frictional (max mu)", float(np.max(prob["mu"], initial=0.0)), "> 0", not frictionless))
    out["checks"] = [{"name": n, "value": v, "limit": l, "passed": bool(p)} for n, v, l, p in checks]
    out["passed"] = all(p for _, _, _, p in checks)
    return out


def _fmt_compl(c):
    return f"cone {c['cone']:.1e}, dual {c['dual']:.1e}, gap {c['gap']:.1e}"


def _fmt(value):
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3e}"
    return str(value)


def print_summary(out):
    print(f"{out['problem']}: {out['title'] or 'untitled'}")
    print(f"  {out['contacts']} contacts, {out['unknowns']} unknowns, nnz(W) {out['nnz']}, "
          f"{'frictionless' if out['frictionless'] else 'frictional'}, symmetry error {_fmt(out['symmetry_error'])}")
    if "solver" in out:
        storage = {"sbm": "sparse block", "dense": "dense"}[out["storage"]]
        print(f"  Siconos {out['solver']} ({storage} W): info {out['siconos_info']}, its error {_fmt(out['siconos_error'])}, "
              f"{out['iterations']} iterations in {out['seconds']:.4g} s (setup {out['setup_seconds']:.3g} s"
              + (f", {out['seconds_per_sweep']:.3e} s per sweep" if out.get("seconds_per_sweep") else "") + ")")
        print(f"  residual Siconos {_fmt(out['residual_siconos'])}   complementarity: {_fmt_compl(out['complementarity_siconos'])}")
    if out["residual_kergs"] is not None:
        print(f"  residual kergs   {_fmt(out['residual_kergs'])}   complementarity: {_fmt_compl(out['complementarity_kergs'])}")
        if "kergs_u_stored_error" in out:
            print(f"  stored u against W r + q: {_fmt(out['kergs_u_stored_error'])}")
    else:
        print("  no kergs solution in the file (solution/r)")
    if "u_difference" in out:
        print(f"  Siconos - kergs: u {_fmt(out['u_difference'])}, W r {_fmt(out['Wr_difference'])}, r {_fmt(out['r_difference'])} "
              f"(relative; unique: {out['unique_quantities']})")
    if "comparison" in out:
        c = out["comparison"]
        print(f"  against {c['same_as']}: " + (f"W {_fmt(c['W_difference'])}, q {_fmt(c['q_difference'])}, mu {_fmt(c['mu_difference'])}"
                                                 + (" (contacts reordered)" if c.get("permuted") else "") if "W_difference" in c else c.get("reason", "")))
    if "warning" in out:
        print("  warning: " + out["warning"])
    for c in out["checks"]:
        print(f"  check {c['name']}: {_fmt(c['value'])} (limit {_fmt(c['limit'])}) {'ok' if c['passed'] else 'FAILED'}")


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        out = run(args)
    except InputError as err:
        print(f"siconos_solve.py: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if args.json:
        print(json.dumps(out, allow_nan=True))
    else:
        print_summary(out)
    if not out["passed"]:
        failed = [c["name"] for c in out["checks"] if not c["passed"]]
        print("siconos_solve.py: FAILED: " + ", ".join(failed), file=sys.stderr)
        return EXIT_CHECK_FAILED
    return 0


if __name__ == "__main__":
    sys.exit(main())
