#!/usr/bin/python3
"""Compare two kergs results files bit for bit: every dataset under /snapshots (positions, orientations,
velocities, contact lists, gaps, impulses) and the physical statistics under /stats that both files record
(everything but wall times, memory and bytes sent, which differ between any two runs). A statistic recorded by one
file only is listed, not counted as a difference (a newer kergs records more).

  compare_results.py OLD.h5 NEW.h5 [--ignore name,name]   (--ignore: statistics whose meaning changed on purpose)

Exit status 0 when they are identical, 1 otherwise (the first differences are printed), 2 on unreadable input.
Used by scripts/compare_revisions to show that a refactoring leaves trajectories unchanged."""
import sys

import h5py
import numpy as np

# statistics that measure the machine, not the physics
MACHINE = ("seconds", "memory", "sent_bytes", "imbalance")


def datasets(group, prefix=""):
    out = {}
    for name, obj in group.items():
        path = f"{prefix}/{name}"
        if isinstance(obj, h5py.Group):
            out.update(datasets(obj, path))
        else:
            out[path] = np.asarray(obj[()])
    return out


def physical(path):
    return path.startswith("/snapshots/") or (path.startswith("/stats/") and not any(m in path for m in MACHINE))


def main():
    args = sys.argv[1:]
    ignore = set()
    if len(args) == 4 and args[2] == "--ignore":
        ignore = {f"/stats/{n}" for n in args[3].split(",")}
        args = args[:2]
    if len(args) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    sys.argv[1:] = args
    try:
        with h5py.File(sys.argv[1], "r") as f, h5py.File(sys.argv[2], "r") as g:
            old, new = datasets(f), datasets(g)
    except OSError as e:
        print(f"compare_results: {e}", file=sys.stderr)
        return 2
    old = {k: v for k, v in old.items() if physical(k)}
    new = {k: v for k, v in new.items() if physical(k)}
    for k in sorted(set(old) ^ set(new)):
        if k.startswith("/stats/"):
            print(f"compare_results: note: {k} is recorded by {'the old' if k in old else 'the new'} file only")
    problems = [f"only in {sys.argv[1]}: {k}" for k in sorted(set(old) - set(new)) if not k.startswith("/stats/")]
    problems += [f"only in {sys.argv[2]}: {k}" for k in sorted(set(new) - set(old)) if not k.startswith("/stats/")]
    for k in ignore:
        old.pop(k, None)
        new.pop(k, None)
    compared = 0
    for k in sorted(set(old) & set(new)):
        a, b = old[k], new[k]
        compared += 1
        if a.shape != b.shape:
            problems.append(f"{k}: shape {a.shape} against {b.shape}")
        elif a.tobytes() != b.tobytes():  # bit for bit, NaN included
            diff = np.flatnonzero(~((a.ravel() == b.ravel()) | (np.isnan(a.ravel()) & np.isnan(b.ravel()))))
            first = int(diff[0]) if diff.size else 0
            problems.append(f"{k}: {diff.size} of {a.size} entries differ, first at {first}: {a.ravel()[first]!r} against {b.ravel()[first]!r}")
    if compared == 0:
        problems.append("no snapshot dataset to compare")
    for p in problems[:20]:
        print(f"compare_results: {p}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
