#!/usr/bin/python3
"""Batch use of kergs (docs/running.md), tested through the executable on 1 and 2 ranks.

  check_batch.py TEST --kergs build/kergs --mpiexec mpiexec --dir WORKDIR

TEST is one of:
  restart   10 + 10 steps of confine500 against 20 (scripts/compare_results.py: bit for bit) on 2 ranks; 4 + 4 steps,
            2 -> 1 and 1 -> 2 ranks, against the uninterrupted 8, frictionless and solved to 1e-10 (velocities unique): the
            first 4 rows bit for bit, the end within the solver's tolerance; a pressure-controlled wall over a closed box's
            moving height, 10 + 10 steps against 20 bit for bit; the radius-ratio-100 pile, whose automatic alert
            distance grows with the grains' speed, 120 + 120 steps against 240 bit for bit; a checkpoint edited to a
            negative row count, a time that is not a number or an infinite wall displacement: refused, no output
  signals   SIGTERM and SIGINT sent to the ranks, SIGUSR1 to mpiexec (which forwards it) and to both at once: exit status 4, the results file
            complete under its final name, the checkpoint of the last step; a restart continues the same file
  kill      SIGKILL: the .tmp left is readable and holds every flushed row and snapshot; a restart from the last
            checkpoint continues it into one run's file
  paths     outputs that would replace an input or another output (links resolved), PETSc viewers' files included
            (-solver_monitor ascii:FILE, -log_view :FILE), a directory, a path under a file: refused before any work,
            inputs untouched; a 300-character path on 2 ranks works
  enospc    a full file system (a 200 KB tmpfs; skipped when it cannot be mounted): "No space left on device", the
            file named, the partial .tmp removed
  fclib     -fclib_step N exports the problem solved in the step whose line says "step N"
  statuses  exit statuses 0, 2 (blow-up), 3 (-error_on_nonconvergence on the infeasible straight row); progress lines
Exit status 0 when every check holds, 1 otherwise, 77 when the test cannot run here (skipped)."""
import argparse
import hashlib
import os
import shutil
import signal
import stat
import subprocess
import sys
import time

import h5py
import numpy as np

from checks import Kergs, check, failures, small_tmpfs

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
CONFINE500 = os.path.join(ROOT, "cases", "confine500.opts")
# the batch tests run confine500 with the paper's NLGS (fast, many steps), not the scene's default newton
PAPER500 = ["-options_file", CONFINE500, "-solver_type", "nlgs", "-solver_max_it", "150", "-solver_tol", "1e-4"]
CONFINE5 = os.path.join(ROOT, "cases", "confine5.opts")


def ranks_of(p):
    """The rank processes of a run: the children of mpiexec."""
    out = subprocess.run(["ps", "-o", "pid=", "--ppid", str(p.pid)], capture_output=True, text=True).stdout
    return [int(x) for x in out.split()]


def wait_for_steps(log, n, p, timeout=60):
    """Until the run has printed its step line n (or ended)."""
    t0 = time.time()
    while time.time() - t0 < timeout and p.poll() is None:
        with open(log) as f:
            if sum(1 for line in f if line.startswith("step ")) >= n:
                return True
        time.sleep(0.05)
    return False


def stats(path):
    with h5py.File(path, "r") as f:
        return {k: f["stats"][k][()] for k in f["stats"]}, dict(f.attrs), sorted(f["snapshots"])


def sha(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def compare(a, b):
    p = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "compare_results.py"), a, b], capture_output=True, text=True)
    return p.returncode, p.stdout.strip()


# ---------------------------------------------------------------------------------------------------------------------

