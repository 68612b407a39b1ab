#!/usr/bin/python3
"""scripts/proto_fixed_points.py on a problem its methods solve: confine5's step 3 (5 contacts, friction), exported
by kergs. The De Saxce fixed point must reach 1e-9, the Fischer-Burmeister Newton, Levenberg-Marquardt and the
interior point on the Stewart-Trinkle LCP 1e-10 on kergs's natural residual, each reporting it in its JSON line. The
interior point's answer, written with --write, must be read back by kergs (-fclib_start solution) as solved, and
--write onto the problem itself refused. `pieces` on kergs's answer perturbed by 1e-3 (its
contact states kept) must find its states' equations consistent and step back to the answer. A missing file is
refused with status 2."""
import json
import os
import subprocess
import sys

from checks import ROOT, Kergs, check, failures

SCRIPT = os.path.join(ROOT, "scripts", "proto_fixed_points.py")


def run_method(*args):
    """The script's exit status and its last line, parsed as JSON ({} if it is not)."""
    p = subprocess.run(["/usr/bin/python3", SCRIPT] + [str(x) for x in args], capture_output=True, text=True)
    try:
        return p, json.loads(p.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return p, {}


def main():
    k = Kergs.from_command_line(__doc__)
    problem = k.path("confine5_step3.fclib.h5")
    p = k.run(1, "-options_file", "cases/confine5.opts", "-steps", 3, "-solver_type", "newton", "-output", k.path("confine5.h5"),
              "-fclib_step", 3, "-fclib_output", problem, "-quiet")
    check(p.returncode == 0 and os.path.exists(problem), "kergs exports confine5's step 3")
    for method, extra, tol in (("desaxce", ["--outer", "60"], 1e-9), ("fb-lcp", ["--max-it", "50"], 1e-10),
                               ("lm", ["--max-it", "50"], 1e-10), ("ip-lcp", ["--max-it", "50"], 1e-10)):
        p, out = run_method(method, problem, *extra)
        check(p.returncode == 0 and out.get("method") == method and out.get("contacts") == 5 and out.get("residual", 1) <= tol,
              f"{method}: natural residual {out.get('residual')} <= {tol:g} on 5 contacts")
    answer = k.path("confine5_step3_ip.fclib.h5")
    p, out = run_method("ip-lcp", problem, "--write", answer)
    check(p.returncode == 0 and out.get("written") == answer and os.path.exists(answer), "ip-lcp --write: the answer written")
    p = k.run(1, "-fclib_input", answer, "-fclib_start", "solution", "-solver_type", "newton", "-solver_tol", "1e-10",
              "-error_on_nonconvergence", "-output", k.path("confine5_ip.h5"))
    check(p.returncode == 0 and "iterations    0" in p.stdout, "kergs reads the written answer back as solved, in 0 Newton steps")
    p, _ = run_method("ip-lcp", problem, "--write", problem)
    check(p.returncode == 2 and "other than the problem" in p.stderr, "--write onto the problem itself: status 2, named")
    p, out = run_method("pieces", problem, "--perturb", "1e-3")
    check(p.returncode == 0 and out.get("residual", 0) > 1e-5 and out.get("unreached_fraction", 1) <= 1e-8
          and out.get("residual_after_step", 1) <= 1e-12,
          f"pieces: a perturbed answer's states are consistent ({out.get('unreached_fraction')}) and one step returns "
          f"({out.get('residual')} -> {out.get('residual_after_step')})")
    p = subprocess.run(["/usr/bin/python3", SCRIPT, "desaxce", k.path("missing.h5")], capture_output=True, text=True)
    check(p.returncode == 2 and "no such file" in p.stderr, "a missing problem file: status 2, named")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
