#!/usr/bin/python3
"""Four exact methods for the 2D frictional contact problem, prototyped on kergs's FCLib exports before any C is
written, and not kept, and one diagnosis of a stored answer (docs/solver.md, "Prototypes measured and not kept"). All
are judged by kergs's own natural residual (scripts/siconos_solve.py's, recomputed from r).

  proto_fixed_points.py desaxce PROBLEM.fclib.h5 [--outer 40] [--theta 1.0]
  proto_fixed_points.py fb-lcp  PROBLEM.fclib.h5 [--max-it 200]
  proto_fixed_points.py ip-lcp  PROBLEM.fclib.h5 [--max-it 200] [--write ANSWER.fclib.h5]
  proto_fixed_points.py lm      PROBLEM.fclib.h5 [--max-it 200] [--start zero|stored]
  proto_fixed_points.py pieces  PROBLEM.fclib.h5 [--perturb 0] [--max-it 5000]

desaxce: the De Saxce fixed point of Acary, Cadoux, Lemarechal and Malick (2011). With the shift s = mu |u_t| fixed, the
problem is a convex QP: r in the Coulomb cone K (in 2D the cone of its two edges e+- = (1, +-mu), so r = a e+ + b e-
with a, b >= 0), and u + s e_n in the dual cone, complementary to r. In the edge coordinates z = (a, b) it is the
monotone LCP 0 <= z _|_ E^T W E z + E^T (q + s e_n) >= 0, solved here by Mehrotra's predictor-corrector interior point.
Its velocities u = W E z are unique even where W's kernel leaves r undetermined (unlike the Tresca fixed point's
thresholds mu r_n), and at a fixed point s = mu |u_t| the pair (r, u) solves Coulomb's problem. --theta relaxes the
update s <- (1 - theta) s + theta mu |u_t|.

fb-lcp: the 2D law as the linear complementarity problem of Stewart and Trinkle in (r_n, beta+, beta-, lambda) per
contact (r_t = beta+ - beta-, lambda the sliding speed), every pair scaled to impulse units by rho = 1 / W_nn, solved
by a semismooth Newton method on the Fischer-Burmeister function with an Armijo search on its C^1 merit (De Luca,
Facchinei and Kanzow 1996), and a gradient step where the Newton direction does not descend.

ip-lcp: the same Stewart-Trinkle LCP solved by Mehrotra's predictor-corrector interior point (the desaxce QPs' solver),
although its theory needs a monotone LCP and this one is not; from every x equal to the scale of its right-hand side.
--write copies the problem with the best iterate (by natural residual) as its solution, so that kergs can start from
it (-fclib_input ANSWER -fclib_start solution).

lm: Levenberg-Marquardt on kergs's Alart-Curnier function F (rho = 1 / W_nn, its generalized Jacobian J = A + B W),
lambda = |F| (Yamashita and Fukushima), the step from the augmented system [[-I, J], [J^T, lambda I]] (J^T J is denser),
an Armijo search on 1/2 |F|^2; from r = 0 or from the solution stored in the file (kergs's answer).

pieces: whether the stored answer's contact states admit a solution. With the states of F at r (open, stick, slip and
its sign), the step dr that makes them hold exactly (open: r + dr = 0; stick: u + W dr = 0; slip: u_n + (W dr)_n = 0
with r_t + dr_t = +-mu (r_n + dr_n)) solves a linear system, singular where W is. LSQR's least-squares solution says
how much of its right-hand side no dr reaches: near 0 when the states are those of a solution nearby, large when they
are not. --perturb e multiplies r by 1 + e N(0, 1) first (a control: a solution perturbed keeps most of its states).
Reports the natural residual after the best of the steps 1, 1/2, ..., 1/16 along dr.

Each prints one line per outer iteration (desaxce), per interior-point iteration (ip-lcp) or per 10 Newton steps (fb-lcp)
and a last JSON line.
"""
import argparse
import json
import math
import os
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from siconos_solve import InputError, contact_rho, natural_residual, read_problem  # noqa: E402