def test_restart(k):
    common = [*PAPER500, "-quiet"]
    # same number of ranks: bit for bit, snapshots and physical statistics (scripts/compare_results.py)
    k.run(2, *common, "-steps", 20, "-output", k.path("A.h5"), log="A.log")
    p1 = k.run(2, *common, "-steps", 10, "-output", k.path("B.h5"), "-checkpoint_every", 10, log="B1.log")
    check(p1.returncode == 0 and os.path.exists(k.path("B.checkpoint.h5")), "restart: 10 steps write the checkpoint of step 10")
    # under PETSc's -malloc_dump: every block the restore allocates is freed
    p2 = k.run(2, "-restart", k.path("B.checkpoint.h5"), "-steps", 20, "-malloc_debug", "-malloc_dump", log="B2.log")
    leaks = [line for line in (p2.stdout + p2.stderr).splitlines() if " bytes " in line and "]" in line]
    check(p2.returncode == 0 and not leaks, "restart: -restart FILE -steps 20 continues to step 20 (exit status 0, nothing leaked) " + " ".join(leaks[:2]))
    # the packing and the walls come from the checkpoint: a changed -box is refused, not ignored
    p3 = k.run(1, "-restart", k.path("B.checkpoint.h5"), "-steps", 20, "-box", "0,0,0.6,1.2", "-output", k.path("C.h5"), log="B3.log")
    check(p3.returncode == 1 and "-box 0,0,0.6,1.2 differs from the checkpointed run's -box" in p3.stdout + p3.stderr
          and not os.path.exists(k.path("C.h5")), "restart: a changed -box is refused, naming both values, before any output")
    _, a_attrs, _ = stats(k.path("A.h5"))
    date = a_attrs.get("date", b"").decode()
    check(a_attrs.get("kergs_version", b"") not in (b"",) and a_attrs.get("ranks") == 2 and b"-steps 20" in a_attrs.get("options", b"")
          and len(date) == 20 and date[4] == "-" and date.endswith("Z"),
          f"provenance: root attributes kergs_version ({a_attrs.get('kergs_version')}), options, ranks (2), date ({date})")
    rc, out = compare(k.path("A.h5"), k.path("B.h5"))
    check(rc == 0, "restart: 10 + 10 steps on 2 ranks give the 20-step run bit for bit (snapshots, statistics) " + out[:300])
    s, attrs, snaps = stats(k.path("B.h5"))
    check(list(s["step"]) == list(range(1, 21)) and snaps == ["000000", "000001"],
          "restart: one file, steps 1..20 once each, the snapshots of one run (first and last only: -output_every 25)")
    check(attrs.get("restart_step") == 10 and b"-restart" in attrs.get("restart_options", b""),
          "restart: the file records the restart (restart_step, restart_options) next to the first run's provenance")
    # another number of ranks: to the solver's tolerance (frictionless: the velocities solve a problem with one answer);
    # 4 + 4 steps against 8, each solved to a natural residual of 1e-10
    tight = ["-friction", 0, "-solver_tol", "1e-10", "-solver_criterion", "natural", "-solver_max_it", 20000]
    for first, second in ((2, 1), (1, 2)):
        ref, part = k.path(f"R{first}.h5"), k.path(f"P{first}{second}.h5")
        k.run(first, *common, *tight, "-steps", 8, "-output", ref, log=f"R{first}.log")
        k.run(first, *common, *tight, "-steps", 4, "-output", part, "-checkpoint_every", 4, log=f"P{first}a.log")
        ckpt = part.replace(".h5", ".checkpoint.h5")
        p = k.run(second, "-restart", ckpt, "-steps", 8, log=f"P{first}{second}b.log")
        check(p.returncode == 0, f"restart {first} -> {second} ranks: runs to step 8")
        check(f"restart of a checkpoint written on {first} rank(s) on {second}: " in p.stdout and "not bit for bit" in p.stdout,
              f"restart {first} -> {second} ranks: the run says at start that it continues to rounding, not bit for bit")
        with h5py.File(ref, "r") as f, h5py.File(part, "r") as g:
            same4 = all(np.array_equal(f["stats"][n][:4], g["stats"][n][:4]) for n in ("residual", "contacts", "iterations", "time"))
            check(same4 and g["stats/step"].shape == (8,), f"restart {first} -> {second} ranks: rows 1-4 are the first run's, bit for bit")

            def last(h):
                snap = h["snapshots"][sorted(h["snapshots"])[-1]]
                order = np.argsort(snap["id"][()])
                return snap["x"][()][order], snap["v"][()][order], snap.attrs["step"]
            xa, va, sa = last(f)
            xb, vb, sb = last(g)
            dx, dv = np.abs(xa - xb).max(), np.abs(va - vb).max()
            # an uninterrupted run on the other number of ranks differs by about 1e-13 m; losing the velocities or the walls
            # would move the grains by 1e-5 m or more in 4 steps
            check(sa == sb == 8 and dx < 1e-10 and dv < 1e-8,
                  f"restart {first} -> {second} ranks: step 8 within the solver's tolerance (positions {dx:.1e} m, velocities {dv:.1e} m/s)")
    test_restart_pressure(k)
    test_restart_alert(k)
    test_restart_monitors(k)
    test_restart_corrupt(k, k.path("B.checkpoint.h5"))


def test_restart_corrupt(k, good):
    """A checkpoint edited to hold what no run writes is refused before any step or output, naming the file and the
    value: a negative count of result rows (the run then wrote rows without end: 19 GB in 13 minutes), a time that is not
    a number, a wall displacement that is infinite."""
    def rows(f):
        f["state"].attrs["results_rows"] = np.array(-1, dtype=f["state"].attrs["results_rows"].dtype)

    def nan_time(f):
        f.attrs["time"] = np.array(np.nan, dtype=f.attrs["time"].dtype)

    def disp(f):
        d = f["walls/disp"][()]
        d.flat[0] = np.inf
        f["walls/disp"][...] = d

    for name, edit, message in (("rows", rows, "attribute results_rows on /state is -1, not a count"),
                                ("time", nan_time, "attribute time on / is nan"),
                                ("disp", disp, "dataset /walls/disp holds a value that is not finite")):
        bad, out = k.path(f"bad_{name}.checkpoint.h5"), k.path(f"bad_{name}.h5")
        shutil.copyfile(good, bad)
        with h5py.File(bad, "r+") as f:
            edit(f)
        p = k.run(1, "-restart", bad, "-steps", 12, "-output", out, log=f"bad_{name}.log")
        text = p.stdout + p.stderr
        check(p.returncode == 1 and message in text and bad in text and not os.path.exists(out) and not os.path.exists(out + ".tmp"),
              f"restart from a checkpoint with a bad {name}: refused with '{message}', naming the file, no output (exit {p.returncode})")


