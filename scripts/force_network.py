#!/usr/bin/python3
"""The force network of a kergs run, as granular physicists read it from its snapshots (Radjai, Jean, Moreau and Roux,
PRL 77, 274 (1996); Radjai, Wolf, Jean and Moreau, PRL 80, 61 (1998)): the distribution of the normal forces, the polar
diagrams of the contact normals and of the mean forces by direction with their Rothenburg-Bathurst fits, and the
stress carried by the strong network (forces above the mean) and by the weak one.

Usage: scripts/force_network.py RESULTS.h5 [--from-strain E0] [--to-strain E1] [-o PREFIX]

Snapshots: those whose step's axial strain (/stats strain_axial) lies in [E0, E1]; by default the last 40 % of the
run's strain, the window in which docs/tradeoff.md reads the critical state. In a run whose walls never form a box
(no strain), every snapshot after the first. Contacts: the force-carrying (r_n > 0) disk-disk contacts of those
snapshots, each force normalised by its snapshot's mean, f = r_n / <r_n>, and pooled.

Writes PREFIX_forces.png (PREFIX defaults to RESULTS without .h5): the probability density of f on a log scale with
the exponential fit of its tail, and the polar diagrams. Prints one JSON line:
  snapshots, steps, strain_window   the snapshots used;
  contacts                          pooled force-carrying disk-disk contacts;
  below_mean                        the fraction with f < 1 (an exponential distribution gives 1 - 1/e = 0.63);
  tail_decay                        beta of P(f) ~ exp(-beta f) for f >= 1, a least-squares fit of log P over the
                                    bins of width 0.1 that hold at least 5 contacts;
  f_max                             the largest f;
  a_c, a_n, a_t                     Rothenburg-Bathurst anisotropies of the pooled contacts, from the tensors of
                                    docs/results.md ("Anisotropies"), with the normalised forces;
  q_over_p                          (s1 - s2)/(s1 + s2) of the disk-disk contacts' Love-Weber tensor, sum of f (x) l
                                    over the contacts (l the branch vector), each snapshot's normalised by its trace;
  q_over_p_strong, q_over_p_weak    the same tensor over f >= 1 and over f < 1, projected on the whole tensor's
                                    principal axes: (e1.s.e1 - e2.s.e2)/(e1.s.e1 + e2.s.e2), signed, so a weak network
                                    whose own anisotropy is orthogonal comes out negative;
  weak_share_p, strong_share_q      the weak network's share of the mean stress, the strong one's of the deviator.
Both outputs are written atomically. The shebang is /usr/bin/python3 on purpose: Debian's h5py and matplotlib import
only there.
"""
import argparse
import json
import math
import os
import sys
import tempfile

import h5py
import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

RESULTS_FORMAT = "kergs results 1"  # the root attribute kergs_format of a results file (src/io/results.c)
CRITICAL_WINDOW = 0.4  # the default window: this fraction of the run's final axial strain, at its end
TAIL_MIN_COUNT = 5  # bins of the tail fit hold at least this many contacts
BIN = 0.1  # width of the histogram's bins of f
ANGLE_BINS = 18  # polar bins over [0, pi): 10 degrees each


def fail(message):
    sys.exit(f"force_network.py: {message}")


def snapshot_steps(f, path):
    """(name, step) of every complete snapshot, in order."""
    fmt = f.attrs.get("kergs_format", b"")
    if (fmt.decode() if isinstance(fmt, bytes) else str(fmt)) != RESULTS_FORMAT:
        fail(f"{path}: not a kergs results file (its root attribute kergs_format is not '{RESULTS_FORMAT}')")
    if "snapshots" not in f:
        fail(f"{path}: no /snapshots")
    count = int(f.attrs.get("nsnapshots", len(f["snapshots"])))
    names = sorted(f["snapshots"].keys())[:count]
    if any("step" not in f["snapshots"][k].attrs for k in names):
        fail(f"{path}: a snapshot has no step attribute (a damaged results file)")
    return [(k, int(f["snapshots"][k].attrs["step"])) for k in names]


