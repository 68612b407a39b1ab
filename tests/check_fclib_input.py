#!/usr/bin/python3
"""kergs -fclib_input (docs/solver.md, "Solving FCLib problems"), tested through the executable.

  check_fclib_input.py TEST --kergs build/kergs --mpiexec mpiexec --dir WORKDIR

TEST is one of:
  solve     kergs exports step 5 of confine500 (friction 0.3, and frictionless), solved by Newton to 1e-10, then reads the
            files back: Newton from r = 0 reaches 1e-10 and NLGS 1e-8 (natural residual), statistics in the results file;
            started from the stored solution the import is the run's problem (Newton stops at once, same impulses, same
            residual); frictionless (a unique solution here) Newton from r = 0 finds the run's impulses to 1e-8 on 1 and
            2 ranks, NLGS to its tolerance; -fclib_output writes the problem again (W, q, mu as read) with the impulses
            found as its solution, on 1 and 2 ranks, and that solution read back solves it with no Newton step; a
            solve stopped after 3 Newton steps writes the answer it reached
  global    a global problem (M diagonal, H of full column rank, f, w, mu) written with h5py around a known exact solution
            (contacts open, sticking, slipping either way): started there Newton stops at once (W = H^T M^-1 H and
            q = H^T M^-1 f + w built right), and from r = 0 Newton and NLGS find it (W is positive definite: one solution);
            an off-diagonal M is refused
  bad       a missing file, a text file, an HDF5 file that is no FCLib problem, a 3D problem, a NaN in q, a short
            dataset, a non-symmetric W, -fclib_start solution without a solution, a kernel-regularised type, an
            -fclib_output that is the -fclib_input or an -options_file, or on a full file system: each refused with a
            message naming the fault, no crash
Exit status 0 when every check holds, 1 otherwise."""
import argparse
import os
import shutil
import sys

import h5py
import numpy as np
import scipy.sparse

from checks import Kergs, check, failures, small_tmpfs

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFINE500 = os.path.join(ROOT, "cases", "confine500.opts")


class FCLibKergs(Kergs):
    """The runner, with an export of confine500's step 5 and a solve of an FCLib file."""

    def export(self, name, *extra):
        """Step 5 of confine500 solved by Newton to 1e-10, exported."""
        out = self.path(name)
        p = self.run(1, "-options_file", CONFINE500, "-steps", 5, "-fclib_step", 5, "-fclib_output", out, "-output_none", "-quiet",
                     "-solver_type", "newton", "-solver_tol", 1e-10, *extra)
        if not check(p.returncode == 0 and os.path.exists(out), f"kergs exports step 5 of confine500 {' '.join(map(str, extra))} to {name}"):
            print(p.stdout[-2000:], p.stderr[-2000:])
        return out

    def solve(self, fclib, results, ranks=1, *args):
        p = self.run(ranks, "-fclib_input", fclib, "-output", results, *args)
        if p.returncode != 0:
            print(p.stdout[-3000:], p.stderr[-3000:])
            return p, None
        with h5py.File(results, "r") as f:
            stats = {k: float(f["stats"][k][-1]) for k in f["stats"]}
            stats["solver_type"] = f["stats"].attrs["solver_type"].decode()
        return p, stats


def read_local(path):
    """W (compressed columns), q, mu and the stored solution r of a local FCLib file, as arrays."""
    with h5py.File(path, "r") as f:
        g = f["fclib_local"]
        m = int(g["W/m"][0])
        W = scipy.sparse.csc_matrix((g["W/x"][()], g["W/i"][()], g["W/p"][()]), shape=(m, m))
        r = f["solution/r"][()] if "solution" in f else None
        return W, g["vectors/q"][()], g["vectors/mu"][()], r, f["fclib_local/info/title"][()]