def test_restart_monitors(k):
    """PETSc's monitors that start in PetscInitialize (-log_view, -memory_view, -malloc_view), given to the first run
    only: the restart, which takes its options from the checkpoint, reports the first two, says the third is not
    applied, and ends with status 0 (it used to end with status 1 in PetscFinalize, after its checkpoint)."""
    monitors = ["-log_view", "-memory_view", "-malloc_view"]
    p1 = k.run(1, *PAPER500, "-quiet", "-steps", 2, "-output", k.path("M.h5"), "-checkpoint_every", 2, *monitors, log="M1.log")
    p2 = k.run(1, "-restart", k.path("M.checkpoint.h5"), "-steps", 4, log="M2.log")
    out = p2.stdout + p2.stderr
    check(p1.returncode == 0 and p2.returncode == 0 and "PETSC ERROR" not in out,
          f"restart, PETSc's monitors from the checkpoint: exit {p1.returncode}, then {p2.returncode}")
    check("Performance Summary" in out and "Summary of Memory Usage" in out and "-malloc_view of the checkpointed run is not applied" in out,
          "restart, PETSc's monitors from the checkpoint: the restart prints -log_view's and -memory_view's summaries, and says "
          "that -malloc_view (PETSc's tracing malloc, installed at start only) is not applied")


def test_restart_pressure(k):
    """A pressure-controlled wall's force is set from the restored walls: box_right under a pressure over the height of
    a closed box whose top moves down (its force changes every step), 10 + 10 steps against 20, bit for bit."""
    common = [*PAPER500, "-quiet", "-box_open_top", "0", "-wall_box_top_velocity", "0,-0.05", "-wall_box_right_velocity", "0,0",
              "-wall_box_right_type", "free", "-wall_box_right_mass", "0.1", "-wall_box_right_pressure", "200"]
    k.run(2, *common, "-steps", 20, "-output", k.path("PA.h5"), log="PA.log")
    p1 = k.run(2, *common, "-steps", 10, "-output", k.path("PB.h5"), "-checkpoint_every", 10, log="PB1.log")
    p2 = k.run(2, "-restart", k.path("PB.checkpoint.h5"), "-steps", 20, log="PB2.log")
    check(p1.returncode == 0 and p2.returncode == 0, "restart, pressure wall: 10 steps, then the restart to 20, run")
    rc, out = compare(k.path("PA.h5"), k.path("PB.h5"))
    check(rc == 0, "restart, pressure wall: 10 + 10 steps give the 20-step run bit for bit (the force from the restored height) "
          + out[:300])


def test_restart_alert(k):
    """The automatic alert distance follows the speed (KergsSceneAdaptAlert) and the ghost layer is rebuilt as it grows:
    the radius-ratio-100 pile of docs/running.md, whose grains fall faster than the alert's floor allows for, 120 + 120
    steps against 240 on 2 ranks, bit for bit (the checkpoint keeps the alert's floor and the layer's margin)."""
    common = ["-scene_name", "r100", "-gravity", "0,-9.81", "-friction", "0.3", "-dt", "1e-3", "-disks_source", "random", "-random_n",
              "500", "-random_box", "0,0,1,6", "-random_radius", "0.0005,0.05", "-random_seed", "2013", "-box", "0,0,1,7", "-box_open_top",
              "-quiet"]
    k.run(2, *common, "-steps", 240, "-output", k.path("RA.h5"), "-checkpoint_every", 240, log="RA.log")
    p1 = k.run(2, *common, "-steps", 120, "-output", k.path("RB.h5"), "-checkpoint_every", 120, log="RB1.log")
    with h5py.File(k.path("RB.checkpoint.h5"), "r") as f:
        alert, floor = float(f["state"].attrs["alert"]), float(f["state"].attrs["alert_floor"])
    check(alert > 1.2 * floor, f"restart, automatic alert: at step 120 the alert {alert:.3g} has grown past its floor {floor:.3g}")
    p2 = k.run(2, "-restart", k.path("RB.checkpoint.h5"), "-steps", 240, log="RB2.log")
    check(p1.returncode == 0 and p2.returncode == 0, "restart, automatic alert: 120 steps, then the restart to 240, run")
    rc, out = compare(k.path("RA.h5"), k.path("RB.h5"))
    check(rc == 0, "restart, automatic alert: 120 + 120 steps on 2 ranks give the 240-step run bit for bit " + out[:300])
    # the ghost layer too (an extra rebuild changes no physics): the checkpoints of step 240 hold the same layer
    with h5py.File(k.path("RA.checkpoint.h5"), "r") as a, h5py.File(k.path("RB.checkpoint.h5"), "r") as b:
        same = all(a["disks"].attrs[key] == b["disks"].attrs[key] for key in ("ghost_rebuilds", "ghost_margin"))
        same = same and all(np.array_equal(a["disks"][key][()], b["disks"][key][()]) for key in ("xref", "ghosts"))
        layers = int(a["disks"].attrs["ghost_rebuilds"])
    check(same and layers > 1, f"restart, automatic alert: the same ghost layer at step 240 ({layers} built, margin, xref, ghosts)")