def choose(f, path, snaps, lo, hi):
    """The snapshots in the strain window [lo, hi] (None: the default window), and the window used."""
    stats = f.get("stats")
    if stats is None or any(k not in stats for k in ("strain_axial", "step", "box_area")) or not (stats["box_area"][()] > 0).any():
        if lo is not None or hi is not None:
            fail(f"{path}: the walls never form a box, so there is no axial strain for --from-strain or --to-strain")
        return snaps[1:], None
    strain = dict(zip(stats["step"][()].astype(int), stats["strain_axial"][()]))
    final = stats["strain_axial"][-1]
    ends = sorted(((1 - CRITICAL_WINDOW) * final, final))  # an extension test has a negative axial strain
    lo = ends[0] if lo is None else lo
    hi = ends[1] if hi is None else hi
    if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
        fail(f"the strain window [{lo}, {hi}] is empty or not finite")
    chosen = [(k, s) for k, s in snaps if s in strain and lo <= strain[s] <= hi]
    return chosen, (float(lo), float(hi))


def contacts(snap):
    """Force-carrying disk-disk contacts of one snapshot: normals, tangential over normal impulse, branch vectors and
    forces normalised by their mean."""
    kind, r, n = snap["kind"][()].astype(int), snap["r"][()], snap["n"][()]
    if r.ndim == 1:  # frictionless: one component
        r = np.stack([r, np.zeros_like(r)], axis=1)
    keep = (kind == 0) & (r[:, 0] > 0)
    x = snap["x"][()]
    a, b = snap["a"][()].astype(int)[keep], snap["b"][()].astype(int)[keep]
    rn, rt, n = r[keep, 0], r[keep, 1], n[keep]
    mean = rn.mean() if len(rn) else 1.0
    return n, rn / mean, rt / mean, x[a] - x[b]


def principal(T):
    """Eigenvalues (descending) and eigenvectors of a symmetric 2 x 2 tensor."""
    w, v = np.linalg.eigh(T)
    return w[::-1], v[:, ::-1]


def anisotropies(n, fn, ft):
    """Rothenburg-Bathurst a_c, a_n, a_t from the fabric and force tensors (docs/results.md) and their axes' angles."""
    t = np.stack([-n[:, 1], n[:, 0]], axis=1)
    F = np.einsum("ki,kj->ij", n, n) / len(n)
    chin = np.einsum("k,ki,kj->ij", fn, n, n) / fn.sum()
    chit = np.einsum("k,ki,kj->ij", ft, t, n) / fn.sum()
    chi = chin + 0.5 * (chit + chit.T)
    (F1, F2), vF = principal(F)
    (n1, n2), vn = principal(chin)
    (c1, c2), vc = principal(chi)
    ac = 2 * (F1 - F2) / (F1 + F2)
    an = 2 * (n1 - n2) / (n1 + n2) - ac
    at = 2 * (c1 - c2) / (n1 + n2) - ac - an
    angle = lambda v: np.arctan2(v[1, 0], v[0, 0]) % np.pi  # noqa: E731
    return ac, an, at, angle(vF), angle(vn), angle(vc)


def love_weber(n, fn, ft, l):
    t = np.stack([-n[:, 1], n[:, 0]], axis=1)
    force = fn[:, None] * n + ft[:, None] * t
    S = np.einsum("ki,kj->ij", force, l)
    return 0.5 * (S + S.T)