def check_solved_file(k, source, solved, ranks):
    """solved (-fclib_output of an -fclib_input run on source) holds source's problem, its solution solves it: read back,
    Newton takes no step. W is the one the solvers used: its upper triangle mirrored (the import accepts asymmetry up to
    1e-10 of the largest entry; kergs's exports carry rounding's), so it equals the input's to that tolerance; it may
    hold explicit zeros the input did not (the solvers store W by 2 x 2 blocks)."""
    if not check(os.path.exists(solved), f"-fclib_output writes {os.path.basename(solved)} ({ranks} rank(s))"):
        return
    (Wa, qa, mua, _, _), (Wb, qb, mub, rb, title) = read_local(source), read_local(solved)
    dW = float(abs(Wa - Wb).max() / abs(Wa).max()) if Wa.shape == Wb.shape else np.inf
    same = dW <= 1e-10 and np.array_equal(qa, qb) and np.array_equal(mua, mub)
    check(same, f"{ranks} rank(s): the written problem is the one read (q, mu equal; W to {dW:.2g} of its largest entry <= 1e-10)")
    check(b"kergs solution of" in bytes(title), f"{ranks} rank(s): its title says it is kergs's solution of the input")
    check(rb is not None and np.all(np.isfinite(rb)), f"{ranks} rank(s): it holds a finite solution")
    p, s = k.solve(solved, k.path(f"solved_back_{ranks}.h5"), 1, "-solver_type", "newton", "-solver_tol", 1e-10, "-fclib_start", "solution")
    if check(s is not None, f"{ranks} rank(s): the written file is read back"):
        check(s["iterations"] == 0 and s["residual"] <= 1e-10,
              f"{ranks} rank(s): its solution solves it: residual {s['residual']:.3g}, {s['iterations']:.0f} Newton steps")


def test_solve(k):
    friction = k.export("c500.fclib.h5")
    frictionless = k.export("c500_frictionless.fclib.h5", "-friction", 0)
    with h5py.File(friction, "r") as f:
        nc = len(f["fclib_local/vectors/mu"])
        assert_some_friction = float(np.max(f["fclib_local/vectors/mu"][()]))
    check(nc > 500 and assert_some_friction == 0.3, f"the frictional export holds {nc} contacts with mu 0.3")

    # from r = 0 (Siconos's start): the residual reached, whatever solution is found (with friction it need not be unique)
    solved = k.path("c500_solved.fclib.h5")
    p, s = k.solve(friction, k.path("newton.h5"), 1, "-solver_type", "newton", "-solver_tol", 1e-10, "-solver_max_it", 1000,
                   "-fclib_output", solved)
    if check(s is not None, "newton solves the frictional problem from r = 0"):
        check_solved_file(k, friction, solved, 1)
        check(s["residual"] <= 1e-10 and s["converged"] == 1, f"newton: natural residual {s['residual']:.3g} <= 1e-10, converged")
        check(s["contacts"] == nc and s["active"] == nc, "newton: every contact of the file is a contact of the solve")
        check(s["solve_seconds"] > 0 and s["iterations"] >= 1 and s["solver_type"] == "newton", "newton: time, iterations, type recorded")
        check(p.stdout.count("fclib c500 contacts") == 1 and " residual " in p.stdout, "newton: one summary line")
    p, s = k.solve(friction, k.path("nlgs.h5"), 1, "-solver_type", "nlgs", "-solver_criterion", "natural", "-solver_tol", 1e-8,
                   "-solver_max_it", 100000)
    if check(s is not None, "nlgs solves the frictional problem from r = 0"):
        check(s["residual"] <= 1e-8 and s["converged"] == 1, f"nlgs: natural residual {s['residual']:.3g} <= 1e-8 after {s['iterations']:.0f} sweeps")

    # a solve stopped early writes the answer it reached: read back, it starts there (its residual, no step)
    capped = k.path("c500_capped.fclib.h5")
    p, s = k.solve(friction, k.path("newton_capped.h5"), 1, "-solver_type", "newton", "-solver_max_it", 3, "-fclib_output", capped)
    if check(s is not None and s["converged"] == 0 and p.returncode == 0, "newton stopped after 3 Newton steps writes its answer (exit 0)"):
        p2, back = k.solve(capped, k.path("capped_back.h5"), 1, "-solver_type", "newton", "-solver_tol", 1, "-fclib_start", "solution")
        if check(back is not None, "the capped answer is read back"):
            check(back["iterations"] == 0 and abs(back["residual"] - s["residual"]) <= 1e-6 * s["residual"],
                  f"it is the answer the capped solve reached: residual {back['residual']:.6g} against {s['residual']:.6g}")
            check(read_local(capped)[3] is not None and not np.allclose(read_local(capped)[3], read_local(friction)[3]),
                  "not the input's stored solution")

    # from the stored solution: the run's very problem (W, q, mu read exactly), so newton has nothing to do
    p, s = k.solve(friction, k.path("newton_start.h5"), 1, "-solver_type", "newton", "-solver_tol", 1e-10, "-fclib_start", "solution")
    if check(s is not None, "newton from the file's solution"):
        check(s["iterations"] == 0 and s["residual"] <= 1e-10, f"the run's solution solves the imported problem: residual {s['residual']:.3g}, "
              f"{s['iterations']:.0f} Newton steps")
        check(s["reference_impulse_difference"] == 0.0, "and the impulses are the run's")

    # frictionless: the solve from r = 0 finds the run's impulses
    for ranks in (1, 2):
        solved = k.path(f"c500_frictionless_solved_{ranks}.fclib.h5")
        p, s = k.solve(frictionless, k.path(f"newton_frictionless_{ranks}.h5"), ranks, "-solver_type", "newton", "-solver_tol", 1e-10,
                       "-solver_max_it", 1000, "-fclib_output", solved)
        if check(s is not None, f"newton solves the frictionless problem on {ranks} rank(s)"):
            check_solved_file(k, frictionless, solved, ranks)
            check(s["residual"] <= 1e-10, f"newton, {ranks} rank(s): natural residual {s['residual']:.3g} <= 1e-10")
            check(s["reference_impulse_difference"] <= 1e-8 and s["reference_velocity_difference"] <= 1e-8,
                  f"newton, {ranks} rank(s): impulses {s['reference_impulse_difference']:.3g} and velocities "
                  f"{s['reference_velocity_difference']:.3g} from the run's (relative) <= 1e-8")
    p, s = k.solve(frictionless, k.path("nlgs_frictionless.h5"), 1, "-solver_type", "nlgs", "-solver_criterion", "natural", "-solver_tol",
                   1e-8, "-solver_max_it", 100000)
    if check(s is not None, "nlgs solves the frictionless problem"):
        check(s["residual"] <= 1e-8 and s["reference_impulse_difference"] <= 1e-4,
              f"nlgs: residual {s['residual']:.3g} <= 1e-8, impulses {s['reference_impulse_difference']:.3g} from the run's <= 1e-4")


