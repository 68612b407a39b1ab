"""What the Python tests share (as tests/testing.h for the C ones): one line per check, the failures kept, and a
runner for the kergs under test."""

import argparse
import contextlib
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
failures = []


def check(ok, what):
    """Print one line for a check (ok or FAIL) and remember a failure; returns ok."""
    print(("ok   " if ok else "FAIL ") + what, flush=True)
    if not ok:
        failures.append(what)
    return ok


@contextlib.contextmanager
def small_tmpfs(path, size="200k"):
    """A file system of `size` mounted at path, for the checks of a full disk; None where it cannot be mounted (mounting
    needs root). Unmounted on exit."""
    os.makedirs(path, exist_ok=True)
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", path], capture_output=True).returncode:
        yield None
        return
    try:
        yield path
    finally:
        subprocess.run(["umount", path], capture_output=True)


class Kergs:
    """The kergs under test, run through mpiexec from the repository's root; a.kergs, a.mpiexec and a.dir (the scratch
    directory for its files) come from the test's command line."""

    def __init__(self, a):
        self.kergs, self.mpiexec, self.dir = os.path.abspath(a.kergs), a.mpiexec, os.path.abspath(a.dir)

    @classmethod
    def from_command_line(cls, description=None):
        """The kergs of the test's command line (--kergs, --mpiexec, --dir), its scratch directory created."""
        ap = argparse.ArgumentParser(description=description)
        ap.add_argument("--kergs", required=True)
        ap.add_argument("--mpiexec", required=True)
        ap.add_argument("--dir", required=True)
        k = cls(ap.parse_args())
        os.makedirs(k.dir, exist_ok=True)
        return k

    def cmd(self, ranks, args):
        return [self.mpiexec, "-n", str(ranks), self.kergs] + [str(x) for x in args]

    def run(self, ranks, *args, log=None):
        """Run to the end; with log, its output is also written to that file of the scratch directory."""
        p = subprocess.run(self.cmd(ranks, args), cwd=ROOT, capture_output=True, text=True)
        if log:
            with open(self.path(log), "w") as f:
                f.write(p.stdout + p.stderr)
        return p

    def start(self, ranks, *args, log):
        """Start in the background, its output to log: (the mpiexec process, the log's path)."""
        out = open(self.path(log), "w")
        return subprocess.Popen(self.cmd(ranks, args), cwd=ROOT, stdout=out, stderr=subprocess.STDOUT), self.path(log)

    def path(self, name):
        return os.path.join(self.dir, name)