def analyse(f, chosen):
    pooled = {"n": [], "fn": [], "ft": []}
    whole, strong, weak = np.zeros((2, 2)), np.zeros((2, 2)), np.zeros((2, 2))
    for name, _ in chosen:
        n, fn, ft, l = contacts(f["snapshots"][name])
        if not len(fn):
            continue
        S = love_weber(n, fn, ft, l)
        scale = np.trace(S)
        if scale <= 0:
            continue
        up = fn >= 1
        whole += S / scale
        strong += love_weber(n[up], fn[up], ft[up], l[up]) / scale
        weak += love_weber(n[~up], fn[~up], ft[~up], l[~up]) / scale
        for key, v in (("n", n), ("fn", fn), ("ft", ft)):
            pooled[key].append(v)
    if not pooled["fn"]:
        fail("the snapshots chosen hold no force-carrying contact between disks")
    n, fn, ft = (np.concatenate(pooled[k]) for k in ("n", "fn", "ft"))
    return n, fn, ft, whole, strong, weak


def tail_decay(fn):
    edges = np.arange(0, fn.max() + BIN, BIN)
    counts, edges = np.histogram(fn, bins=edges)
    centre = 0.5 * (edges[1:] + edges[:-1])
    density = counts / (len(fn) * BIN)
    use = (centre >= 1) & (counts >= TAIL_MIN_COUNT)
    slope, intercept = np.polyfit(centre[use], np.log(density[use]), 1) if use.sum() >= 3 else (float("nan"), float("nan"))
    return -slope, np.exp(intercept), centre, density


def projected(S, e1, e2):
    return e1 @ S @ e1, e2 @ S @ e2


def network_shares(whole, strong, weak):
    _, v = principal(whole)
    e1, e2 = v[:, 0], v[:, 1]
    out = {}
    W1, W2 = projected(whole, e1, e2)
    out["q_over_p"] = (W1 - W2) / (W1 + W2)
    for tag, S in (("strong", strong), ("weak", weak)):
        s1, s2 = projected(S, e1, e2)
        out[f"q_over_p_{tag}"] = (s1 - s2) / (s1 + s2) if s1 + s2 > 0 else 0.0
        out[f"_{tag}"] = (s1, s2)
    out["weak_share_p"] = sum(out["_weak"]) / (W1 + W2)
    out["strong_share_q"] = (out["_strong"][0] - out["_strong"][1]) / (W1 - W2) if W1 != W2 else float("nan")
    del out["_strong"], out["_weak"]
    return out


def save_atomic(fig, out):
    """The figure to a new temporary file beside out, renamed onto out: never a partial PNG, nothing left on failure."""
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(out) or ".", prefix=".force_network.", suffix=".png")
    os.close(fd)
    try:
        fig.savefig(tmp)
        os.replace(tmp, out)
    except OSError as e:
        os.remove(tmp)
        fail(f"cannot write {out}: {e}")