def block_diagonal(blocks):
    """A sparse block-diagonal matrix from an array of k x l blocks."""
    return sp.block_diag([sp.csr_matrix(b) for b in blocks], format="csr")


def interior_point_lcp(M, b, z0=None, tol=1e-14, max_it=200, monitor=None):
    """Mehrotra's predictor-corrector on the LCP 0 <= z _|_ w = M z + b >= 0 (its theory needs M monotone; ip-lcp runs it
    on one that is not). monitor(it, z), when given, is called before each iteration and ends the solve by returning
    True. Returns z, iterations, ok."""
    n = b.size
    scale = max(float(np.abs(b).max()), 1e-300)
    z = np.ones(n) if z0 is None else np.maximum(z0, 1e-3 * max(float(z0.max()), 1e-12))
    w = np.maximum(M @ z + b, 0) + scale
    for it in range(max_it):
        f1 = w - M @ z - b
        gap = z @ w / n
        if np.linalg.norm(f1, np.inf) <= tol * scale and gap <= tol * scale * max(float(z.max()), 1e-300):
            return z, it, True
        if monitor is not None and monitor(it, z):
            return z, it, True
        lu = spla.splu((M + sp.diags(w / z)).tocsc(), permc_spec="COLAMD")

        def direction(target):
            f2 = z * w - target
            dz = lu.solve(f1 - f2 / z)
            return dz, (-f2 - w * dz) / z

        def longest(dz, dw):
            step = 1.0
            for v, d in ((z, dz), (w, dw)):
                neg = d < 0
                if np.any(neg):
                    step = min(step, float(np.min(-v[neg] / d[neg])))
            return step

        dza, dwa = direction(np.zeros(n))
        step = longest(dza, dwa)
        centring = ((z + step * dza) @ (w + step * dwa) / n / gap) ** 3 if gap > 0 else 0.0
        dz, dw = direction(centring * gap - dza * dwa)
        step = min(1.0, 0.995 * longest(dz, dw))
        z, w = z + step * dz, w + step * dw
    return z, max_it, False


def desaxce(prob, outer, theta):
    W, q, mu = prob["W"].tocsr(), prob["q"], prob["mu"]
    E = block_diagonal([[[1.0, 1.0], [m, -m]] for m in mu])
    M = (E.T @ W @ E).tocsr()
    u = q.copy()
    s = mu * np.abs(u[1::2])
    z, history, ipm = None, [], 0
    for k in range(outer):
        shifted = q.copy()
        shifted[0::2] += s
        z, its, ok = interior_point_lcp(M, E.T @ shifted, z0=z)
        ipm += its
        r = E @ z
        u = W @ r + q
        target = mu * np.abs(u[1::2])
        res = natural_residual(prob, r)[0]
        change = float(np.linalg.norm(target - s) / max(np.linalg.norm(target), 1e-300))
        history.append(res)
        print(f"outer {k + 1}: {its} interior-point iterations{'' if ok else ' (not converged)'}, natural residual {res:.3e}, "
              f"|mu |u_t| - s| / |mu |u_t|| {change:.2e}", flush=True)
        if res < 1e-10:
            break
        s = (1 - theta) * s + theta * target
    return {"method": "desaxce", "outer": len(history), "interior_point_iterations": ipm, "residual": history[-1],
            "residual_best": min(history)}


def fischer_burmeister(a, b):
    return np.hypot(a, b) - a - b


def stewart_trinkle(W, q, mu):
    """M x + c with x = (r_n, beta+, beta-, lambda') per contact, lambda' = lambda / rho, rows in impulse units (rho = 1 / W_nn);
    r = T x."""
    rho = contact_rho(W)  # as the natural residual's rho
    T = block_diagonal([[[1, 0, 0, 0], [0, 1, -1, 0]] for _ in mu])
    S = block_diagonal([[[p, 0], [0, p], [0, -p], [0, 0]] for p in rho])
    G = block_diagonal([[[0, 0, 0, 0], [0, 0, 0, 1], [0, 0, 0, 1], [m, -1, -1, 0]] for m in mu])
    return (S @ W @ T + G).tocsr(), S @ q, T