def write_global(path, rng, offdiag=False):
    """A 2D global FCLib problem with 4 contacts around a known solution r*, u* = W r* + q; returns them."""
    n, nc = 10, 4
    m = 2 * nc
    H = rng.standard_normal((n, m))
    Mdiag = rng.uniform(1.0, 3.0, n)
    M = np.diag(Mdiag)
    if offdiag:
        M[0, 1] = M[1, 0] = 0.1
    mu = np.array([0.3, 0.5, 0.2, 0.4])
    # per contact (normal, tangential): open, stick, slip with u_t > 0, slip with u_t < 0
    r = np.array([0.0, 0.0, 1.0, 0.1, 2.0, -0.2 * 2.0, 0.5, 0.4 * 0.5])
    u = np.array([0.7, 0.0, 0.0, 0.0, 0.0, 0.3, 0.0, -0.8])
    f = rng.standard_normal(n)
    W = H.T @ np.diag(1 / Mdiag) @ H
    w = u - W @ r - H.T @ (f / Mdiag)
    with h5py.File(path, "w") as h:
        g = h.create_group("fclib_global")
        g["spacedim"] = np.array([2], dtype=np.int32)
        for name, A in (("M", M), ("H", H)):
            cols = [np.nonzero(A[:, j])[0] for j in range(A.shape[1])]  # compressed columns (nz = -1)
            p = np.concatenate([[0], np.cumsum([len(c) for c in cols])]).astype(np.int32)
            i = np.concatenate(cols).astype(np.int32)
            x = np.concatenate([A[c, j] for j, c in enumerate(cols)])
            for key, val in (("m", A.shape[0]), ("n", A.shape[1]), ("nz", -1), ("nzmax", len(x))):
                g[f"{name}/{key}"] = np.array([val], dtype=np.int32)
            g[f"{name}/p"], g[f"{name}/i"], g[f"{name}/x"] = p, i, x
        g["vectors/f"], g["vectors/w"], g["vectors/mu"] = f, w, mu
        h["solution/r"], h["solution/u"] = r, u
        h["solution/v"] = np.linalg.solve(M, H @ r + f)
    return r, u