def draw(out, fn, ft, n, centre, density, beta, scale, fits):
    ac, an, at, thc, thn, tht = fits
    fig = plt.figure(figsize=(11, 4), dpi=110)
    ax = fig.add_subplot(1, 2, 1)
    ax.semilogy(centre[density > 0], density[density > 0], "o", ms=3, label="P(f)")
    if np.isfinite(beta):
        tail = centre >= 1
        ax.semilogy(centre[tail], scale * np.exp(-beta * centre[tail]), "-", label=f"exp(-{beta:.2f} f)")
    ax.axvline(1, color="grey", lw=0.5)
    ax.set_xlabel("f = f_n / <f_n>")
    ax.set_ylabel("probability density")
    ax.legend(fontsize=8)
    theta = np.arctan2(n[:, 1], n[:, 0]) % np.pi
    edges = np.linspace(0, np.pi, ANGLE_BINS + 1)
    which = np.minimum(np.digitize(theta, edges) - 1, ANGLE_BINS - 1)
    count = np.bincount(which, minlength=ANGLE_BINS)
    mid = 0.5 * (edges[1:] + edges[:-1])
    p = count / (len(n) * (np.pi / ANGLE_BINS))
    mfn = np.array([fn[which == k].mean() if count[k] else 0 for k in range(ANGLE_BINS)])
    mft = np.array([ft[which == k].mean() if count[k] else 0 for k in range(ANGLE_BINS)])
    th = np.linspace(0, 2 * np.pi, 361)
    pax = fig.add_subplot(1, 2, 2, projection="polar")
    for vals, fit, label, colour in [(p * np.pi, 1 + ac * np.cos(2 * (th - thc)), "P(theta) pi", "tab:blue"),
                                     (mfn, 1 + an * np.cos(2 * (th - thn)), "<f_n>(theta)", "tab:red"),
                                     (np.abs(mft), np.abs(at * np.sin(2 * (th - tht))), "|<f_t>(theta)|", "tab:green")]:
        both = np.concatenate([mid, mid + np.pi])
        pax.plot(both, np.concatenate([vals, vals]), "o", ms=3, color=colour, label=label)
        pax.plot(th, fit, "-", lw=1, color=colour)
    pax.set_rlabel_position(100)
    pax.tick_params(labelsize=7)
    pax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(-0.35, -0.12))
    pax.set_title(f"a_c {ac:.3f}, a_n {an:.3f}, a_t {at:.3f}", fontsize=9)
    fig.tight_layout()
    save_atomic(fig, out)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("results", help="kergs results file (HDF5) with snapshots")
    ap.add_argument("--from-strain", type=float, help="lower end of the axial strain window (default: 60 %% of the final strain)")
    ap.add_argument("--to-strain", type=float, help="upper end of the axial strain window (default: the final strain)")
    ap.add_argument("-o", "--prefix", help="output prefix (default: RESULTS without .h5)")
    a = ap.parse_args()
    stem = os.path.basename(a.results)
    for ext in (".tmp", ".h5"):
        stem = stem[: -len(ext)] if stem.endswith(ext) else stem
    prefix = a.prefix or os.path.join(os.path.dirname(a.results), stem)
    if os.path.isdir(prefix):
        prefix = os.path.join(prefix, stem)
    out = prefix + "_forces.png"
    folder = os.path.dirname(out) or "."
    if not os.path.isdir(folder) or not os.access(folder, os.W_OK):
        fail(f"cannot write {out}: {folder} is not a writable folder")
    if os.path.isdir(out):
        fail(f"cannot write {out}: it is a folder")
    if os.path.exists(out) and os.path.exists(a.results) and os.path.samefile(out, a.results):
        fail(f"the figure {out} would replace the results file")
    try:
        f = h5py.File(a.results, "r")
    except OSError as e:
        fail(f"cannot open {a.results} as HDF5: {e}")
    with f:
        snaps = snapshot_steps(f, a.results)
        chosen, window = choose(f, a.results, snaps, a.from_strain, a.to_strain)
        if not chosen:
            fail(f"{a.results}: no snapshot in the strain window {window} (snapshots at steps "
                 f"{[s for _, s in snaps]}; -output_every sets how many there are)")
        n, fn, ft, whole, strong, weak = analyse(f, chosen)
        complete = bool(f.attrs.get("complete", 1))
    if not complete:
        print(f"force_network.py: warning: {a.results} is not complete (a run still writing it, or killed): only its "
              "snapshots so far are read, and the default window ends at the strain reached so far", file=sys.stderr)
    beta, scale, centre, density = tail_decay(fn)
    fits = anisotropies(n, fn, ft)
    row = {"results": a.results, "complete": complete, "snapshots": len(chosen), "steps": [s for _, s in chosen], "strain_window": window,
           "contacts": int(len(fn)), "below_mean": float((fn < 1).mean()), "tail_decay": float(beta), "f_max": float(fn.max()),
           "a_c": float(fits[0]), "a_n": float(fits[1]), "a_t": float(fits[2])}
    row.update({k: float(v) for k, v in network_shares(whole, strong, weak).items()})
    draw(out, fn, ft, n, centre, density, beta, scale, fits)
    finite = lambda v: v if not isinstance(v, float) or math.isfinite(v) else None  # noqa: E731 (a fit without data)
    print(json.dumps({k: finite(v) for k, v in row.items()}, allow_nan=False))
    return 0


if __name__ == "__main__":
    sys.exit(main())