def fb_lcp(prob, max_it):
    M, c, T = stewart_trinkle(prob["W"].tocsr(), prob["q"], prob["mu"])
    x = np.zeros(c.size)
    res = 1.0
    for it in range(max_it + 1):
        F = M @ x + c
        phi = fischer_burmeister(x, F)
        merit = 0.5 * phi @ phi
        res = natural_residual(prob, T @ np.maximum(x, 0))[0]
        if it % 10 == 0:
            print(f"Newton step {it}: natural residual {res:.3e}, |Phi| {math.sqrt(2 * merit):.3e}", flush=True)
        if res < 1e-10 or it == max_it:
            break
        norm = np.hypot(x, F)
        kink = norm < 1e-300
        norm[kink] = 1.0
        da = np.where(kink, 1 / math.sqrt(2) - 1, x / norm - 1)
        db = np.where(kink, 1 / math.sqrt(2) - 1, F / norm - 1)
        H = (sp.diags(da) + sp.diags(db) @ M).tocsc()
        grad = H.T @ phi
        try:
            d = spla.splu((H + 1e-10 * sp.identity(c.size)).tocsc()).solve(-phi)
            if not np.all(np.isfinite(d)) or grad @ d > -1e-12 * np.linalg.norm(d) ** 2.1:
                d = -grad
        except RuntimeError:
            d = -grad
        t = 1.0
        for _ in range(60):  # after 60 halvings the smallest step is taken, as kergs's newton does
            trial = x + t * d
            p = fischer_burmeister(trial, M @ trial + c)
            if 0.5 * p @ p <= merit + 1e-4 * t * (grad @ d):
                break
            t *= 0.5
        x = trial
    return {"method": "fb-lcp", "newton_steps": it, "residual": res}


def ip_lcp(prob, max_it):
    """Mehrotra's interior point on the Stewart-Trinkle LCP itself (not monotone once mu > 0), from x = the scale of c;
    stops at natural residual 1e-10. Returns the JSON dict and r."""
    M, c, T = stewart_trinkle(prob["W"].tocsr(), prob["q"], prob["mu"])
    history, best = [], {}

    def monitor(it, x):
        r = T @ x
        history.append(natural_residual(prob, r)[0])
        print(f"interior-point iteration {it}: natural residual {history[-1]:.3e}", flush=True)
        if history[-1] <= min(history):
            best["r"] = r
        return history[-1] < 1e-10

    x0 = np.full(c.size, max(float(np.abs(c).max()), 1e-300))
    x, its, _ = interior_point_lcp(M, c, z0=x0, tol=0.0, max_it=max_it, monitor=monitor)
    res = natural_residual(prob, T @ x)[0]
    r = best["r"] if history and min(history) < res else T @ x
    return {"method": "ip-lcp", "iterations": its, "residual": res, "residual_best": min(history + [res])}, r


def write_solution(source, target, prob, r):
    """A copy of the problem file with r (and u = W r + q) as its solution, for kergs's -fclib_start solution; written
    to a temporary file and renamed."""
    import shutil

    import h5py
    tmp = target + ".tmp"
    shutil.copyfile(source, tmp)
    with h5py.File(tmp, "r+") as f:
        for name, value in (("r", r), ("u", prob["W"] @ r + prob["q"])):
            path = "solution/" + name
            if path in f:
                del f[path]
            f.create_dataset(path, data=value)
    os.replace(tmp, target)


def alart_curnier(W, q, mu, rho, r, jacobian):
    """F(r) contact by contact, the contact states, and with `jacobian` J = A + B W (sparse)."""
    u = W @ r + q
    rn, rt, un, ut = r[0::2], r[1::2], u[0::2], u[1::2]
    xi, zeta = rn - rho * un, rt - rho * ut
    tau = mu * np.maximum(0, xi)
    F = np.empty_like(r)
    F[0::2], F[1::2] = rn - np.maximum(0, xi), rt - np.clip(zeta, -tau, tau)
    opened = xi <= 0
    stick = ~opened & (np.abs(zeta) <= tau)
    sign = np.where(zeta > tau, 1.0, -1.0)
    states = {"u": u, "open": opened, "stick": stick, "slip": ~opened & ~stick, "sign": sign}
    if not jacobian:
        return F, states, None
    A, B = np.zeros((mu.size, 2, 2)), np.zeros((mu.size, 2, 2))
    A[opened, 0, 0] = A[opened, 1, 1] = 1
    B[~opened, 0, 0] = rho[~opened]
    B[stick, 1, 1] = rho[stick]
    slip = states["slip"]
    A[slip, 1, 0], A[slip, 1, 1] = -sign[slip] * mu[slip], 1
    B[slip, 1, 0] = sign[slip] * mu[slip] * rho[slip]
    return F, states, (block_diagonal(A) + block_diagonal(B) @ W).tocsr()