def test_signals(k):
    for sig, how in ((signal.SIGTERM, "ranks"), (signal.SIGINT, "ranks"), (signal.SIGUSR1, "mpiexec")):
        name = sig.name
        out = k.path(f"{name}.h5")
        p, log = k.start(2, *PAPER500, "-steps", 100000, "-output", out, "-output_every", 10, log=f"{name}.log")
        started = wait_for_steps(log, 5, p)
        targets = ranks_of(p) if how == "ranks" else [p.pid]
        for pid in targets:
            os.kill(pid, sig)
        try:
            rc = p.wait(timeout=60)
        except subprocess.TimeoutExpired:
            p.kill()
            rc = None
        text = open(log).read()
        check(started and rc == 4, f"{name} to the {how}: the run stops with exit status 4 (got {rc})")
        check(f"{name} received" in text, f"{name}: the log says the signal was received")
        check(os.path.exists(out) and not os.path.exists(out + ".tmp"), f"{name}: the results file is closed under its final name")
        try:
            s, attrs, snaps = stats(out)
            nrows = len(s["step"])
            with h5py.File(out.replace(".h5", ".checkpoint.h5"), "r") as c:
                cstep = int(c.attrs["step"])
            check(attrs.get("complete") == 1 and attrs.get("end") == f"stopped by {name}".encode() and nrows >= 5
                  and list(s["step"]) == list(range(1, nrows + 1)),
                  f"{name}: the file is complete (end = 'stopped by {name}', {nrows} rows, steps 1..{nrows})")
            check(cstep == nrows, f"{name}: the checkpoint is of the last step ({cstep} = {nrows})")
        except (OSError, KeyError) as e:
            check(False, f"{name}: results and checkpoint readable ({e})")
            continue
        if sig == signal.SIGTERM:  # the batch system's next job: restart, 3 more steps
            p2 = k.run(2, "-restart", out.replace(".h5", ".checkpoint.h5"), "-steps", nrows + 3, log="SIGTERM-restart.log")
            s2, attrs2, _ = stats(out)
            with h5py.File(out, "r") as f:
                steps = sorted(int(g.attrs["step"]) for g in f["snapshots"].values())
            want = sorted({0, nrows + 3} | {n for n in range(10, nrows + 4, 10)})
            check(p2.returncode == 0 and list(s2["step"]) == list(range(1, nrows + 4)) and attrs2.get("end") == b"done" and steps == want,
                  f"SIGTERM: the restart continues the same file to step {nrows + 3}: rows contiguous, snapshots those of one "
                  f"run (steps {want}; the stop's own snapshot dropped)")
    test_signals_early(k)
    test_signals_ctrl_c(k)
    test_signals_usr1_twice(k)
    test_signals_recipe(k)


def catches_usr1(pid):
    """Whether the process has a handler for SIGUSR1 (its SigCgt mask in /proc)."""
    try:
        with open(f"/proc/{pid}/status") as f:
            mask = next(int(line.split()[1], 16) for line in f if line.startswith("SigCgt:"))
        return bool(mask & (1 << (signal.SIGUSR1 - 1)))
    except (OSError, StopIteration):
        return False


def kergs_ranks(p):
    """The rank processes of p that already run the kergs executable (not mpiexec's fork before exec)."""
    ranks = []
    for pid in ranks_of(p):
        try:
            if os.path.basename(os.readlink(f"/proc/{pid}/exe")) == "kergs":
                ranks.append(pid)
        except OSError:
            pass
    return ranks


def test_signals_early(k):
    """SIGUSR1 to the ranks as soon as they catch it, or 5 s after they started (a batch system's signal at once):
    the run stops cleanly before its first step. kergs installs its handler first thing in main, before MPI_Init
    (0.12 s after the start on the idle machine; with 0.3 s as the bound, the test failed once in three at a load of
    4 on 2 cores, the signal arriving before the handler)."""
    out = k.path("early.h5")
    p, log = k.start(2, *PAPER500, "-steps", 100000, "-output", out, log="early.log")
    t0, ranks = time.time(), []
    while time.time() - t0 < 30 and len(ranks) < 2 and p.poll() is None:
        ranks = kergs_ranks(p)
        time.sleep(0.005)
    t1 = time.time()
    while time.time() - t1 < 5 and not all(catches_usr1(pid) for pid in ranks):
        time.sleep(0.005)
    for pid in ranks:
        os.kill(pid, signal.SIGUSR1)
    sent = time.time() - t1
    rc = p.wait(timeout=60)
    text = open(log).read()
    check(len(ranks) == 2 and rc == 4 and "SIGUSR1 received: stopped after step 0" in text,
          f"SIGUSR1 {sent:.3f} s after the ranks' start: stopped before the first step, exit status 4 (got {rc})")
    check(os.path.exists(out) and os.path.exists(k.path("early.checkpoint.h5")), "SIGUSR1 at start: results and checkpoint of step 0")


def stop_by_signals(k, name, send):
    """A paper500 run on 2 ranks, stopped by send(mpiexec process, ranks' pids) after 5 steps: whether it started, its exit
    status (None if it had not ended within 60 s), its results' attributes, and whether its checkpoint is of step 5 or
    later."""
    out = k.path(f"{name}.h5")
    p, log = k.start(2, *PAPER500, "-steps", 100000, "-output", out, log=f"{name}.log")
    started = wait_for_steps(log, 5, p)
    send(p, ranks_of(p))
    try:
        rc = p.wait(timeout=60)
    except subprocess.TimeoutExpired:
        p.kill()
        rc = None
    try:
        _, attrs, _ = stats(out)
        with h5py.File(k.path(f"{name}.checkpoint.h5"), "r") as c:
            ok = int(c.attrs["step"]) >= 5
    except (OSError, KeyError):
        attrs, ok = {}, False
    return started and ok and not os.path.exists(out + ".tmp"), rc, attrs