def test_global(k):
    rng = np.random.default_rng(11)
    path = k.path("global.fclib.h5")
    write_global(path, rng)
    p, s = k.solve(path, k.path("global_start.h5"), 1, "-solver_type", "newton", "-solver_tol", 1e-12, "-fclib_start", "solution")
    if check(s is not None, "newton from the known solution of the global problem"):
        check(s["iterations"] == 0 and s["residual"] <= 1e-13, f"the known solution solves the problem kergs built: residual {s['residual']:.3g}")
    for solver, extra in (("newton", ["-solver_tol", 1e-12]), ("nlgs", ["-solver_criterion", "natural", "-solver_tol", 1e-12, "-solver_max_it", 100000])):
        p, s = k.solve(path, k.path(f"global_{solver}.h5"), 1, "-solver_type", solver, *extra)
        if check(s is not None, f"{solver} solves the global problem from r = 0"):
            check(s["residual"] <= 1e-12 and s["reference_impulse_difference"] <= 1e-9,
                  f"{solver}: residual {s['residual']:.3g}, the known impulses to {s['reference_impulse_difference']:.3g} (<= 1e-9)")
    bad = k.path("global_offdiag.fclib.h5")
    write_global(bad, rng, offdiag=True)
    refused(k, "global problem with an off-diagonal M", ["M has an off-diagonal entry", "diagonal M"], "-fclib_input", bad, "-output",
            k.path("offdiag.h5"))


def refused(k, what, regex_words, *args):
    p = k.run(1, *args)
    out = p.stdout + p.stderr
    crashed = any(w in out for w in ("Segmentation", "SIGSEGV", "Caught signal", "core dumped"))
    ok = p.returncode != 0 and not crashed and all(w in out for w in regex_words)
    if not check(ok, f"{what}: refused, the message says {regex_words}"):
        print(out[-2500:])


def copy_with(k, src, name, edit):
    dst = k.path(name)
    shutil.copyfile(src, dst)
    with h5py.File(dst, "r+") as f:
        edit(f)
    return dst


def check_full_disk(k, good):
    """-fclib_output on a file system too small for it (a 200 KB tmpfs; skipped unless root can mount one): refused with
    "No space left on device" naming the file before libfclib writes (it exits the process on a failed write), no .tmp
    left, and the solve's results file, written first, kept."""
    with small_tmpfs(k.path("full")) as mnt:
        if mnt is None:
            print("skipped: a full file system (cannot mount a small tmpfs here)")
            return
        out, results = os.path.join(mnt, "solved.fclib.h5"), k.path("full_results.h5")
        p = k.run(1, "-fclib_input", good, "-output", results, "-fclib_output", out)
        text = p.stdout + p.stderr
        check(p.returncode == 1 and "No space left on device" in text and out in text,
              f"a full file system: -fclib_output refused, 'No space left on device' naming it (exit {p.returncode})")
        check(not os.path.exists(out) and not os.path.exists(out + ".tmp") and os.path.exists(results),
              "no partial file is left, and the results file of the solve is kept")