def levenberg_marquardt(prob, max_it, start):
    W, q, mu = prob["W"].tocsr(), prob["q"], prob["mu"]
    rho, m = contact_rho(W), prob["m"]
    if start == "stored" and prob["r_kergs"] is None:
        raise InputError(f"{prob['path']}: no stored solution (/solution/r) to start from")
    r = prob["r_kergs"].copy() if start == "stored" else np.zeros(m)
    for it in range(max_it + 1):
        F, _, J = alart_curnier(W, q, mu, rho, r, True)
        res = natural_residual(prob, r)[0]
        if it % 10 == 0:
            print(f"Levenberg-Marquardt step {it}: natural residual {res:.3e}, |F| {np.linalg.norm(F):.3e}", flush=True)
        if res < 1e-10 or it == max_it:
            break
        lam = float(np.linalg.norm(F))
        K = sp.bmat([[-sp.identity(m), J], [J.T, lam * sp.identity(m)]], format="csc")
        d = spla.splu(K, permc_spec="COLAMD").solve(np.concatenate([-F, np.zeros(m)]))[m:]
        merit, slope, t = 0.5 * F @ F, float((J.T @ F) @ d), 1.0
        for _ in range(40):
            Ft = alart_curnier(W, q, mu, rho, r + t * d, False)[0]
            if 0.5 * Ft @ Ft <= merit + 1e-4 * t * slope:
                break
            t *= 0.5
        r = r + t * d
    return {"method": "lm", "steps": it, "residual": res}


def piece_equations(W, r, st, mu):
    """A y = b for dr = E y + f: the contact states of `st` made to hold exactly (see the module's docstring)."""
    nc = mu.size
    stick, slip, sign = np.flatnonzero(st["stick"]), np.flatnonzero(st["slip"]), st["sign"]
    f = np.zeros(2 * nc)
    opened = np.flatnonzero(st["open"])
    f[2 * opened], f[2 * opened + 1] = -r[2 * opened], -r[2 * opened + 1]
    f[2 * slip + 1] = sign[slip] * mu[slip] * r[2 * slip] - r[2 * slip + 1]
    ns = stick.size
    rows = np.concatenate([2 * stick, 2 * stick + 1, 2 * slip, 2 * slip + 1])
    cols = np.concatenate([2 * np.arange(ns), 2 * np.arange(ns) + 1, 2 * ns + np.arange(slip.size), 2 * ns + np.arange(slip.size)])
    vals = np.concatenate([np.ones(2 * ns), np.ones(slip.size), sign[slip] * mu[slip]])
    E = sp.csr_matrix((vals, (rows, cols)), shape=(2 * nc, 2 * ns + slip.size))
    picked = np.concatenate([np.stack([2 * stick, 2 * stick + 1], 1).ravel(), 2 * slip])
    P = sp.csr_matrix((np.ones(picked.size), (np.arange(picked.size), picked)), shape=(picked.size, 2 * nc))
    return (P @ W @ E).tocsr(), -(P @ (st["u"] + W @ f)), E, f