def test_signals_ctrl_c(k):
    """Ctrl-C in a terminal: SIGINT reaches mpiexec and the ranks (one process group), then mpiexec relays SIGTERM to the
    ranks (and SIGKILL one second later, which kergs cannot prevent: docs/running.md). The relayed signal, of another kind,
    must not kill them: here SIGINT then SIGTERM go to the ranks directly, and the run must stop as on SIGINT alone."""

    def send(_, ranks):
        for sig in (signal.SIGINT, signal.SIGTERM):
            for pid in ranks:
                os.kill(pid, sig)

    ok, rc, attrs = stop_by_signals(k, "ctrlc", send)
    check(ok and rc == 4 and attrs.get("end", b"").startswith(b"stopped by SIG"),
          f"SIGINT then SIGTERM to the ranks (Ctrl-C relayed by mpiexec): stopped cleanly with status 4, results complete, checkpoint "
          f"written (got {rc}, {attrs.get('end')})")


def test_signals_usr1_twice(k):
    """A scheduler's warning that reaches the ranks directly and again through mpiexec (a job script that forwards it):
    the second SIGUSR1 is the same request and must not kill the ranks before their checkpoint."""

    def send(mpiexec, ranks):
        for _ in range(2):  # twice to the ranks directly (the second arrives before the step ends), then through mpiexec
            for pid in ranks:
                os.kill(pid, signal.SIGUSR1)
            time.sleep(0.05)
        os.kill(mpiexec.pid, signal.SIGUSR1)

    ok, rc, attrs = stop_by_signals(k, "usr1twice", send)
    check(ok and rc == 4 and attrs.get("end") == b"stopped by SIGUSR1",
          f"SIGUSR1 to the ranks and to mpiexec (delivered twice): stopped cleanly with status 4, results complete, checkpoint "
          f"written (got {rc}, {attrs.get('end')})")


def test_signals_recipe(k):
    """The stop recipe of scripts/slurm/kergs.sbatch with mpiexec as the launcher: SIGTERM to the job script (as
    scancel --batch --signal=TERM, or --signal=B:...), which relays SIGUSR1 to mpiexec. Exit status 4 (the chain reads
    it), a checkpoint from which a restart runs."""
    out, ckpt = k.path("recipe.h5"), k.path("recipe.checkpoint.h5")
    env = dict(os.environ, KERGS=k.kergs, KERGS_CASE=CONFINE500, KERGS_CHECKPOINT=ckpt, KERGS_CHECKPOINT_SECONDS="100000",
               KERGS_MAX_JOBS="1", KERGS_LAUNCH=f"{k.mpiexec} -n 2", SLURM_SUBMIT_DIR=ROOT,
               KERGS_ARGS=f"-solver_type nlgs -solver_max_it 150 -solver_tol 1e-4 -steps 100000 -output {out}")
    log = k.path("recipe.log")
    with open(log, "w") as f:
        p = subprocess.Popen(["bash", os.path.join(ROOT, "scripts", "slurm", "kergs.sbatch")], cwd=ROOT, env=env, stdout=f,
                             stderr=subprocess.STDOUT, start_new_session=True)
    started = wait_for_steps(log, 5, p)
    p.send_signal(signal.SIGTERM)
    try:
        rc = p.wait(timeout=60)
    except subprocess.TimeoutExpired:
        rc = None
    try:  # whatever is left of the job (a script that did not relay leaves mpiexec and the ranks running)
        os.killpg(p.pid, signal.SIGKILL)
    except OSError:
        pass
    text = open(log).read()
    check(started and rc == 4 and "stopped by SIGUSR1, exit status 4" in text and "KERGS_MAX_JOBS" in text,
          f"recipe: SIGTERM to the job script stops kergs through mpiexec with status 4 (got {rc})")
    try:
        s, attrs, _ = stats(out)
        with h5py.File(ckpt, "r") as c:
            cstep = int(c.attrs["step"])
        nrows = len(s["step"])
    except (OSError, KeyError) as e:
        check(False, f"recipe: results and checkpoint readable ({e})")
        return
    p2 = k.run(2, "-restart", ckpt, "-steps", nrows + 3, log="recipe-restart.log")
    s2, attrs2, _ = stats(out)
    check(cstep == nrows and p2.returncode == 0 and list(s2["step"]) == list(range(1, nrows + 4)),
          f"recipe: the checkpoint (step {cstep}) restarts: 3 more steps appended to the same results file")