def test_bad(k):
    good = k.export("good.fclib.h5")
    out = ["-output", k.path("bad.h5")]
    refused(k, "missing file", ["no_such.fclib.h5", "No such file"], "-fclib_input", k.path("no_such.fclib.h5"), *out)
    text = k.path("text.fclib.h5")
    with open(text, "w") as f:
        f.write("not hdf5\n")
    refused(k, "text file", ["text.fclib.h5", "not an HDF5 file"], "-fclib_input", text, *out)
    other = k.path("other.h5")
    with h5py.File(other, "w") as f:
        f["stats/residual"] = np.zeros(3)
    refused(k, "HDF5 file without FCLib groups", ["other.h5", "not an FCLib problem"], "-fclib_input", other, *out)

    def set_3d(f):
        f["fclib_local/spacedim"][0] = 3

    refused(k, "3D problem", ["3D problem", "spacedim 2"], "-fclib_input", copy_with(k, good, "three_d.fclib.h5", set_3d), *out)

    def set_nan(f):
        f["fclib_local/vectors/q"][7] = np.nan

    refused(k, "NaN in q", ["q has a non-finite entry", "at 7"], "-fclib_input", copy_with(k, good, "nan.fclib.h5", set_nan), *out)

    def set_subnormal(f):  # kergs's own export of biaxial 20k's step 3 holds a q entry of 5e-317: finite, so accepted
        f["fclib_local/vectors/q"][7] = 5e-317

    p = k.run(1, "-fclib_input", copy_with(k, good, "subnormal.fclib.h5", set_subnormal), "-output", k.path("subnormal.h5"), "-solver_type",
              "newton", "-solver_max_it", 1000)
    check(p.returncode == 0, "a subnormal entry in q is a finite number: accepted")

    def shorten_mu(f):
        mu = f["fclib_local/vectors/mu"][()]
        del f["fclib_local/vectors/mu"]
        f["fclib_local/vectors/mu"] = mu[:-1]

    refused(k, "short dataset", ["fclib_local/vectors/mu has", "expected"], "-fclib_input", copy_with(k, good, "short.fclib.h5", shorten_mu), *out)

    def break_symmetry(f):
        p, i = f["fclib_local/W/p"][()], f["fclib_local/W/i"][()]
        for e in range(p[0], p[1]):  # an off-diagonal entry of column 0
            if i[e] != 0:
                f["fclib_local/W/x"][e] = f["fclib_local/W/x"][e] + 1.0
                return

    refused(k, "non-symmetric W", ["not symmetric"], "-fclib_input", copy_with(k, good, "asym.fclib.h5", break_symmetry), *out)
    # the options of a scene's time loop: named as options that an FCLib run does not use (-help lists them for scenes)
    for opt, val in (("-steps", 5), ("-progress_every", 1), ("-checkpoint_every", 1)):
        refused(k, f"{opt} with -fclib_input", ["an -fclib_input run does not use option " + opt, "time loop"], "-fclib_input", good, *out,
                opt, val)
    refused(k, "-output_every with -fclib_input", ["-output_every: an -fclib_input run writes", "no snapshot"], "-fclib_input", good, *out,
            "-output_every", 1)
    p = k.run(1, "-fclib_input", good, "-output", k.path("quiet.h5"), "-quiet")
    check(p.returncode == 0 and "fclib " in p.stdout, "-quiet with -fclib_input is accepted (the summary line stays)")

    def drop_solution(f):
        del f["solution"]

    nosol = copy_with(k, good, "nosol.fclib.h5", drop_solution)
    refused(k, "-fclib_start solution without one", ["holds no solution"], "-fclib_input", nosol, "-fclib_start", "solution", *out)
    refused(k, "kernel-regularised type", ["-solver_type nlgsjac needs", "nlgs or newton"], "-fclib_input", good, "-solver_type", "nlgsjac",
            *out)
    refused(k, "misspelled option", ["does not use option -solver_max_itt", "misspelled?"], "-fclib_input", good, "-solver_max_itt", 3, *out)
    opts = k.path("run.opts")
    with open(opts, "w") as f:
        f.write("-solver_type newton\n")
    refused(k, "-fclib_output that is an -options_file", ["-fclib_output", "-options_file", "run.opts"], "-options_file", opts,
            "-fclib_input", good, "-fclib_output", opts, *out)
    check(open(opts).read() == "-solver_type newton\n", "the options file is left as it was")
    before = os.path.getmtime(good), os.path.getsize(good)
    refused(k, "-fclib_output that is the -fclib_input", ["-fclib_output", "-fclib_input", "good.fclib.h5"], "-fclib_input", good,
            "-fclib_output", good, *out)
    check((os.path.getmtime(good), os.path.getsize(good)) == before, "the input is left as it was")
    check_full_disk(k, good)
    p = k.run(1, "-fclib_input", nosol, "-output", k.path("nosol.h5"), "-solver_type", "newton", "-solver_max_it", 1000)
    check(p.returncode == 0 and "against the file's solution" not in p.stdout, "a file without a solution is solved, no comparison")
    check(not os.path.exists(k.path("bad.h5")), "no results file is left by a refused input")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("test", choices=("solve", "global", "bad"))
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    os.makedirs(a.dir, exist_ok=True)
    k = FCLibKergs(a)
    {"solve": test_solve, "global": test_global, "bad": test_bad}[a.test](k)
    print(f"{len(failures)} failure(s)" if failures else "every check holds")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
