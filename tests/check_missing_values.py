#!/usr/bin/python3
"""Every option kergs reads that takes a value, given without one, is an error naming it, before any work.

Usage: check_missing_values.py KERGS [scene options...]

Reads `kergs SCENE -help` and walks every option listed only as taking a value ("  -name <..."; a flag prints
"  -name: <...", a viewer "  -name ascii[...", both may go without a value), except the options of PETSc objects
(-predictor_ksp_type, -solver_tresca_tao_monitor: PETSc owns their meaning, -tao_monitor alone monitors to stdout) and
PETSc's own, read at PetscInitialize (the PetscDevice headings). For each it runs kergs SCENE -steps 1 -output_none
-NAME, one process on one rank (MPI's singleton start: a third faster than through mpiexec), and expects a non-zero exit, the message "option -NAME is given without its value", no crash and
no sign of work (the scene's view, printed once the options are read). Then one run gives flags, viewers and PETSc's
own options without values, and must succeed.
"""
import re
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

PETSC_OBJECT_STEMS = ("ksp_", "pc_", "snes_", "tao_", "mat_")
CRASH = re.compile(r"segmentation|signal [0-9]+|SIGSEGV|SIGABRT|core dumped|Caught signal", re.I)
WORK = re.compile(r"^Scene \S+: \d+ disks", re.M)
# the examples must be among the walked options, so that a parser that finds nothing cannot pass
MUST_WALK = ("dt", "friction", "steps", "output", "solver_type", "restart", "fclib_input")
# a run that must succeed: kergs's flags and viewers, PETSc's own options and a PETSc object's, all without values
OPTIONAL = ["-quiet", "-partition_view", "-solver_monitor", "-log_view", "-malloc_dump", "-solver_type", "tresca",
            "-solver_tresca_tao_monitor"]


def run(cmd):
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=120)
    return p.returncode, p.stdout


def is_petsc_object_option(name):
    return any(name.startswith(s) or "_" + s in name for s in PETSC_OBJECT_STEMS)


def value_options(help_text):
    """Options that every help line lists as taking a value, in order, outside PETSc's start-up headings."""
    kinds, heading, order = {}, "", []
    for line in help_text.splitlines():
        m = re.match(r"  -([A-Za-z0-9_]+)(.*)", line)
        if not m:
            if line and not line.startswith(" ") and line.endswith(":"):
                heading = line
            continue
        name, rest = m.groups()
        if "PetscDevice" in heading or is_petsc_object_option(name):
            continue
        if name not in kinds:
            order.append(name)
        kinds.setdefault(name, set()).add("value" if rest.startswith(" <") else "optional")
    return [n for n in order if kinds[n] == {"value"}]


def check(launch, scene, name):
    steps = [] if name == "steps" else ["-steps", "1"]
    rc, out = run(launch + scene + steps + ["-output_none", "-" + name])
    problems = []
    if rc == 0:
        problems.append("exit status 0")
    if CRASH.search(out):
        problems.append("crashed")
    if f"option -{name} is given without its value" not in out:
        problems.append("no message naming it")
    if WORK.search(out):
        problems.append("the run started (the scene's view was printed)")
    return name, problems, out


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    launch = [sys.argv[1]]
    scene = sys.argv[2:]
    rc, help_text = run(launch + scene + ["-help"])
    if rc != 0:
        print(help_text[-3000:])
        sys.exit(f"FAIL: kergs -help exited with status {rc}")
    names = value_options(help_text)
    missing = [n for n in MUST_WALK if n not in names]
    if missing:
        sys.exit(f"FAIL: -help does not list these as taking a value: {missing} (the help's format changed?)")
    failures = 0
    with ThreadPoolExecutor(max_workers=12) as pool:  # a run mostly waits for MPI's start-up (0.8 s, 0.15 s of CPU)
        for name, problems, out in pool.map(lambda n: check(launch, scene, n), names):
            if problems:
                failures += 1
                print(f"FAIL -{name}: {', '.join(problems)}\n" + "\n".join(out.splitlines()[-15:]))
    print(f"{len(names) - failures} of {len(names)} options refused without their value")
    rc, out = run(launch + scene + ["-steps", "1", "-output_none"] + OPTIONAL)
    if rc != 0:
        failures += 1
        print(out[-3000:] + f"\nFAIL: {' '.join(OPTIONAL)} (values optional) exited with status {rc}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