def test_kill(k):
    out = k.path("killed.h5")
    p, log = k.start(2, *PAPER500, "-steps", 100000, "-output", out, "-output_every", 10, "-output_flush_every", 5,
                     "-checkpoint_every", 20, log="killed.log")
    started = wait_for_steps(log, 45, p)
    for pid in ranks_of(p):
        os.kill(pid, signal.SIGKILL)
    p.wait(timeout=60)
    printed = sum(1 for line in open(log) if line.startswith("step "))
    check(started and not os.path.exists(out) and os.path.exists(out + ".tmp"),
          "SIGKILL: the run leaves only <output>.tmp (a file under the final name is always complete)")
    try:
        with h5py.File(out + ".tmp", "r") as f:
            n = int(f["stats"].attrs["nrows"])
            steps = f["stats/step"][()]
            nsnap = int(f.attrs["nsnapshots"])
            snaps_ok = all(f["snapshots"][f"{i:06d}"]["x"].shape[0] == 500 for i in range(nsnap))
            complete = int(f.attrs["complete"])
        check(complete == 0 and len(steps) == n and list(steps) == list(range(1, n + 1)) and n >= printed - 5 - 1,
              f"SIGKILL: the .tmp is readable: {n} rows of the {printed} steps printed (flushed every 5), steps 1..{n}, complete = 0")
        check(nsnap >= n // 10 and snaps_ok, f"SIGKILL: its {nsnap} snapshots (nsnapshots) are whole")
    except (OSError, KeyError) as e:
        check(False, f"SIGKILL: the .tmp is a readable results file ({e})")
        return
    p2 = k.run(2, "-restart", k.path("killed.checkpoint.h5"), "-steps", 60, log="killed-restart.log")
    s, attrs, snaps = stats(out)
    check(p2.returncode == 0 and list(s["step"]) == list(range(1, 61)) and not os.path.exists(out + ".tmp"),
          "SIGKILL: a restart from the last checkpoint continues the killed run's .tmp into one file of steps 1..60")


def test_paths(k):
    d = k.path("p")
    os.makedirs(d, exist_ok=True)
    sample = os.path.join(d, "sample.h5")
    shutil.copy(os.path.join(ROOT, "cases", "deposit500.h5"), sample)
    os.symlink(d, os.path.join(d, "link"))
    before = sha(sample)
    base = [*PAPER500, "-steps", 2, "-quiet", "-sample_input", sample]
    bad = [
        (["-output", os.path.join(d, "link", "sample.h5")], "is the input -sample_input", "-output through a link to the input"),
        (["-output", os.path.join(d, "r.h5"), "-sample_output", os.path.join(d, "link", "sample.h5")], "is the input -sample_input",
         "-sample_output replacing the input"),
        (["-output", os.path.join(d, "r.h5"), "-sample_output", os.path.join(d, "link", "r.h5")], "are the same file",
         "two outputs, one through a link"),
        (["-output", os.path.join(d, "r.h5"), "-checkpoint_path", os.path.join(d, "r.h5.tmp")], "are the same file",
         "an output on another's .tmp"),
        (["-output", d], "is a directory", "an output that is a directory"),
        (["-output", os.path.join(sample, "r.h5")], "is not a directory", "an output under a regular file"),
        (["-output", os.path.join(d, "r.h5"), "-checkpoint_path", CONFINE500], "is the input -options_file", "-checkpoint_path on the options file"),
    ]
    # paths through directories that do not exist yet, then "..": compared after normalising what mkdir -p would create
    opts = os.path.join(d, "my.opts")
    shutil.copy(CONFINE500, opts)
    sub = os.path.join(d, "D")
    os.makedirs(sub, exist_ok=True)
    bad += [
        (["-options_file", opts, "-output", os.path.join(d, "newdir", "..", "my.opts")], "is the input -options_file",
         "-output newdir/../my.opts replacing the options file"),
        (["-output", os.path.join(d, "r.h5"), "-sample_output", os.path.join(d, "new", "er", "..", "..", "sample.h5")],
         "is the input -sample_input", "-sample_output new/er/../../sample.h5 replacing -sample_input"),
        (["-output", os.path.join(sub, "a.h5"), "-checkpoint_path", os.path.join(sub, ".", "sub", "..", "a.h5")], "are the same file",
         "-output D/a.h5 -checkpoint_path D/./sub/../a.h5"),
    ]
    # a PETSc viewer opens (an ASCII one truncates) its file when its option is read: checked against the inputs first
    bad += [
        (["-output", os.path.join(d, "r.h5"), "-solver_monitor", "ascii:" + sample], "Output -solver_monitor " + sample + " is the input -sample_input",
         "a viewer's file (-solver_monitor ascii:FILE) on the input"),
        (["-output", os.path.join(d, "r.h5"), "-solver_converged_reason", "ascii:" + os.path.join(d, "link", "sample.h5") + "::append"],
         "is the input -sample_input", "a viewer's file through a link to the input, with a format and a mode"),
        (["-options_file", opts, "-output", os.path.join(d, "r.h5"), "-log_view", ":" + opts], "is the input -options_file",
         "-log_view's file on the options file"),
    ]
    # a file name of 253 characters: its .tmp (257) would exceed the file system's 255; refused before any work, named
    bad.append((["-output", os.path.join(d, "n" * 250 + ".h5")], "its file name has 253 characters", "a 253-character file name"))
    # devices: a character device with /dev/null's numbers, made for the test (never /dev/null itself)
    dev = os.path.join(d, "null")
    try:
        os.mknod(dev, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except OSError as e:
        dev = None
        print(f"skipped: the device cases need mknod ({e})")
    if dev:
        bad += [(["-output", dev], "is a character device", "-output on a device"),
                (["-output", os.path.join(d, "r.h5"), "-checkpoint_path", dev], "is a character device", "-checkpoint_path on a device"),
                (["-output", os.path.join(d, "r.h5"), "-sample_output", dev], "is a character device", "-sample_output on a device"),
                (["-output", os.path.join(d, "nul")], "nul.tmp is a character device", "an output whose .tmp is (a link to) a device")]
        os.symlink(dev, os.path.join(d, "nul.tmp"))
    for extra, message, what in bad:
        p = k.run(2, *base, *extra, log="paths.log")
        text = p.stdout + p.stderr
        check(p.returncode == 1 and message in text and "step " not in p.stdout, f"paths: {what} is refused before any step ('{message}')")
    check(sha(sample) == before and not os.path.exists(os.path.join(d, "r.h5")), "paths: the input is untouched, nothing written")
    check(sha(opts) == sha(CONFINE500) and not os.path.exists(os.path.join(d, "newdir")), "paths: the options file is untouched")
    if dev:
        check(stat.S_ISCHR(os.stat(dev).st_mode), "paths: the device is still a device")
        # a device that appears under the output's name while the run goes on: the final rename refuses it, the .tmp stays
        out = os.path.join(d, "late.h5")
        p, log = k.start(2, *PAPER500, "-steps", 100000, "-output", out, log="late.log")
        started = wait_for_steps(log, 3, p)
        os.mknod(out, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        for pid in ranks_of(p):
            os.kill(pid, signal.SIGTERM)
        rc = p.wait(timeout=60)
        text = open(log).read()
        check(started and rc == 1 and "is a character device" in text and stat.S_ISCHR(os.stat(out).st_mode) and os.path.exists(out + ".tmp"),
              f"paths: a device made at the output's name during the run is not replaced at the end (exit 1, the .tmp kept; got {rc})")
    # a path of 300 characters on 2 ranks (Open MPI's ompio aborted from 241 on)
    long_dir = os.path.join(k.dir, "L" * 100, "o" * 100)
    os.makedirs(long_dir, exist_ok=True)
    out = os.path.join(long_dir, "n" * (300 - len(long_dir) - 4) + ".h5")
    p = k.run(2, "-options_file", CONFINE5, "-steps", 3, "-quiet", "-output", out, "-checkpoint_every", 3, log="long.log")
    ok = p.returncode == 0 and os.path.exists(out) and os.path.exists(out[:-3] + ".checkpoint.h5")
    check(ok and len(out) == 300, f"paths: an output path of {len(out)} characters works on 2 ranks (results and checkpoint)")


def test_enospc(k):
    with small_tmpfs(k.path("full")) as mnt:
        if mnt is None:
            print("skipped: cannot mount a small tmpfs here (mounting needs root)")
            return 77
        out = os.path.join(mnt, "r.h5")
        p = k.run(2, *PAPER500, "-steps", 30, "-quiet", "-output", out, "-output_every", 1, log="enospc.log")
        text = p.stdout + p.stderr
        check(p.returncode == 1 and "No space left on device" in text and out in text,
              "enospc: a full disk stops the run with 'No space left on device' naming the file")
        check(not os.path.exists(out + ".tmp") and not os.path.exists(out), "enospc: the partial .tmp is removed")
    return 0


def test_statuses(k):
    straight = os.path.join(ROOT, "cases", "confine5_straight.opts")
    p = k.run(1, "-options_file", straight, "-steps", 3, "-quiet", "-output_none", log="straight.log")
    check(p.returncode == 0 and " 0 not converged" not in p.stdout,
          f"statuses: the infeasible straight row has steps that do not converge, exit status 0 by default (got {p.returncode})")
    p = k.run(1, "-options_file", straight, "-steps", 3, "-quiet", "-output_none", "-error_on_nonconvergence", log="straight-error.log")
    check(p.returncode == 3 and "exit status 3" in p.stdout, f"statuses: ... and 3 with -error_on_nonconvergence (got {p.returncode})")
    p = k.run(1, "-options_file", CONFINE5, "-steps", 3, "-quiet", "-output_none", "-error_on_nonconvergence", log="done.log")
    check(p.returncode == 0 and " 0 not converged" in p.stdout, f"statuses: a converged run with -error_on_nonconvergence exits 0 (got {p.returncode})")
    # overlapping grains are found by the first detection, once the results file is open: it is removed, XDMF included
    out = k.path("overlap.h5")
    p = k.run(2, "-options_file", CONFINE5, "-disks_x", "0.5,0.5,1.5,0.5,2.2,0.5,3.5,0.5,4.5,0.5", "-output", out, log="overlap.log")
    check(p.returncode == 1 and "grains 1 and 2 overlap" in p.stdout + p.stderr and not os.path.exists(out + ".tmp")
          and not os.path.exists(out) and not os.path.exists(k.path("overlap.xdmf")),
          f"statuses: overlapping grains at start: exit status 1, no results file, no .tmp, no XDMF left (got {p.returncode}, "
          f"{sorted(f for f in os.listdir(k.dir) if f.startswith('overlap.'))})")
    # ... and the results of an earlier run under that name, its XDMF included, are left as they were
    prev = k.path("previous.h5")
    k.run(1, "-options_file", CONFINE5, "-steps", 2, "-quiet", "-output", prev, log="previous.log")
    before = {f: sha(k.path(f)) for f in ("previous.h5", "previous.xdmf")}
    p = k.run(2, "-options_file", CONFINE5, "-disks_x", "0.5,0.5,1.5,0.5,2.2,0.5,3.5,0.5,4.5,0.5", "-output", prev, log="previous-overlap.log")
    after = {f: sha(k.path(f)) if os.path.exists(k.path(f)) else None for f in before}
    check(p.returncode == 1 and after == before and not os.path.exists(prev + ".tmp"),
          f"statuses: overlapping grains refused with -output of an earlier run: its results file and XDMF unchanged, no .tmp "
          f"(got {p.returncode}, changed: {[f for f in before if after[f] != before[f]]})")
    # restarts that cannot be what the user meant: -steps below the checkpoint's step, a checkpoint of another format
    out = k.path("short.h5")
    k.run(1, "-options_file", CONFINE5, "-steps", 4, "-quiet", "-output", out, "-checkpoint_every", 4, log="short.log")
    ckpt = k.path("short.checkpoint.h5")
    p = k.run(1, "-restart", ckpt, "-steps", 2, log="short-restart.log")
    check(p.returncode == 1 and "-steps 2 is below the step of the checkpoint" in p.stdout + p.stderr,
          f"statuses: a restart with -steps below the checkpoint's step is refused, naming both (got {p.returncode})")
    other = k.path("other.checkpoint.h5")
    shutil.copy(ckpt, other)
    with h5py.File(other, "r+") as f:
        f.attrs["kergs_format"] = np.bytes_("kergs checkpoint 10")
    p = k.run(1, "-restart", other, "-steps", 6, "-output", k.path("other.h5"), log="other-restart.log")
    check(p.returncode == 1 and "is not a kergs checkpoint" in p.stdout + p.stderr,
          f"statuses: a checkpoint whose kergs_format is another ('kergs checkpoint 10') is refused (got {p.returncode})")
    out = k.path("blowup.h5")
    p = k.run(2, "-options_file", CONFINE5, "-gravity", "0,1e308", "-dt", 10, "-steps", 5, "-quiet", "-output", out, log="blowup.log")
    _, attrs, snaps = stats(out)
    check(p.returncode == 2 and "blow-up after step 1: grain" in p.stdout and attrs.get("end") == b"blow-up: non-finite state" and len(snaps) == 2,
          f"statuses: a blow-up (gravity 1e308) stops after step 1 naming the grain, exit status 2, the results file closed (got {p.returncode})")
    p = k.run(2, "-options_file", CONFINE5, "-steps", "2", "-quiet", "-output_none", "-progress_every", 1, log="progress.log")
    lines = [line for line in p.stdout.splitlines() if line.startswith("progress: step")]
    fields = ("step 2/2", " t ", " contacts ", " sweeps ", " residual ", " max interpenetration ", " s/step, ", " to the end")
    check(len(lines) == 2 and all(f in lines[-1] for f in fields),
          "statuses: -progress_every 1 prints step, time, contacts, sweeps, residual, interpenetration, s/step, time to the end")


def test_fclib(k):
    out, fc = k.path("fc.h5"), k.path("fc.fclib.h5")
    p = k.run(1, "-options_file", CONFINE5, "-steps", 6, "-output", out, "-output_every", 1, "-fclib_step", 4, "-fclib_output", fc,
              log="fclib.log")
    check(p.returncode == 0 and "FCLib problem of step 4" in p.stdout, "fclib: -fclib_step 4 exports")
    with h5py.File(out, "r") as f, h5py.File(fc, "r") as g:
        title = g["fclib_local/info/title"][()]
        title = title.decode() if isinstance(title, bytes) else str(title)
        r = g["solution/r"][()].reshape(-1, 2)[:, 0]  # normal components of the active contacts
        by_step = {int(s.attrs["step"]): s for s in f["snapshots"].values()}
        # snapshot of step N holds the contacts and impulses solved in step N
        matches = {n: np.array_equal(np.sort(by_step[n]["r"][()][:, 0][by_step[n]["r"][()][:, 0] != 0]), np.sort(r[r != 0]))
                   for n in (3, 4, 5)}
        active = int(f["stats/active"][3])
    check(title.endswith("step 4") and matches[4] and not matches[3] and not matches[5] and active == len(r),
          f"fclib: the file holds the problem of the step printed 'step 4' (title '{title}', impulses of step 4, stats row 3)")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("test", choices=["restart", "signals", "kill", "paths", "enospc", "fclib", "statuses"])
    ap.add_argument("--kergs", required=True)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--dir", required=True)
    a = ap.parse_args()
    if os.path.isdir(a.dir):
        subprocess.run(["umount", os.path.join(a.dir, "full")], capture_output=True)
        shutil.rmtree(a.dir)
    os.makedirs(a.dir)
    try:
        status = globals()["test_" + a.test](Kergs(a)) or 0
    except (OSError, KeyError, ValueError) as e:  # a file that a check needs is missing or not what it should be
        check(False, f"{a.test}: {type(e).__name__}: {e}")
        status = 0
    if status == 77:
        return 77
    print(f"{a.test}: {len(failures)} failure(s)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