def pieces(prob, perturb, max_it):
    W, q, mu = prob["W"].tocsr(), prob["q"], prob["mu"]
    if prob["r_kergs"] is None:
        raise InputError(f"{prob['path']}: no stored solution (/solution/r) to check")
    r = prob["r_kergs"] * (1 + perturb * np.random.default_rng(2013).standard_normal(prob["m"]))
    _, st, _ = alart_curnier(W, q, mu, contact_rho(W), r, False)
    A, b, E, f = piece_equations(W, r, st, mu)
    y, _, its, rnorm, _, anorm, _, arnorm = spla.lsqr(A, b, atol=1e-14, btol=1e-14, iter_lim=max_it)[:8]
    d = E @ y + f
    start = natural_residual(prob, r)[0]
    after = min([start] + [natural_residual(prob, r + d / 2**k)[0] for k in range(5)])
    out = {"method": "pieces", "residual": start, "residual_after_step": after, "lsqr_iterations": int(its),
           "unreached_fraction": float(rnorm / max(np.linalg.norm(b), 1e-300)),
           "lsqr_optimality": float(arnorm / max(anorm * rnorm, 1e-300)), "open": int(st["open"].sum()),
           "stick": int(st["stick"].sum()), "slip": int(st["slip"].sum())}
    print(f"states open {out['open']} stick {out['stick']} slip {out['slip']}; LSQR leaves {out['unreached_fraction']:.2e} of "
          f"the right-hand side; natural residual {start:.3e} -> {after:.3e}", flush=True)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("method", choices=("desaxce", "fb-lcp", "ip-lcp", "lm", "pieces"))
    ap.add_argument("problem")
    ap.add_argument("--outer", type=int, default=40, help="desaxce: outer iterations (default 40)")
    ap.add_argument("--theta", type=float, default=1.0, help="desaxce: relaxation of the shift's update, in (0, 1] (default 1)")
    ap.add_argument("--max-it", type=int, default=None,
                    help="fb-lcp, lm: Newton steps (default 200); ip-lcp: interior-point iterations (200); pieces: LSQR iterations (5000)")
    ap.add_argument("--write", metavar="FILE", help="ip-lcp: write the problem with its answer as the solution, for kergs's "
                    "-fclib_input FILE -fclib_start solution")
    ap.add_argument("--start", choices=("zero", "stored"), default="zero", help="lm: from r = 0 or from the file's solution")
    ap.add_argument("--perturb", type=float, default=0.0, help="pieces: relative random perturbation of the stored r (default 0)")
    a = ap.parse_args(argv)
    if a.max_it is None:
        a.max_it = 5000 if a.method == "pieces" else 200
    if not (0 < a.theta <= 1) or a.outer < 1 or a.max_it < 1 or not (0 <= a.perturb < 1):
        print("proto_fixed_points.py: --theta must lie in (0, 1], --outer and --max-it be positive, --perturb in [0, 1)",
              file=sys.stderr)
        return 2
    if a.write is not None:
        bad = a.method != "ip-lcp" or (os.path.exists(a.write) and not os.path.isfile(a.write))
        if bad or (os.path.exists(a.problem) and os.path.exists(a.write) and os.path.samefile(a.problem, a.write)):
            print(f"proto_fixed_points.py: --write {a.write}: only with ip-lcp, and to a regular file other than the problem",
                  file=sys.stderr)
            return 2
    try:
        prob = read_problem(a.problem)
    except InputError as err:
        print(f"proto_fixed_points.py: {err}", file=sys.stderr)
        return 2
    if prob["nc"] == 0:
        print(f"proto_fixed_points.py: {a.problem} has no contacts: nothing to solve", file=sys.stderr)
        return 2
    t0 = time.time()
    try:
        out = {"desaxce": lambda: desaxce(prob, a.outer, a.theta), "fb-lcp": lambda: fb_lcp(prob, a.max_it),
               "ip-lcp": lambda: ip_lcp(prob, a.max_it),
               "lm": lambda: levenberg_marquardt(prob, a.max_it, a.start),
               "pieces": lambda: pieces(prob, a.perturb, a.max_it)}[a.method]()
    except InputError as err:
        print(f"proto_fixed_points.py: {err}", file=sys.stderr)
        return 2
    if a.method == "ip-lcp":
        out, r = out
        if a.write is not None:
            write_solution(a.problem, a.write, prob, r)
            out["written"] = a.write
    out.update({"problem": a.problem, "contacts": prob["nc"], "seconds": round(time.time() - t0, 2)})
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
